"""The Python module (python/fractalbake) against the command line: the same bits, the same error
lines, progress and cancelling (a callback, Ctrl-C), compare's statistics, two contexts on two
backends at once. Run by tests/python/run.sh, which names the program and the library."""
import json
import os
import signal
import subprocess
import sys
import threading

import numpy as np
import pytest

import fractalbake

FB = os.environ["FRACTALBAKE_PROGRAM"]
ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
SMALL = ["size=96x48"]


def cli(*args, check=True):
    p = subprocess.run([FB, *args], capture_output=True, text=True)
    if check:
        assert p.returncode == 0, p.stderr
    return p


def same_bits(a, b):
    assert list(a) == list(b)
    for k in a:
        assert a[k].dtype == b[k].dtype and a[k].shape == b[k].shape, k
        assert a[k].tobytes() == b[k].tobytes(), f"{k} differs"


@pytest.fixture(scope="module")
def cli_small(tmp_path_factory):
    path = tmp_path_factory.mktemp("cli") / "small.exr"
    cli("render", "-q", "--backend", "native", "--set", SMALL[0], "-o", str(path))
    return path


def test_render_equals_cli(cli_small):
    planes = fractalbake.render(sets=SMALL, backend="native")
    same_bits(fractalbake.read(cli_small), planes)
    # the types are the EXR's, as `fractalbake info` lists them
    info = cli("info", str(cli_small)).stdout
    assert planes["sky.R"].dtype == np.float16 and "R (half)" in info
    assert planes["sky.iter"].dtype == np.uint32 and "iter (uint)" in info
    assert planes["detail.Y"].dtype == np.float32 and planes["detail.Y"].shape == (48, 96)
    assert np.isfinite(planes["sky.R"]).all() and planes["sky.R"].std() > 0  # a picture, not a constant


def test_size_argument_is_the_set(cli_small):
    same_bits(fractalbake.read(cli_small), fractalbake.render(size=(96, 48), backend="native"))


def test_docs_example_full_default_scene():
    """docs/examples/library.py: the default scene at its own size, in-process against the CLI."""
    p = subprocess.run([sys.executable, os.path.join(ROOT, "docs/examples/library.py"), FB], capture_output=True,
                       text=True, env=os.environ)
    assert p.returncode == 0, p.stdout + p.stderr
    assert "1024 x 512" in p.stdout and "the same bits" in p.stdout


def test_bake_file_and_region(tmp_path, cli_small):
    out = tmp_path / "lib.exr"
    fractalbake.bake(None, out, sets=SMALL, backend="native")
    full = fractalbake.read(out)
    same_bits(fractalbake.read(cli_small), full)
    part = fractalbake.render(sets=SMALL, backend="native", region=(10, 7, 40, 21))
    for k in full:
        assert part[k].tobytes() == full[k][7:28, 10:50].tobytes(), k


def test_scene_as_text_dict_and_path(tmp_path):
    text = '{"size": [64, 32], "seed": 3, "layers": [{"type": "fbm", "name": "n", "octaves": 4}]}'
    path = tmp_path / "s.json"
    path.write_text(text)
    a = fractalbake.render(text, backend="native")
    b = fractalbake.render(json.loads(text), backend="native")
    c = fractalbake.render(str(path), backend="native")
    cli("render", "-q", "--backend", "native", str(path), "-o", str(tmp_path / "s.exr"))
    same_bits(fractalbake.read(tmp_path / "s.exr"), a)
    same_bits(a, b)
    same_bits(a, c)


def test_render_writes_no_file(tmp_path, monkeypatch):
    # a scene that names an instances file and a heightmap: render() returns planes and writes neither (the
    # scene's own folder, the working folder); bake() writes them beside the scene, as the command line does
    scene = {"size": [64, 48], "seed": 2, "layers": [
        {"type": "fbm", "name": "ground", "octaves": 3, "heightmap": "ground.png", "heightmap-range": [-2, 2]},
        {"type": "ifs", "name": "trees", "preset": "population", "points": 20000, "instances": "trees.csv",
         "instances-surface": "ground", "instances-min-size": 0.5}]}
    (tmp_path / "scene").mkdir()
    (tmp_path / "work").mkdir()
    path = tmp_path / "scene" / "s.json"
    path.write_text(json.dumps(scene))
    monkeypatch.chdir(tmp_path / "work")
    planes = fractalbake.render(str(path), backend="native")
    assert sorted(os.listdir(tmp_path / "scene")) == ["s.json"] and os.listdir(tmp_path / "work") == []
    fractalbake.bake(str(path), str(tmp_path / "work" / "s.exr"), backend="native")
    assert sorted(os.listdir(tmp_path / "scene")) == ["ground.png", "s.json", "trees.csv"]
    same_bits(fractalbake.read(tmp_path / "work" / "s.exr"), planes)


