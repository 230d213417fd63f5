#!/usr/bin/env bash
# compare --report and --junit: the HTML page in headless Chromium (Debian's `chromium`): it
# renders, every picture loads (the page counts them once loaded: 4 per layer), no console message
# (a page that logs one is caught, as a control), and the screenshot of a failing comparison shows
# the failing layer's red banner above the passing one's green; the page is self-contained (no
# http, no file reference); it lists the scene key that differs. The JUnit file: one test case per
# channel and threshold, a <failure> exactly where compare failed, read by Python's XML parser.
# Usage: report.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
command -v chromium > /dev/null || { echo "chromium is not installed (scripts/setup.sh --test)" >&2; exit 77; }
N="--backend native --quiet"
cat > sc.json << 'JSON'
{"size": [200, 100], "seed": 11, "layers": [
  {"type": "julia", "name": "sky", "mapping": "polar", "alpha": [-0.3, 0], "palette": "nebula"},
  {"type": "fbm", "name": "detail", "octaves": 6, "frequency": 8}]}
JSON
sed 's/"octaves": 6/"octaves": 5/' sc.json > changed.json
"$FB" render sc.json $N -o a.exr
"$FB" render changed.json $N -o b.exr
code() { "$FB" compare "$@" > out.txt 2> err.txt; echo $?; }
check "the failing comparison exits 1" \
  test "$(code a.exr b.exr --fail sky=0.01,detail=1e-5 --flip-fail sky=0.02 --report r.html --junit j.xml)" = 1
check "the page names the differing scene key" grep -q "layers.detail.octaves: 6 in A, 5 in B" r.html
check "the page is self-contained" sh -c "! grep -Eq 'https?:|src=\"[^d]|href=' r.html"
C="chromium --headless --no-sandbox --disable-gpu --hide-scrollbars --window-size=1000,1200"
$C --virtual-time-budget=5000 --enable-logging=stderr --v=0 --dump-dom "file://$T/r.html" > dom.html 2> chrome.err
check "Chromium renders the page" grep -q '<section id="layer-0"' dom.html
check "every picture loads (8 of 8)" grep -q '<body data-images="8/8">' dom.html
check "no console message" sh -c "! grep -q ':CONSOLE' chrome.err"
$C --virtual-time-budget=5000 --dump-dom "file://$T/r.html#full=5" > full.html 2> /dev/null
check "a picture opens at full size (#full=5: the sixth, shown over the page)" python3 -c "
import re
d = open('full.html').read()
thumbs = re.findall(r'<img class=\"thumb\"[^>]*src=\"([^\"]+)\"', d)
m = re.search(r'<div id=\"full\" style=\"display: block;\"><img alt=\"full size\" src=\"([^\"]+)\"', d)
assert len(thumbs) == 8 and m and m.group(1) == thumbs[5]"
printf '<html><body><script>console.error("boom")</script></body></html>' > noisy.html
$C --virtual-time-budget=2000 --enable-logging=stderr --v=0 --dump-dom "file://$T/noisy.html" > /dev/null 2> noisy.err
check "  (a page that logs is caught)" grep -q ':CONSOLE.*boom' noisy.err
$C --screenshot="$T/shot.png" "file://$T/r.html" 2> /dev/null
check "a screenshot is taken" test -s shot.png
# the screenshot: down the left edge inside the sections, the first banner is red (the failing
# layer), and a green one follows (PNG decoded here with zlib: an independent reader)
check "the failing layer comes first in the screenshot" python3 - << 'PY'
import struct, zlib
d = open("shot.png", "rb").read()
assert d[:8] == b"\x89PNG\r\n\x1a\n"
pos, idat, w = 8, b"", 0
while pos < len(d):
    n, t = struct.unpack(">I4s", d[pos:pos + 8])
    body = d[pos + 8:pos + 8 + n]
    if t == b"IHDR":
        w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
        assert depth == 8 and ctype in (2, 6)
        bpp = 3 if ctype == 2 else 4
    elif t == b"IDAT":
        idat += body
    pos += 12 + n
raw, stride, rows, prev = zlib.decompress(idat), w * bpp, [], bytearray(w * bpp)
for y in range(h):
    f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
    for i in range(stride):
        a = line[i - bpp] if i >= bpp else 0
        b, c = prev[i], prev[i - bpp] if i >= bpp else 0
        if f == 1: line[i] = (line[i] + a) & 255
        elif f == 2: line[i] = (line[i] + b) & 255
        elif f == 3: line[i] = (line[i] + (a + b) // 2) & 255
        elif f == 4:
            p = a + b - c; pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
    rows.append(line)
    prev = line
seen = []
for y in range(h):
    r, g, b = rows[y][25 * bpp:25 * bpp + 3]
    kind = "red" if (r, g, b) == (0xc6, 0x28, 0x28) else "green" if (r, g, b) == (0x2e, 0x7d, 0x32) else None
    if kind and (not seen or seen[-1] != kind):
        seen.append(kind)
assert seen[:2] == ["red", "green"], seen
PY
check "the JUnit file: one case per channel and threshold, failures where compare failed" python3 - << 'PY'
import xml.etree.ElementTree as ET
s = ET.parse("j.xml").getroot().find("testsuite")
cases = {(c.get("classname"), c.get("name")): c.find("failure") is not None for c in s.findall("testcase")}
assert int(s.get("tests")) == len(cases) == 9, cases      # 8 channels' --fail and sky's FLIP
assert cases[("detail.Y", "at most 0% of pixels beyond 1e-05")] is True
assert cases[("sky", "FLIP mean at most 0.02")] is False
assert sum(cases.values()) == int(s.get("failures")) == 1, cases
PY
check "an unwritable report is refused before the work" test "$(code a.exr b.exr --report nodir/r.html)" = 2
check "  naming it" grep -q "nodir/r.html: cannot create the HTML report" err.txt
check "--report must be .html" test "$(code a.exr b.exr --report r.png)" = 2
cli_finish
