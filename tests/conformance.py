#!/usr/bin/env python3
"""The generator conformance test: every class that `fractalbake generators --json` lists (the
generator list, host/gen/list.c) is held to the same contract, so a new generator is covered with no
edit here.

Usage: conformance.py FRACTALBAKE [--gpu]
For each class: its --help lists every key's flag; its example scene bakes natively at 64 x 32 into
an EXR with the layer's channels; the plan gives it a positive cost that grows with the image and
the sharing mode its class states (a banded class is cut into bands when tasks cost nothing to
start); an unknown key and a wrong value are each refused with exit 2, one line on stderr naming
the key, and no file. With --gpu (exit 77 without a Vulkan device): the example also bakes on
Vulkan, within the class's stated tolerance of the native file, with a silent validation layer.
"""
import json
import os
import subprocess
import sys
import tempfile

fb = os.path.realpath(sys.argv[1])
gpu = "--gpu" in sys.argv[2:]
tmp = tempfile.mkdtemp(prefix="fb-conf-")
# an example may name an input of docs/examples/ (a flame genome), relative to the repository
os.symlink(os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "docs"), os.path.join(tmp, "docs"))
env = dict(os.environ, XDG_RUNTIME_DIR=os.environ.get("XDG_RUNTIME_DIR", tmp))
passed = failed = 0


def run(*args, stdin=None):
    p = subprocess.run([fb, *args], cwd=tmp, env=env, capture_output=True, text=True, input=stdin)
    return p.returncode, p.stdout, p.stderr


def check(what, cond, detail=""):
    global passed, failed
    if cond:
        passed += 1
    else:
        failed += 1
        print(f"FAIL: {what}{': ' + detail if detail else ''}", file=sys.stderr)


if gpu and run("devices")[0] != 0:
    print("no Vulkan device: not run")
    sys.exit(77)

rc, out, err = run("generators", "--json")
check("generators --json", rc == 0, err)
classes = json.loads(out)
check("at least the seven generators of the first release", len(classes) >= 7)


def scene(c, size=(64, 32), extra=None):
    layers = json.loads(json.dumps(c["example"]))
    layers[-1].update(extra or {})
    return json.dumps({"size": list(size), "seed": 5, "layers": layers})


def write(name, text):
    path = os.path.join(tmp, name)
    with open(path, "w") as f:
        f.write(text)
    return path


def refused(what, args, out_name, key):
    rc, _, err = run(*args)
    lines = err.strip().splitlines()
    check(f"{what}: exit 2", rc == 2, f"exit {rc}: {err.strip()}")
    check(f"{what}: one line on stderr", len(lines) == 1, err.strip())
    check(f"{what}: the line names {key}", key in err, err.strip())
    check(f"{what}: no output file", not os.path.exists(os.path.join(tmp, out_name)))


for c in classes:
    name = c["name"]
    # help: every key's flag (the generator's type and its part's compression are the scene's)
    if c["command"]:
        rc, out, _ = run(name, "--help")
        check(f"{name} --help", rc == 0)
        for k in c["keys"]:
            if k["type"] in ("type", "layers") or k["key"] == "compression":
                continue
            check(f"{name} --help lists --{k['flag']}", f"--{k['flag']}" in out)
    check(f"{name}: a sharing mode", c["share"] in ("bands", "points parts", "whole"), c["share"])
    # a small bake, natively
    path = write(f"{name}.json", scene(c))
    rc, _, err = run("render", path, "--backend", "native", "--quiet", "-o", f"{name}-native.exr")
    check(f"{name}: the example bakes natively", rc == 0, err.strip())
    rc, out, err = run("plan", path, "--tasks", "1", "--json")
    check(f"{name}: plan", rc == 0, err.strip())
    layer = json.loads(out)["layers"][-1]["name"] if rc == 0 else name  # the example's last layer
    rc, out, err = run("info", f"{name}-native.exr", "--json")
    check(f"{name}: info reads it", rc == 0, err.strip())
    if rc == 0:
        layers = [l["layer"] for l in json.loads(out)["layers"]]
        check(f"{name}: the file holds layer {layer}", layer in layers, str(layers))
    # the plan: a positive cost, growing with the image; bands for a banded class
    costs = []
    for size in ((64, 32), (256, 128)):
        rc, out, err = run("plan", write(f"{name}-plan.json", scene(c, size)), "--tasks", "4", "--task-startup", "0",
                           "--json")
        check(f"{name}: plan", rc == 0, err.strip())
        if rc == 0:
            p = json.loads(out)
            L = [l for l in p["layers"] if l["name"] == layer]
            check(f"{name}: the plan lists the layer", len(L) == 1, str(p["layers"]))
            if L:
                costs.append(L[0]["seconds"])
                if c["share"] == "bands" and size == (256, 128):
                    check(f"{name}: a banded class is split in bands", L[0]["split"] == "bands", L[0]["split"])
    check(f"{name}: positive costs that grow with the image", len(costs) == 2 and 0 < costs[0] < costs[1], str(costs))
    # bad input
    refused(f"{name}: an unknown key", ["render", write(f"{name}-badkey.json", scene(c, extra={"no-such-key": 1})),
                                        "-o", "bad.exr"], "bad.exr", "no-such-key")
    num = [k for k in c["keys"] if k["type"] in ("int", "number")]
    if num:
        k = num[0]["key"]
        refused(f"{name}: a string for number key {k}",
                ["render", write(f"{name}-badval.json", scene(c, extra={k: "many"})), "-o", "bad.exr"], "bad.exr", k)
    # Vulkan against native, within the class's stated tolerance
    if gpu:
        rc, _, err = run("render", path, "--backend", "vulkan", "--validation", "--quiet", "-o", f"{name}-vulkan.exr")
        check(f"{name}: the example bakes on Vulkan", rc == 0, err.strip())
        t = c["tolerance"]
        args = ["compare", f"{name}-native.exr", f"{name}-vulkan.exr", "--quiet"]
        if t["max_abs"] > 0 or t["fail_percent"] > 0:
            args += ["--max-abs", repr(t["max_abs"]), "--fail-percent", repr(t["fail_percent"])]
        rc, out, err = run(*args)
        check(f"{name}: Vulkan within the stated tolerance of native ({t})", rc == 0, (out + err).strip())

print(f"{passed} passed, {failed} failed")
sys.exit(1 if failed else 0)