def test_errors_are_the_cli_line(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text('{"size": [64, 32], "layers": [{"type": "fbm", "octaves": 99}]}')
    p = cli("render", "-q", str(path), "-o", str(tmp_path / "x.exr"), check=False)
    assert p.returncode == 2
    with pytest.raises(fractalbake.Error) as e:
        fractalbake.render(str(path), backend="native")
    assert str(e.value) == p.stderr.strip() and "octaves" in str(e.value) and e.value.code == 2
    with pytest.raises(fractalbake.Error) as e:
        fractalbake.render(backend="cuda")
    assert str(e.value) == 'fractalbake: backend "cuda": expected auto, vulkan or native' and e.value.code == 1


def test_progress_and_cancel(tmp_path):
    seen = []
    fractalbake.render(sets=SMALL, backend="native", progress=seen.append)
    assert seen and seen == sorted(seen) and seen[-1] == 1.0 and all(0 <= f <= 1 for f in seen)
    out = tmp_path / "stopped.exr"
    with pytest.raises(fractalbake.Error) as e:
        fractalbake.bake(None, out, sets=SMALL, backend="native", progress=lambda f: True)
    assert e.value.code == fractalbake.ERR_CANCELLED and "cancelled" in str(e.value)
    assert not out.exists() and os.listdir(tmp_path) == []


def test_ctrl_c_cancels_cleanly(tmp_path):
    """SIGINT during a bake: the bake stops at its next strip, no file is left, KeyboardInterrupt is raised."""
    out = tmp_path / "interrupted.exr"
    calls = []

    def progress(f):
        calls.append(f)
        if len(calls) == 1:
            signal.raise_signal(signal.SIGINT)  # what Ctrl-C sends; Python raises it here

    with pytest.raises(KeyboardInterrupt):
        fractalbake.bake(None, out, sets=["size=96x96"], backend="native", progress=progress)
    assert len(calls) >= 1 and not out.exists() and os.listdir(tmp_path) == []
    # the context still works afterwards
    assert "sky.R" in fractalbake.render(sets=SMALL, backend="native")


# A bake of several seconds on one thread (julia, 3000 iterations, 2048 x 2048: 2 to 8 s on a loaded
# two-core machine); the child says "started" at its first progress call, then waits in the bake.
CHILD = r"""
import os, sys, time, fractalbake
out, started = sys.argv[1], []
def progress(f):
    if not started:
        started.append(f)
        print("started", flush=True)
    started.append(f)
try:
    fractalbake.bake({"size": [2048, 2048], "layers": [{"name": "j", "type": "julia", "max-iter": 3000}]}, out,
                     backend="native", threads=1, progress=progress)
    print("finished", flush=True)
except KeyboardInterrupt:
    print(f"KeyboardInterrupt {time.monotonic():.6f} last {started[-1]} cpu {time.process_time():.6f}", flush=True)
"""


def cpu_seconds(pid):
    """A process's CPU time so far, user and system, from /proc (all its threads)."""
    fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def test_sigint_from_outside_stops_the_bake(tmp_path):
    """Ctrl-C as a terminal sends it: SIGINT from another process while the bake runs in C. Within one
    second the call raises KeyboardInterrupt, the process lives on, and nothing is left in the folder.
    The second is the child's own CPU time from the signal to the exception (its clock on an idle
    machine; on a loaded one the wall clock also counts the time others had the cores, so the wall
    bound is ten times looser: a bake that ignored the signal would run for seconds of CPU)."""
    out = tmp_path / "sigint.exr"
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(out)], stdout=subprocess.PIPE, text=True,
                             env=os.environ)
    try:
        assert child.stdout.readline().strip() == "started"
        import time
        time.sleep(0.3)  # well inside the bake's C code
        sent, cpu_sent = time.monotonic(), cpu_seconds(child.pid)
        child.send_signal(signal.SIGINT)
        line = child.stdout.readline().split()
        assert child.wait(timeout=30) == 0
    finally:
        child.kill()
    assert line[:1] == ["KeyboardInterrupt"], line
    assert float(line[5]) - cpu_sent < 1.0, f"KeyboardInterrupt {float(line[5]) - cpu_sent:.3f} CPU s after SIGINT"
    assert float(line[1]) - sent < 10.0, f"KeyboardInterrupt {float(line[1]) - sent:.3f} s after SIGINT"
    assert float(line[3]) < 1.0  # the bake had not finished
    assert os.listdir(tmp_path) == []  # no output, no temporary file


