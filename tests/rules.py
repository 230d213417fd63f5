#!/usr/bin/env python3
"""The house rules, checked on the source tree (docs/architecture.md, host/base/fb.h):

  env      Only host/cli/env.c reads the environment (getenv, secure_getenv, environ, setenv,
           putenv, unsetenv): settings reach the libraries in descriptors.
  print    Below host/cli (every other folder of host/, and kernels/) nothing prints or exits: no
           printf, vprintf, puts, putchar, perror, psignal, no stdout, stderr or STDERR_FILENO, no
           exit, _exit, _Exit or quick_exit (comments and strings aside). Library code hands text to
           the logger; the commands of host/cli print.
  length   No function of host/ or kernels/ is longer than 150 lines, but those of LONG_ALLOWED.
  table    docs/architecture.md's table of folders has a row for every folder of host/ (one row
           `host/gen/NAME/` for the generators, each of which has its layer.c and gen_NAME.h),
           naming in it every .c file of the folder and every header that has no .c of its name;
           every file a row names exists.
  gens     host/gen/list.c lists every folder of host/gen/ and no other; each generator's class
           (fb_gen_NAME) is defined in its folder, so that tests/conformance.py, which walks the
           list, holds it to the contract; each has a golden scene: a tests/golden/scenes/*.json
           with a layer of its type, listed in tests/golden/thresholds.txt, with its reference EXR.
  layers   scripts/check-layers.sh --allowed and CMakeLists.txt agree: each folder may include
           exactly the folders that its library links, directly or through others.
  paths    Every path of the repository that a comment of host/ or kernels/ names exists (NAME
           stands for any generator; a * is a pattern), but those of PATH_ALLOWED.
  picture  docs/img/architecture.svg is what scripts/architecture-svg.py draws from the code: every
           folder, every generator, the arrows that check-layers.sh allows.
  params   No generator (host/gen) assigns a JSON value to its parameters by hand: a key's table entry
           names its field (FB_FIELD) and the schema check fills it (core/schema.h). A statement that
           reads a JSON value (fb_json_num, json_number_value, json_string_value, ...) and names a
           params pointer of its function (one taken from ->params or fb_layer_params, or a parameter
           of an fb_*params type) is a breach; a value type's reader (fb_kvalue.read) writes its own
           field, and checks that read a value into a local stay.
  tests    Tests are added with fb_test (cmake/fb_test.cmake) alone: no add_test or
           set_tests_properties elsewhere, so that the tiers are the labels.

Usage: rules.py [ROOT]   with ROOT: check that tree and print what breaks a rule (exit 1 if any);
                         without: check this tree, then check the checker on a scratch copy of it
                         with violations planted (a getenv in a generator, a golden removed, ...):
                         each must be found.
"""
import functools
import glob
import importlib.util
import os
import re
import shutil
import subprocess
import sys
import tempfile

MAX_LINES = 150
# Functions over MAX_LINES that their owners are rewriting now: the lead empties this list as their
# branches land (issue 43).
LONG_ALLOWED = set()
# Paths in comments that name what no longer exists, in files that others own now (issue 43).
PATH_ALLOWED = set()
ENV_READER = "host/cli/env.c"


def sources(root, top):
    """The C files under root/top, as paths relative to root, sorted."""
    out = []
    for dirpath, _, names in os.walk(os.path.join(root, top)):
        for n in names:
            if n.endswith((".c", ".h")):
                out.append(os.path.relpath(os.path.join(dirpath, n), root))
    return sorted(out)


def read(root, rel):
    with open(os.path.join(root, rel), encoding="utf-8", errors="replace") as f:
        return f.read()


_LEXEMES = re.compile(r"/\*.*?\*/|//[^\n]*|\"(?:\\.|[^\"\\\n])*\"|'(?:\\.|[^'\\\n])*'", re.S)


@functools.lru_cache(maxsize=None)
def code_only(text):
    """text with comments and string and character literals blanked (newlines kept)."""

    def blank(m):
        t = m.group(0)
        if t[0] in "\"'":
            return t[0] + re.sub(r"[^\n]", " ", t[1:-1]) + t[-1]
        return re.sub(r"[^\n]", " ", t)

    return _LEXEMES.sub(blank, text)


@functools.lru_cache(maxsize=None)
def comments_only(text):
    """The text of text's comments, joined by newlines."""
    return "\n".join(m.group(0) for m in _LEXEMES.finditer(text) if m.group(0)[0] == "/")


