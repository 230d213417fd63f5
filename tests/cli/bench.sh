#!/usr/bin/env bash
# fractalbake bench: the machine's ceilings first (FMA GFLOP/s and copy GB/s on each backend, the CPU
# and driver named), every line with lavapipe's settings and its rate per peak GFLOP/s, and
# --compare against an earlier run's JSON; the flame's rows.
source "$(dirname "$0")/lib.sh"
cli_init "$@"

"$FB" bench --json --quiet --size 64x64 --generator fbm --backend native > a.json 2> err.txt
check "bench --json runs" test -s a.json
check "native ceilings: an FMA and a copy row with positive rates" python3 -c "
import json, sys
rows = [json.loads(l) for l in open('a.json')]
c = {(r['backend'], r['mode']): r['rate'] for r in rows if r['generator'] == 'ceiling'}
assert c.get(('native', 'fma'), 0) > 0 and c.get(('native', 'copy'), 0) > 0, c
assert all('LP_NUM_THREADS' in r and 'LP_NATIVE_VECTOR_WIDTH' in r for r in rows), 'lavapipe settings'
g = [r for r in rows if r['generator'] == 'fbm']
assert g and all(abs(r['per_peak_gflops'] - r['rate'] / c[('native', 'fma')]) < 1e-3 * r['per_peak_gflops'] for r in g), g
"
LP_NUM_THREADS=1 "$FB" bench --json --quiet --size 64x64 --generator fbm --backend native --compare a.json > b.json
check "LP_NUM_THREADS is recorded as given" python3 -c "
import json
assert all(json.loads(l)['LP_NUM_THREADS'] == '1' for l in open('b.json'))"
check "--compare: every row has its ratio to the earlier run, as is and per peak" python3 -c "
import json
rows = [json.loads(l) for l in open('b.json')]
assert all(r['vs_before'] > 0 and r['vs_before_per_peak'] > 0 for r in rows), rows"
"$FB" bench --quiet --size 64x64 --generator fbm --backend native --compare a.json > c.txt
check "text: the machine line and the ratios" grep -q '^machine: .*LP_NUM_THREADS' c.txt
check "text: a ratio per row" grep -q 'of before' c.txt
# the flame rows: gold at 1024 x 1024, the points asked for (3 a pixel), the game alone faster than
# the whole render (which adds density estimation, the filter and the file)
"$FB" bench --json --quiet --generator flame --backend native --points 3145728 > f.json 2> err.txt
check "flame: a chaos-game and an end-to-end row, the points asked for" python3 -c "
import json
rows = {r['mode']: r for r in map(json.loads, open('f.json')) if r['generator'] == 'flame'}
g, w = rows['chaos-game'], rows['end-to-end-zip']
assert g['unit'] == w['unit'] == 'Mpts/s' and g['backend'] == 'native', rows
assert all(abs(r['points'] - 3145728) <= 8 for r in (g, w)), rows
assert g['rate'] > w['rate'] > 0, rows"
echo 'not json' > bad.json
expect_fail 2 "bad.json:1: not a line of" "" -- bench --compare bad.json --generator fbm --backend native
expect_fail 2 "cannot open" "" -- bench --compare missing.json --generator fbm --backend native
cli_finish