def test_callback_exception_cancels_and_is_raised(tmp_path):
    out = tmp_path / "raised.exr"
    calls = []

    def progress(f):
        calls.append(f)
        raise ValueError("from the callback")

    with pytest.raises(ValueError, match="from the callback"):
        fractalbake.bake(None, out, sets=SMALL, backend="native", progress=progress)
    assert calls == [calls[0]] and os.listdir(tmp_path) == []  # called once: the bake stopped
    assert "sky.R" in fractalbake.render(sets=SMALL, backend="native")


@pytest.mark.parametrize("call, kind, words", [
    (lambda o: fractalbake.render(sets=[None], backend="native"), TypeError,
     'sets[0]: expected a "KEY.PATH=VALUE" string such as "seed=9", found NoneType None'),
    (lambda o: fractalbake.render(sets="seed=9", backend="native"), TypeError, "sets: expected a list"),
    (lambda o: fractalbake.render(sets=SMALL, region=(0, 0, 2 ** 32 + 4, 4), backend="native"), OverflowError,
     "region[2] (w) 4294967300: does not fit the C argument"),
    (lambda o: fractalbake.render(sets=SMALL, region=(0, 0, 70000, 4), backend="native"), ValueError,
     "region[2] (w) 70000: expected w, h in 1..65536"),
    (lambda o: fractalbake.bake(None, o, sets=SMALL, region=(-1, 0, 4, 4), backend="native"), ValueError,
     "region[0] (x) -1: expected x, y >= 0"),
    (lambda o: fractalbake.render(sets=SMALL, size=(2 ** 40, 4), backend="native"), OverflowError, "size[0]"),
    (lambda o: fractalbake.render(size="big", backend="native"), TypeError, "size: expected W or (W, H)"),
    (lambda o: fractalbake.render(sets=SMALL, backend="native", threads=10 ** 6), ValueError,
     "threads 1000000: expected 0 (one per core) or 1..1024, as --threads"),
    (lambda o: fractalbake.render(sets=SMALL, backend="native", threads=2.5), TypeError,
     "threads: expected an integer, found float 2.5"),
    (lambda o: fractalbake.render(sets=SMALL, backend="native", max_memory=-1), ValueError,
     "max_memory -1: expected 0 (80% of the memory) or 1 MiB to 9e18 bytes, as --max-memory"),
    (lambda o: fractalbake.render(sets=SMALL, backend="native", max_memory=2 ** 64), OverflowError, "max_memory"),
    (lambda o: fractalbake.render(sets=SMALL, backend="native", max_memory=1000), ValueError, "max_memory 1000"),
    (lambda o: fractalbake.render(sets=SMALL, backend="native", progress=5), TypeError, "progress: expected a callable"),
    (lambda o: fractalbake.bake(None, 7, sets=SMALL, backend="native"), TypeError, "path: expected a str"),
    (lambda o: fractalbake.bake(None, str(o) + "\0.png", sets=SMALL, backend="native"), ValueError, "NUL"),
    (lambda o: fractalbake.render(b"{}", backend="native"), TypeError, "scene: JSON text, a path"),
    (lambda o: fractalbake.compare(o, o, max_abs=[1]), TypeError, "max_abs: expected a str or a number"),
])
def test_bad_arguments_raise_before_any_call(tmp_path, call, kind, words):
    out = tmp_path / "bad.exr"
    with pytest.raises(kind) as e:
        call(out)
    assert str(e.value).startswith("fractalbake: ") and words in str(e.value), str(e.value)
    assert "\n" not in str(e.value) and os.listdir(tmp_path) == []