def line_of(text, pos):
    return text.count("\n", 0, pos) + 1


def check_env(root, bad):
    pat = re.compile(r"\b(getenv|secure_getenv|setenv|putenv|unsetenv|environ)\b")
    for rel in sources(root, "host") + sources(root, "kernels"):
        if rel == ENV_READER:
            continue
        text = read(root, rel)
        if "env" not in text:
            continue
        code = code_only(text)
        for m in pat.finditer(code):
            bad.append(f"env: {rel}:{line_of(code, m.start())}: {m.group(1)}: only {ENV_READER} reads the environment")


def below_cli(rel):
    return not rel.startswith("host/cli/")


def check_print(root, bad):
    # calls (a format(printf, ...) attribute is no call) and the standard streams by name
    pat = re.compile(
        r"\b(?:(printf|vprintf|puts|putchar|perror|psignal|exit|_exit|_Exit|quick_exit)\s*\(|"
        r"(stdout|stderr|STDERR_FILENO)\b)"
    )
    for rel in sources(root, "host") + sources(root, "kernels"):
        if not below_cli(rel):
            continue
        code = code_only(read(root, rel))
        if not any(w in code for w in ("put", "print", "std", "STDERR", "exit")):
            continue
        for m in pat.finditer(code):
            word = m.group(1) or m.group(2)
            what = "exits" if "exit" in word.lower() else "prints"
            bad.append(f"print: {rel}:{line_of(code, m.start())}: {word}: library code never {what} (fb.h)")


def functions(text):
    """(name, first line, line count) of each function defined in text: a header at column 0, its
    body from a `{` alone on a line to the next `}` alone on a line (the house format)."""
    lines = text.split("\n")
    out = []
    i = 0
    while i < len(lines):
        if lines[i] == "{" and i > 0:
            j = i - 1
            while j > 0 and lines[j][:1] in (" ", "\t"):
                j -= 1
            k = i + 1
            while k < len(lines) and lines[k] != "}":
                k += 1
            m = re.search(r"(\w+)\s*\(", lines[j])
            out.append((m.group(1) if m else lines[j].strip(), j + 1, k - j + 1))
            i = k
        i += 1
    return out


def check_length(root, bad):
    for rel in sources(root, "host") + sources(root, "kernels"):
        for name, first, count in functions(code_only(read(root, rel))):
            if count > MAX_LINES and (rel, name) not in LONG_ALLOWED:
                bad.append(f"length: {rel}:{first}: {name} is {count} lines (at most {MAX_LINES})")


def table_rows(root):
    """{folder: the names of files its row of docs/architecture.md's table names} ("gen/NAME" for
    the generators' row; "gen" for host/gen/list.c's)."""
    rows = {}
    for line in read(root, "docs/architecture.md").split("\n"):
        m = re.match(r"\|\s*`host/([^`]*)`\s*\|(.*)", line)
        if not m:
            continue
        key = m.group(1).rstrip("/")
        if key == "gen/list.c":
            key = "gen"
        names = set(re.findall(r"`([^`]*)`", m.group(2)))
        names = {os.path.basename(n) for n in names if re.search(r"\.[ch]$", n)}
        if key == "gen":
            names.add("list.c")
        rows[key] = names
    return rows


def host_folders(root):
    out = []
    for dirpath, _, names in os.walk(os.path.join(root, "host")):
        if any(n.endswith((".c", ".h")) for n in names):
            out.append(os.path.relpath(dirpath, os.path.join(root, "host")))
    return sorted(out)


def generators(root):
    return sorted(os.path.basename(os.path.dirname(p)) for p in glob.glob(os.path.join(root, "host/gen/*/")))


def check_table(root, bad):
    rows = table_rows(root)
    for folder in host_folders(root):
        files = sorted(os.listdir(os.path.join(root, "host", folder)))
        if folder.startswith("gen/"):
            name = folder[4:]
            if "gen/NAME" not in rows:
                bad.append("table: docs/architecture.md has no row `host/gen/NAME/`")
            for want in ("layer.c", f"gen_{name}.h"):
                if want not in files:
                    bad.append(f"table: host/{folder}/ has no {want} (a generator's folder: docs/architecture.md)")
            continue
        if folder not in rows:
            bad.append(f"table: docs/architecture.md's table has no row for host/{folder}/")
            continue
        stems = {f[:-2] for f in files if f.endswith(".c")}
        for f in files:
            if folder == "gen" or not f.endswith((".c", ".h")):
                continue
            if (f.endswith(".c") or f[:-2] not in stems) and f not in rows[folder]:
                bad.append(f"table: docs/architecture.md's row for host/{folder}/ does not name {f}")
        for f in sorted(rows[folder]):
            if f not in files:
                bad.append(f"table: docs/architecture.md's row for host/{folder}/ names {f}, which is not there")


