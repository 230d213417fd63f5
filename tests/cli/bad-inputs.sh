#!/usr/bin/env bash
# Every bad input in one table (bad-inputs.tsv): each row runs fractalbake in a folder of fixtures
# and
# must exit with the row's code, print exactly one line on stderr matching the row's pattern, and
# leave no file behind (the folder holds what it held before). Rows marked `vk` need a Vulkan device.
# Usage: bad-inputs.sh PATH/TO/fractalbake [TABLE]
. "$(dirname "$0")/lib.sh"
TABLE=$(realpath "${2:-$(dirname "$0")/bad-inputs.tsv}")
cli_init "$@"

# ---- fixtures: the files the rows name ----
S="--size 96x64 --quiet"
I="ifs --size 96x64 --quiet --points 200000"
L="lsystem --size 96x64 --quiet"
Tr="terrain --size 64x64 --quiet"
C="constrain --size 120x80 --quiet"
N="--backend native"
awk 'BEGIN { srand(4); print "# survey"; print "x,y,z"; for (i = 0; i < 300; i++) { x = rand() * 100; y = rand() * 100; printf "%.4f,%.4f,%.4f\n", x, y, 10 * sin(x / 9) + y / 10 } }' > pts.csv
printf '0 0 1\n1 0 2\n2 0 nan\n' > nanpts.xyz
printf '0 0 1\n1 0 2\n2 0\n' > short.xyz
printf '0 0 1\n1 1 2\n2 2 3\n3 3 4\n' > line.xyz
printf '# nothing here\n' > empty.xyz
printf 'x,y,z\n' > header-only.xyz
printf '1,1,3.4,1\n' > badcenters.csv
printf '1,1,2.5,1e300\n' > hugecenters.csv
printf '1 1 1\n1 1 1\n1 1 1\n' > same.xyz
printf '0 0 5\n1 0 5\n0 1 5\n' > flat.xyz
printf '1e300,0,0\n0,1e300,1\n1,1,1\n' > huge.xyz
printf '0,0,0\n1,0,1e300\n0,1,1\n' > hugez.xyz
printf '0,0,0\n2e15,0,1\n0,1,1\n' > far.xyz
printf '0 0 1\n1 0 2\0\n0 1 3\n' > nul.xyz
printf 'x,d\n0,0\n50,10\n100,0\n' > prof.csv
printf '1,2\n3\n' > bad.csv
printf '10.5,10\n' > frac.csv
printf 'nan,5\n' > nanpt.csv
printf '1,1,H,1.5\n' > badregion.csv
printf '1,1,Q,0.5\n' > kindregion.csv
F='<color index="0" rgb="255 0 0"/>'
printf '<flame size="64 64"><xform weight="1" linear="1" coefs="1 0 0 1 0 0"/>%s</flame>\n' "$F" > ok.flame
printf '<flame size="64 64"><xform weight="1" hemisphere="0.5" coefs="1 0 0 1 0 0"/>%s</flame>\n' "$F" > plugin.flame
printf '<flame size="64 64"><xform weight="1" linear="1" coefs="1 0 0"/>%s</flame>\n' "$F" > badcoef.flame
printf '<flame size="64 64"><xform weight="0" linear="1" coefs="1 0 0 1 0 0"/>%s</flame>\n' "$F" > zero.flame
printf '<flame size="64 64"><xform weight="1" linear="1" coefs="1 0 0 1 0 0"/></flame>\n' > nopal.flame
printf '<flame size="64 64"><xform weight="1"\n' > broken.flame
printf '{"size": [64, 32],\n "layers": [\n  {"type": "fbm", "octaves": 3,\n   "octavez": 2}\n ]\n}\n' > unknown.json
printf '{"size": [64, 32], "layers": [{"type": "fbm",\n "octaves": "3"}]}' > wrongtype.json
printf '{"size": [64, 32], "layers": [{"type": "fbm", "octaves": 3,]}' > malformed.json
printf '{"size": [64, 32], "layers": [{"type": "fbm", "hurst": NaN}]}' > nan.json
printf '{"size": [64, 32], "layers": [{"type": "fbm", "octaves": 0}]}' > range.json
printf '{"size": [64, 32], "layers": [{"type": "sky"}]}' > gen.json
printf '{"size": [64, 32], "layers": [{"type": "fbm"}, {"type": "fbm"}]}' > dup.json
printf '{"size": [64, 32]}' > nolayers.json
printf '' > zero.json
printf '{"size": [32, 16], "layers": [{"type": "fbm", "name": "h"}, {"type": "op", "name": "big", "op": "multiply", "inputs": [1e20, 1e20]}]}' > inf.json
printf '{"layers": [{"type": "terrain", "points": [[1e300, 0, 0], [0, 1, 1], [1, 1, 2]]}]}' > inline.json
printf '{"size": [64, 32], "layers": [{"type": "julia", "channels": []}]}' > chan.json
printf '{"size": [64, 32], "layers": [{"type": "ifs",\n "maps": []}]}' > empty.json
printf '{"size": [64, 32], "layers": [{"type": "ifs", "maps": [[0.5, 0, 0, 0.5, 0, 0],\n [0.5, 0, 0, 0.5, 1, NaN]]}]}' > nanmap.json
printf '{"size": [64, 32], "layers": [{"type": "lsystem", "axiom": "F",\n "rules": ["F=F[+F]", 3]}]}' > lrule.json
printf '{"size": [64, 32], "layers": [{"type": "rivers", "uplift-map": 0.5}]}' > rmapnum.json
printf '{"size": [64, 32], "layers": [{"type": "fbm", "name": "h"}, {"type": "op", "name": "o", "op": "multiply", "inputs": ["h", 2]}, {"type": "rivers", "uplift-map": "o"}]}' > rop.json
printf '{"size": [64, 32], "layers": [{"type": "fbm", "name": "h"}, {"type": "rivers", "uplift-map": "h", "uplift-range": [1, 1]}]}' > rrange.json
printf '{"size": [64, 32], "layers": [{"type": "rivers",\n "steps": 1000000000}]}' > rsteps.json
printf '{"size": [64, 32], "layers": [{"type": "rivers", "steps": 5}]}' > rok.json
printf 'leaf {\n  .5 0 0 .5 0 0 .5\n  .5 0 0 .5 1 0 zz\n}\n' > broken.ifs
printf 'halves { .5 0 0 .5 0 0 .5 .5 0 0 .5 1 0 .5 }\nthirds {\n .33 0 0 .33 0 0 .3 .33 0 0 .33 .66 0 .3 .33 0 0 .33 .33 .5 .4\n}\n' > two.ifs
printf '{"size": [32, 32], "layers": [{"type": "fbm", "name": "h"}, {"type": "erode"}]}' > enoin.json
printf '{"size": [32, 32], "layers": [{"type": "fbm", "name": "h"}, {"type": "erode", "input": 3}]}' > enum.json
printf '{"size": [32, 32], "layers": [{"type": "fbm", "name": "h"}, {"type": "erode", "input": "hill"}]}' > ename.json
printf '{"size": [32, 32], "layers": [{"type": "fbm", "name": "h"}, {"type": "erode", "input": "h", "iterations": 2, "masks": "m", "mask-bits": 12}]}' > emb.json
printf '{"size": [32, 32], "layers": [{"type": "fbm", "name": "h"}, {"type": "erode", "input": "h", "iterations": 2, "mask-bits": 8}]}' > emb2.json
printf '{"size": [32, 32], "layers": [{"type": "fbm", "name": "h"}, {"type": "erode", "input": "h", "iterations": 2, "masks": "nodir/m"}]}' > emnd.json
printf '{"size": [32, 32], "layers": [{"type": "fbm", "name": "h"}, {"type": "op", "name": "o", "op": "remap", "inputs": ["h"], "from": [0, 1]}, {"type": "erode", "input": "o"}]}' > eop.json
printf '{"size": [32, 32], "layers": [{"type": "fbm", "name": "h"}, {"type": "erode", "input": "h", "extent": 0}]}' > eext.json
printf '{"size": [32, 32], "layers": [{"type": "fbm", "name": "h"}, {"type": "erode", "input": "h.Z"}]}' > echan.json
printf '{"size": [32, 32], "layers": [{"type": "fbm", "name": "h"}, {"type": "erode", "input": "h", "talus": 90}]}' > etal.json
mkdir -p unreadable.json adir adir.ply adir.png adir.exr
mkfifo afifo afifo.exr
echo precious > victim.txt
ln -s victim.txt alink
ln -s victim.txt alink.png
ln -s victim.txt alink.exr
"$FB" fbm $N --size 16x16 -o small.exr --quiet
"$FB" fbm $N --size 16x16 --seed 2 -o small2.exr --quiet
"$FB" fbm $N --size 32x16 -o wide.exr --quiet
"$FB" render $N --set size=512x256 --points-part 1/2 -o pp1.exr --quiet
"$FB" render $N --set size=512x256 --points-part 2/2 -o pp2.exr --quiet
"$FB" fbm $N --size 8x8 -o tiny.exr --quiet
"$FB" fbm $N --size 16x16 -o small.exr --preview small.png --quiet
head -c 100 small.png > trunc.png
rm small.png
"$FB" fbm $N --size 16x16 -o nocommon.exr --preview nocommon.png --quiet && rm nocommon.exr # R G B: no channel in common with small.exr
printf 'not an exr at all\n' > text.exr
: > zero.exr
head -c 300 small.exr > trunc.exr
# a 2 KB file whose header claims 30000 x 30000 pixels
python3 - << 'PY'
import struct
d = bytearray(open('small.exr', 'rb').read())
for name in (b'dataWindow\0box2i\0', b'displayWindow\0box2i\0'):
    i = d.index(name) + len(name) + 4
    d[i:i + 16] = struct.pack('<4i', 0, 0, 29999, 29999)