def test_reentry_from_a_callback_is_an_error_not_a_deadlock(tmp_path):
    out = tmp_path / "outer.exr"
    result = {}

    def progress(f):
        fractalbake.render(sets=SMALL, backend="native")  # the same context: the module keeps one

    def run():
        try:
            fractalbake.bake(None, out, sets=SMALL, backend="native", progress=progress)
        except BaseException as e:
            result["e"] = e

    t = threading.Thread(target=run, daemon=True)
    t.start()
    t.join(120)
    assert not t.is_alive(), "deadlocked"
    e = result.get("e")
    assert isinstance(e, fractalbake.Error) and e.code == 1, repr(e)
    assert str(e) == ("fractalbake: render: the context is running another call (this one came from its progress "
                      "callback): a context runs one call at a time")
    assert os.listdir(tmp_path) == []
    ctx = fractalbake.Context("native", threads=1)
    with pytest.raises(fractalbake.Error, match="close: called from the context's own progress callback"):
        ctx.bake(None, out, sets=SMALL, progress=lambda f: ctx.close())
    assert "sky.R" in ctx.render(sets=["size=8x4"]) and not out.exists()  # still open
    ctx.close()
    # a callback may use another context
    other = fractalbake.Context("native", threads=1)
    inner = []

    def progress_other(f):
        if not inner:
            inner.append(other.render(sets=["size=8x4"]))  # returns None: the bake goes on

    fractalbake.bake(None, out, sets=SMALL, backend="native", progress=progress_other)
    assert out.exists() and inner and inner[0]["sky.R"].shape == (4, 8)
    other.close()


def test_no_bake_replaces_its_input_or_names_another_format(tmp_path):
    scene = tmp_path / "s.exr"  # a JSON scene under an EXR's name, as a user may keep one
    scene.write_text('{"size": [32, 16], "layers": [{"name": "n", "type": "fbm"}]}')
    before = scene.read_bytes()
    p = cli("render", str(scene), "-o", str(scene), check=False)
    with pytest.raises(fractalbake.Error) as e:
        fractalbake.bake(str(scene), str(scene), backend="native")
    assert p.returncode == 2 and e.value.code == 1 and str(e.value) == p.stderr.strip()
    assert "is an input of this run (read as the scene)" in str(e.value)
    with pytest.raises(fractalbake.Error) as e:
        fractalbake.bake(str(scene), tmp_path / "o.png", backend="native")
    assert str(e.value).endswith("o.png: this writes OpenEXR (.exr), not .png: name the file .exr")
    with pytest.raises(fractalbake.Error) as e:
        fractalbake.bake(str(scene), "-", backend="native")
    assert "the library writes no standard output" in str(e.value)
    assert scene.read_bytes() == before and sorted(os.listdir(tmp_path)) == ["s.exr"]


def test_compare_is_the_cli_json(tmp_path):
    a, b = tmp_path / "a.exr", tmp_path / "b.exr"
    fractalbake.bake(None, a, sets=SMALL, backend="native")
    fractalbake.bake(None, b, sets=SMALL + ["seed=8"], backend="native")
    ours = fractalbake.compare(a, b, max_abs="0.5")
    theirs = json.loads(cli("compare", "--json", "--max-abs", "0.5", str(a), str(b), check=False).stdout)
    assert ours == theirs
    assert ours["result"] == "fail" and len(ours["channels"]) == 24
    # the statistics against numpy's, on the arrays read back
    pa, pb = fractalbake.read(a), fractalbake.read(b)
    for ch in ours["channels"]:
        d = np.abs(pa[ch["name"]].astype(np.float64) - pb[ch["name"]].astype(np.float64))
        assert ch["max_abs"] == pytest.approx(d.max(), rel=1e-12, abs=0), ch["name"]
        assert ch["rmse"] == pytest.approx(np.sqrt((d * d).mean()), rel=1e-9), ch["name"]
        assert ch["beyond_fail_pixels"] == int((d > 0.5).sum()), ch["name"]
    same = fractalbake.compare(a, a)
    assert same["result"] == "pass" and all(ch["max_abs"] == 0 for ch in same["channels"])


def test_two_contexts_on_two_backends():
    try:
        vk = fractalbake.Context("vulkan", threads=2)
    except fractalbake.Error as e:
        pytest.skip(f"no Vulkan device: {e}")
    nat = fractalbake.Context("native", threads=2)
    assert (vk.backend, nat.backend) == ("vulkan", "native")
    results, errors = {}, {}

    def work(name, ctx):
        for _ in range(2):
            results[name] = ctx.render(sets=SMALL)
        try:
            ctx.render(sets=["seed=-1"])
        except fractalbake.Error as e:
            errors[name] = str(e)

    threads = [threading.Thread(target=work, args=a) for a in (("vk", vk), ("nat", nat))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    same_bits(results["vk"], results["nat"])
    assert errors["vk"] == errors["nat"] and "seed" in errors["vk"]
    vk.close()
    nat.close()