def check_gens(root, bad):
    listed = re.findall(r"\bX\((\w+)\)", read(root, "host/gen/list.c"))
    folders = generators(root)
    for g in sorted(set(folders) - set(listed)):
        bad.append(f"gens: host/gen/{g}/ is not in host/gen/list.c's FB_GENERATORS")
    for g in sorted(set(listed) - set(folders)):
        bad.append(f"gens: host/gen/list.c lists {g}, which has no folder host/gen/{g}/")
    golden = {}  # generator -> the golden scenes that have a layer of its type
    names = re.findall(r"^(\w[\w-]*)", read(root, "tests/golden/thresholds.txt"), re.M)
    for name in names:
        scene = os.path.join(root, "tests/golden/scenes", name + ".json")
        if name != "default" and not os.path.exists(scene):
            bad.append(f"gens: tests/golden/thresholds.txt lists {name}, which has no tests/golden/scenes/{name}.json")
            continue
        if not os.path.exists(os.path.join(root, "tests/golden", name + ".exr")):
            bad.append(f"gens: the golden scene {name} has no reference tests/golden/{name}.exr")
        if name != "default":
            for t in re.findall(r'"type"\s*:\s*"(\w+)"', read(root, f"tests/golden/scenes/{name}.json")):
                golden.setdefault(t, []).append(name)
    for g in folders:
        code = "".join(read(root, p) for p in sources(root, f"host/gen/{g}"))
        if not re.search(rf"\bconst fb_gen_class fb_gen_{g}\s*=", code):
            bad.append(f"gens: host/gen/{g}/ defines no class fb_gen_{g} (the conformance test walks the list's classes)")
        if g not in golden:
            bad.append(
                f"gens: {g} has no golden scene (tests/golden/scenes/*.json with a layer of type {g}, "
                "listed in tests/golden/thresholds.txt: scripts/golden.sh)"
            )


def cmake_links(root):
    """{folder of host/: the folders its library links, directly or not}, from CMakeLists.txt."""
    text = re.sub(r"(^|\s)#[^\n]*", r"\1", read(root, "CMakeLists.txt"))
    gens = generators(root)
    folder, links = {}, {}
    for cmd, args in re.findall(r"(\w+)\(([^()]*)\)", text):
        variants = [args.replace("${g}", g) for g in gens] if "${g}" in args else [args]
        for a in variants:
            words = a.split()
            if cmd == "target_include_directories" and "PUBLIC" in words:
                for w in words[words.index("PUBLIC") + 1 :]:
                    if w.startswith("host/"):
                        folder.setdefault(words[0], w[5:].rstrip("/"))
                        break
            elif cmd == "target_link_libraries" and words:
                links.setdefault(words[0], set()).update(w for w in words[1:] if w.startswith("fb_"))
    out = {}
    for lib, f in folder.items():
        seen, todo = set(), [lib]
        while todo:
            for d in links.get(todo.pop(), ()):
                if d not in seen:
                    seen.add(d)
                    todo.append(d)
        out[f] = {f} | {folder[d] for d in seen if d in folder}
    return out


@functools.lru_cache(maxsize=None)
def allowed_by_script(root, script, folders):
    """check-layers.sh --allowed's output (its text and host/'s folders as the cache's key)."""
    p = subprocess.run(
        ["bash", os.path.join(root, "scripts/check-layers.sh"), "--allowed", os.path.join(root, "host")],
        capture_output=True,
        text=True,
    )
    return p.returncode, p.stdout, p.stderr