open('huge.exr', 'wb').write(d)
PY
# data that a header rule must not swallow; constraint sets with nothing in them
printf '1e400 5 5\n0 0 1\n1 0 2\n0 1 3\n' > ovf.xyz
printf '1e999,5\n3,3\n' > ovf.csv
printf '0x1p99999,5\n3,3\n' > hexovf.csv
: > nopins.csv
printf 'x,y\n# nothing else\n' > hdrpins.csv
# tampered metadata: task and plan numbers past 32 bits, outside counts malformed or huge
SETATTR="python3 $HERE/exr-setattr.py"
printf '{"size": [256, 128], "layers": [{"type": "fbm"}]}' > two.json
for k in 0 1; do "$FB" render two.json $N --task $k/2 --task-startup 0 -o task$k.exr --quiet; done
$SETATTR task0.exr fractalbake/task 0/4294967298 tk-trunc.exr
for k in 0 1; do
  $SETATTR task$k.exr fractalbake/plan --sub '"tasks":2' '"tasks":4294967298' pl$k.tmp.exr
  $SETATTR pl$k.tmp.exr fractalbake/task $k/4294967298 plan$k.exr
  rm pl$k.tmp.exr
done
$SETATTR pp1.exr fractalbake/points-outside plants=18446744073709551615 ppmax.exr
$SETATTR pp1.exr fractalbake/points-outside plants=12x ppbad.exr
$SETATTR pp1.exr fractalbake/points-outside plants=-1 ppneg.exr
"$FB" render $N --set size=16x16 --set compression=piz -o piz.exr --quiet
# a named palette beside a gradient or cosine one, in a file or through --set
printf '{"size": [32, 16], "layers": [{"type": "julia", "name": "sky", "palette": "ice",\n "stops": [[0, 0, 0, 0], [1, 1, 1, 1]]}]}' > palstops.json
printf '{"size": [32, 16], "layers": [{"type": "ifs", "name": "fern", "palette": "ice",\n "cosine": [0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 1, 1, 1, 0, 0.33, 0.67]}]}' > palcos.json
printf '{"size": [32, 16], "layers": [{"type": "lsystem", "name": "tree", "palette": "ice"}]}' > palonly.json
printf '{"size": [32, 16], "layers": [{"type": "julia", "name": "sky", "stops": [[0, 0, 0, 0], [1, 1, 1, 1]]}]}' > stopsonly.json
# inputs an output must not replace, under names of the outputs' kinds
cp small.exr in.html && cp small2.exr inb.xml && cp ok.flame okflame.exr && cp pts.csv pts.obj && cp two.ifs two.csv
ln small.exr hard.exr && ln -s small.exr lsmall.exr
"$FB" fbm $N --size 16x16 -o hm.exr --quiet
"$FB" fbm $N --size 16x16 -o pab.exr --preview pa.png --quiet && "$FB" fbm $N --size 16x16 --seed 3 -o pab.exr --preview pb.png --quiet && rm pab.exr
"$FB" ifs $N --size 32x32 --points 10000 -o if.exr --quiet
printf '{"size": [65, 1], "layers": [{"type": "constrain", "profile": "prof.csv", "csv": "scene.csv"}]}' > scene.csv
before=$(ls -A | sort)
# every regular file's inode, size and time, to check that no row replaced or changed one (and its
# bytes, checked once after the table)
sums() { find . -maxdepth 1 -type f -printf '%i %s %T@ %p\n' | sort; }
sums_before=$(sums)
bytes_before=$(find . -maxdepth 1 -type f -exec md5sum {} + | sort -k2)
vk=0
have_vulkan && vk=1

