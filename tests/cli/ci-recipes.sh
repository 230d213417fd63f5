#!/usr/bin/env bash
# docs/ci.md's recipes as shipped: the golden command of step 1, the check of step 2 and the
# commands of every CI example (the GitHub Actions `run:` scripts and the GitLab `script:` lines,
# less the package installation) run as written on lavapipe, each passing; then the thresholds of
# step 2 hold across backends (the check rendered natively against the lavapipe golden), and a
# changed scene fails them.
# Usage: ci-recipes.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
require_vulkan
ln -s "$ROOT/docs" docs
mkdir -p build .bin
ln -s "$FB" build/fractalbake
ln -s "$FB" .bin/fractalbake
export PATH="$T/.bin:$PATH"
# the commands: step 1, step 2 (indented blocks of the recipe), then each yaml block's, one file each
python3 - "$ROOT/docs/ci.md" << 'PY'
import re, sys
text = open(sys.argv[1]).read()
recipe = text[text.index("## A recipe for your own scenes"):]
blocks, cur = [], None
for line in recipe.split("\n"):
    if line.startswith("```"):
        break
    m = re.match(r"^ {7}( *\S.*)$", line)
    if m:
        if cur is None:
            cur = []
            blocks.append(cur)
        if cur and cur[-1].endswith("\\"):
            cur[-1] = cur[-1][:-1].rstrip() + " " + m.group(1).strip()
        else:
            cur.append(m.group(1).strip())
    elif line.strip():
        cur = None
open("step1.sh", "w").write("\n".join(blocks[0]) + "\n")
open("step2.sh", "w").write("\n".join(blocks[1]) + "\n")
skip = re.compile(r"apt-get|setup\.sh")
for n, y in enumerate(re.findall(r"```yaml\n(.*?)```", text, re.S)):
    cmds, body = [], None
    lines = y.split("\n")
    for line in lines:
        if body is not None:
            if line.startswith(" " * (body + 2)) and line.strip():
                t = line.strip()
                if cmds and cmds[-1].endswith("\\"):
                    cmds[-1] = cmds[-1][:-1].rstrip() + " " + t
                else:
                    cmds.append(t)
                continue
            body = None
        m = re.match(r"^(\s*)- run: \|\s*$", line)
        if m:
            body = len(m.group(1))
            continue
        m = re.match(r"^\s*- run: (.*)$", line) or re.match(r"^    - (.*)$", line)
        if m and not line.strip().startswith("- uses") and not line.strip().startswith("- if"):
            cmds.append(m.group(1).split("  #")[0].strip())
    cmds = [c for c in cmds if not skip.search(c)]
    open("ci%d.sh" % n, "w").write("set -e\n" + "\n".join(cmds) + "\n")
PY
check "step 1 (the golden) runs as written" bash -e step1.sh
check "  and makes golden/ci-scene.exr" test -s golden/ci-scene.exr
check "step 2 (the check) runs as written" bash -e -o pipefail step2.sh
check "  and passes" python3 -c "import json; assert json.load(open('out/report.json'))['result'] == 'pass'"
n=0
for f in ci*.sh; do
  d=run-$f
  mkdir "$d" && ln -s "$T/docs" "$d/docs" && ln -s "$T/build" "$d/build" && cp -r golden "$d/"
  check "$f (a CI example) has commands" grep -q "fractalbake compare" "$f"
  check "$f runs as written and passes" sh -c "cd '$d' && bash '$T/$f' > log.txt 2>&1"
  check "  with its diff picture" test -s "$d/out/diff.png"
  check "  its HTML page" grep -q "<section id=\"layer-0\"" "$d/out/report.html"
  check "  and its JUnit file" python3 -c "import xml.etree.ElementTree as E; assert E.parse('$d/out/junit.xml').getroot().find('testsuite').get('failures') == '0'"
  n=$((n + 1))
done
check "two CI examples found" test "$n" = 2
# the same thresholds across backends: lavapipe's golden against a native render
fractalbake render docs/examples/ci-scene.json -o native.exr --backend native --quiet
args=$(sed -n 's/^fractalbake compare golden\/ci-scene.exr out\/ci-scene.exr \(.*\) --diff .*/\1/p' step2.sh)
check "step 2's thresholds read" test -n "$args"
check "they hold across backends (lavapipe golden, native check)" \
  sh -c "fractalbake compare golden/ci-scene.exr native.exr $args --quiet"
sed 's/"octaves": 6/"octaves": 5/' docs/examples/ci-scene.json > changed.json
fractalbake render changed.json -o changed.exr --backend vulkan --quiet
check "a changed scene fails them" test "$(fractalbake compare golden/ci-scene.exr changed.exr $args --quiet > /dev/null; echo $?)" = 1
cli_finish