def check_layers(root, bad):
    rc, out, err = allowed_by_script(root, read(root, "scripts/check-layers.sh"), tuple(host_folders(root)))
    if rc != 0:
        bad.append(f"layers: scripts/check-layers.sh --allowed failed: {err.strip()}")
        return
    allowed = {}
    for line in out.splitlines():
        folder, _, rest = line.partition(":")
        allowed[folder.strip()] = set(rest.split())
    linked = cmake_links(root)
    for f in sorted(set(allowed) | set(linked)):
        a, l = allowed.get(f), linked.get(f)
        if a is None or l is None:
            where = "CMakeLists.txt has no library publishing it" if l is None else "check-layers.sh does not know it"
            bad.append(f"layers: host/{f}: {where}")
        elif a != l:
            extra, missing = sorted(a - l), sorted(l - a)
            bad.append(
                f"layers: host/{f}: check-layers.sh allows {' '.join(extra) or '-'} beyond CMakeLists.txt's links, "
                f"and not {' '.join(missing) or '-'} that they have"
            )


def check_paths(root, bad):
    pat = re.compile(r"\b((?:tests|scripts|docs|host|kernels|shaders|bench|cmake)/[\w.*/-]*\w)")
    for rel in sources(root, "host") + sources(root, "kernels"):
        for path in sorted(set(pat.findall(comments_only(read(root, rel))))):
            if (rel, path) in PATH_ALLOWED:
                continue
            if "NAME" in path:
                path = path.replace("NAME", "*")
            if not glob.glob(os.path.join(root, path)):
                bad.append(f"paths: {rel}: a comment names {path}, which is not in the repository")