# ---- the table ----
rows=0
skipped=0
while IFS=$'\t' read -r code needs pat args; do
  case "$code" in '' | '#'*) continue ;; esac
  rows=$((rows + 1))
  if [ "$needs" = vk ] && [ $vk -eq 0 ]; then skipped=$((skipped + 1)); continue; fi
  eval "set -- $args"
  timeout 60 "$FB" "$@" > stdout.txt 2> stderr.txt < /dev/null # a row that hangs fails (124)
  rc=$?
  lines=$(wc -l < stderr.txt)
  err=$(cat stderr.txt)
  rm -f stdout.txt stderr.txt
  after=$(ls -A | sort)
  if [ $rc -ne "$code" ]; then
    bad "[$args] exit $rc, wanted $code: $err"
  elif [ "$lines" -ne 1 ]; then
    bad "[$args] $lines stderr lines, wanted 1: $err"
  elif ! grep -q -- "$pat" <<< "$err"; then
    bad "[$args] stderr lacks '$pat': $err"
  elif [ "$after" != "$before" ]; then
    bad "[$args] left files: $(comm -13 <(echo "$before") <(echo "$after") | tr '\n' ' ')"
  elif [ "$(sums)" != "$sums_before" ]; then
    bad "[$args] changed a file: $(comm -13 <(echo "$sums_before") <(sums) | tr '\n' ' ')"
    sums_before=$(sums) # the next rows are judged on their own
  else
    ok
  fi
  [ "$after" = "$before" ] || comm -13 <(echo "$before") <(echo "$after") | xargs -r rm -rf # the next row starts clean
done < "$TABLE"
check "every fixture byte-identical after the table" test "$(find . -maxdepth 1 -type f -exec md5sum {} + | sort -k2)" = "$bytes_before"
check "the fixtures were not written through" test "$(cat victim.txt)" = precious -a -c /dev/null -a -p afifo
echo "$rows rows ($skipped need Vulkan and were not run)"
[ "$rows" -ge 120 ] && ok || bad "the table has $rows rows, fewer than 120"
cli_finish