def check_picture(root, bad):
    rc, out, _ = allowed_by_script(root, read(root, "scripts/check-layers.sh"), tuple(host_folders(root)))
    if rc != 0:
        return  # check_layers names it
    spec = importlib.util.spec_from_file_location("architecture_svg", os.path.join(root, "scripts/architecture-svg.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    try:
        svg = module.draw(root, out)
    except SystemExit as e:
        bad.append(f"picture: scripts/architecture-svg.py: {e}")
        return
    if svg != read(root, "docs/img/architecture.svg"):
        bad.append("picture: docs/img/architecture.svg is not what scripts/architecture-svg.py draws from the code "
                   "(scripts/architecture-svg.py > docs/img/architecture.svg)")


JSON_READERS = re.compile(r"\b(fb_json_num|fb_json_bool|fb_json_vec2|fb_json_string|fb_json_ref|json_number_value|"
                          r"json_integer_value|json_real_value|json_boolean_value|json_is_true|json_string_value)\s*\(")


def check_params(root, bad):
    taken = re.compile(r"\b(\w+)\s*=\s*(?:\([^()]*\)\s*)?(?:\w+->params\b|fb_layer_params\s*\()")
    typed = re.compile(r"\bfb_\w*params\s*\*\s*(\w+)")
    for rel in sources(root, "host/gen"):
        code = code_only(read(root, rel))
        if not JSON_READERS.search(code):
            continue
        lines = code.split("\n")
        for name, first, count in functions(code):
            body = "\n".join(lines[first - 1: first - 1 + count])
            ptrs = set(taken.findall(body)) | set(typed.findall(body))
            if not ptrs:
                continue
            named = re.compile(r"\b(?:" + "|".join(sorted(ptrs)) + r")\s*(?:->|\.)")
            pos = 0
            for stmt in re.split(r"(?<=;)", body):
                m = JSON_READERS.search(stmt)
                if m and named.search(stmt):
                    line = first + body.count("\n", 0, pos + m.start())
                    bad.append(f"params: {rel}:{line}: {m.group(1)} in {name}: a key's table entry names its field "
                               f"(FB_FIELD) and the schema check fills it (core/schema.h)")
                pos += len(stmt)


def check_tests(root, bad):
    for rel in ["CMakeLists.txt"] + sorted(
        os.path.relpath(p, root) for p in glob.glob(os.path.join(root, "tests/**/CMakeLists.txt"), recursive=True)
    ):
        text = re.sub(r"(^|\s)#[^\n]*", r"\1", read(root, rel))
        for m in re.finditer(r"\b(add_test|set_tests_properties)\s*\(", text):
            bad.append(f"tests: {rel}:{line_of(text, m.start())}: {m.group(1)}: add tests with fb_test")


def check_verdicts(root, bad):
    """Debian 12's exrinfo (OpenEXR 3.1.5) exits with a random status on valid files: a test or script
    may read what it prints (`$(exrinfo ...)`, `exrinfo ... |`), never take its exit status."""
    files = sorted(os.path.relpath(p, root) for pat in ("tests/**/*.sh", "tests/**/*.py", "scripts/**/*.sh",
                                                         "scripts/**/*.py", "bench/**/*.sh", "bench/**/*.py")
                   for p in glob.glob(os.path.join(root, pat), recursive=True))
    for rel in files:
        if rel in ("tests/rules.py", "tests/cli/verdicts.sh"):  # this check, and the test of a lying exrinfo
            continue
        for n, line in enumerate(read(root, rel).split("\n"), 1):
            code = line.split("#", 1)[0] if rel.endswith(".sh") else line
            for m in re.finditer(r"\bexrinfo\b", code):
                before, after = code[: m.start()], code[m.end():]
                if rel.endswith(".sh") and (before.rstrip().endswith("$(") or re.match(r"[^|;&]*\|(?!\|)", after)):
                    continue
                bad.append(f"verdicts: {rel}:{n}: exrinfo's exit status is no verdict (read its output: exr_strict)")


CHECKS = [check_env, check_print, check_length, check_table, check_gens, check_layers, check_picture, check_paths,
          check_params, check_tests, check_verdicts]


def check(root):
    bad = []
    for c in CHECKS:
        c(root, bad)
    return bad


def scratch(src, dst):
    """A copy of src at dst for planting: the files the rules read copied, the rest linked."""
    copy = {"host", "kernels", "scripts", "cmake", "CMakeLists.txt", "docs/architecture.md", "docs/img/architecture.svg",
            "tests/CMakeLists.txt", "tests/golden/scenes", "tests/golden/thresholds.txt", "tests/cli"}

    def walk(rel):
        for name in sorted(os.listdir(os.path.join(src, rel))):
            r = os.path.join(rel, name) if rel else name
            s, d = os.path.join(src, r), os.path.join(dst, r)
            if r in copy:
                (shutil.copytree if os.path.isdir(s) else shutil.copy)(s, d)
            elif any(c.startswith(r + "/") for c in copy):
                os.mkdir(d)
                walk(r)
            elif r not in ("build", ".git"):
                os.symlink(s, d)

    walk("")


def self_test(src):
    src = os.path.abspath(src)
    passed = failed = 0

    def expect(what, cond, detail=""):
        nonlocal passed, failed
        if cond:
            passed += 1
        else:
            failed += 1
            print(f"FAIL: {what}{': ' + detail if detail else ''}", file=sys.stderr)

    bad = check(src)
    for b in bad:
        print(b, file=sys.stderr)
    expect("the tree keeps the rules", not bad, f"{len(bad)} breaches above")
    tmp = tempfile.mkdtemp(prefix="fb-rules-")
    try:
        scratch(src, tmp)
        expect("the scratch copy keeps them", not check(tmp), "; ".join(check(tmp)[:3]))

        def planted(edits):
            """What check finds with edits ({path: new text, or None to remove}) made, then undone."""
            old, made = {}, []
            for rel, text in edits.items():
                p = os.path.join(tmp, rel)
                old[rel] = read(tmp, rel) if os.path.exists(p) else None
                if text is None:
                    os.remove(p)
                    continue
                if not os.path.isdir(os.path.dirname(p)):
                    made.append(os.path.dirname(p))
                    os.makedirs(made[-1])
                with open(p, "w") as f:
                    f.write(text)
            found = check(tmp)
            for rel, text in old.items():
                p = os.path.join(tmp, rel)
                if text is None:
                    os.remove(p)
                else:
                    with open(p, "w") as f:
                        f.write(text)
            for d in made:
                shutil.rmtree(d)
            return found

        def plant(what, edits, *words):
            """The breach planted by edits must be found, in a line with every one of words."""
            found = planted(edits)
            hit = [b for b in found if all(w in b for w in words)]
            expect(f"{what} is found", hit, "found: " + ("; ".join(found) or "nothing"))

        def add(rel, line):
            return {rel: read(tmp, rel) + line}

        fbm = "host/gen/fbm/layer.c"
        plant("a getenv in a generator", add(fbm, 'static const char *planted(void) { return getenv("HOME"); }\n'),
              "env:", fbm, "getenv")
        plant("a getenv in base", add("host/base/output.c", "const char *planted(void) { return getenv(\"TMPDIR\"); }\n"),
              "env:", "host/base/output.c")
        thresholds = "tests/golden/thresholds.txt"
        plant("a golden removed",
              {"tests/golden/scenes/stars.json": None,
               thresholds: re.sub(r"^stars .*\n", "", read(tmp, thresholds), flags=re.M)},
              "gens:", "stars has no golden scene")
        plant("a printf in core", add("host/core/plan.c", 'void planted(void) { printf("x"); }\n'),
              "print:", "host/core/plan.c", "printf")
        plant("stderr in io", add("host/io/pngio.c", 'void planted(void) { fputs("x", stderr); }\n'),
              "print:", "host/io/pngio.c", "stderr")
        plant("an exit in a generator", add(fbm, "void planted(void) { exit(1); }\n"), "print:", fbm, "exit")
        plant("a file the table does not name", {"host/core/planted.c": "int planted;\n"},
              "table:", "host/core/", "planted.c")
        plant("a generator without its folder's files", {"host/gen/planted/bench.c": "int planted;\n"},
              "table:", "host/gen/planted/", "layer.c")
        plant("a function too long", add("host/io/pngio.c", "void planted(void)\n{\n" + "    ;\n" * 150 + "}\n"),
              "length:", "host/io/pngio.c", "planted is 153 lines")
        plant("a generator's include of geom that CMake does not link",
              add("CMakeLists.txt", "target_link_libraries(fb_gen_fbm PUBLIC fb_geom)\n"),
              "layers:", "host/gen/fbm", "not geom")
        svg = "docs/img/architecture.svg"
        plant("a picture drawn by hand", {svg: read(tmp, svg).replace(">julia<", ">juliet<")},
              "picture:", "architecture.svg")
        plant("a generator that the picture does not show",
              {"host/gen/list.c": read(tmp, "host/gen/list.c").replace("X(op)", "X(op) X(planted)"),
               "host/gen/planted/layer.c": "const fb_gen_class fb_gen_planted = {0};\n"}, "picture:")
        plant("a stale path in a comment", add("host/core/plan.c", "/* see tests/planted.py */\n"),
              "paths:", "host/core/plan.c", "tests/planted.py")
        plant("a parameter read from JSON by hand",
              add(fbm, "static void planted(fb_layer *L, const json_t *obj)\n{\n    fb_fbm_params *f = (void *)L->params;\n"
                       "    f->warp = fb_json_num(obj, \"warp\");\n}\n"),
              "params:", fbm, "fb_json_num in planted")
        julia = "host/gen/julia/layer.c"
        plant("a parameter read by a helper given the params",
              add(julia, "static void planted(fb_julia_params *j, const json_t *obj)\n{\n"
                         "    fb_json_vec2(obj, \"c\", j->c);\n}\n"),
              "params:", julia, "fb_json_vec2 in planted")
        found = planted(add(julia, "static bool planted(fb_julia_params *j, const json_t *obj)\n{\n"
                                   "    double c = json_number_value(json_object_get(obj, \"radius\"));\n"
                                   "    return c > j->radius;\n}\n"))
        expect("a value read into a local for a check is no breach", not found, "; ".join(found))
        plant("a test outside fb_test", add("tests/CMakeLists.txt", "add_test(NAME planted COMMAND true)\n"),
              "tests:", "add_test")
        plant("exrinfo's exit status as a verdict",
              {"tests/cli/planted.sh": 'exrinfo --strict a.exr > /dev/null 2>&1 && ok || bad "invalid"\n'},
              "verdicts:", "tests/cli/planted.sh:1", "exrinfo")
        plant("exrinfo's exit status in Python", {"tests/planted.py": "subprocess.run(['exrinfo', '--strict', f])\n"},
              "verdicts:", "tests/planted.py:1")
        found = planted({"tests/cli/planted.sh": 'out=$(exrinfo --strict a.exr)\nexrinfo a.exr | grep -q File\n'})
        expect("exrinfo's output read is no breach", not found, "; ".join(found))
        found = planted(add(fbm, '/* getenv(), printf */ static const char *planted = "getenv(stderr)";\n'))
        expect("getenv and printf in a comment and a string pass", not found, "; ".join(found))
    finally:
        shutil.rmtree(tmp)
    print(f"{passed} passed, {failed} failed")
    return failed == 0


if __name__ == "__main__":
    if len(sys.argv) > 1:
        found = check(os.path.abspath(sys.argv[1]))
        for b in found:
            print(b)
        sys.exit(1 if found else 0)
    sys.exit(0 if self_test(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))) else 1)
