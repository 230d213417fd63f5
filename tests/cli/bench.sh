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
# the rates are rounded to 3 decimals (half a unit of the last off)
assert g and all(abs(r['per_peak_gflops'] - r['rate'] / c[('native', 'fma')]) < 1e-3 * r['per_peak_gflops'] + 5e-4 / c[('native', 'fma')] for r in g), g
"
check "encode-only: a row after each end-to-end one, in its unit, bake_vs_encode their time ratio" python3 -c "
import json
rows = [json.loads(l) for l in open('a.json') if json.loads(l)['generator'] == 'fbm']
for comp in ('none', 'zip', 'piz'):
    e2e = [r for r in rows if r['mode'] == 'end-to-end-' + comp]
    enc = [r for r in rows if r['mode'] == 'encode-only-' + comp]
    assert len(e2e) == 1 and len(enc) == 1, (comp, rows)
    e, n = e2e[0], enc[0]
    assert n['unit'] == e['unit'] == 'Mpix/s' and n['rate'] > 0 and n['size'] == [64, 64], n
    # the ratio of the times is the inverse ratio of the rates (both rounded to 3 decimals)
    want = n['rate'] / e['rate']
    assert abs(n['bake_vs_encode'] - want) <= 0.002 + 0.01 * want, (n, e)
    assert rows.index(n) == rows.index(e) + 1, 'encode-only follows its bake'
"
if have_vulkan; then
    # each layer's shader beside its minimal shader (bench/peers/): a kernel row, then its peer row,
    # the same bits, vs_peer their ratio by the timestamps (or the host clock without them)
    for gen in stars ifs erode; do
        "$FB" bench --json --quiet --size 64x64 --points 1e6 --generator $gen --backend vulkan > p-$gen.json 2>> err.txt
        check "$gen: kernel and peer rows, the same bits, vs_peer their ratio" python3 -c "
import json
rows = [json.loads(l) for l in open('p-$gen.json') if json.loads(l)['generator'] == '$gen']
ks = [i for i, r in enumerate(rows) if r['mode'].startswith('kernel')]
assert ks, rows
for i in ks:
    k, p = rows[i], rows[i + 1]
    assert p['mode'] == 'peer' + k['mode'][6:] and 'bench/peers/' in p['device'], (k, p)
    assert k['same_bits'] == 1 and k['differing'] == 0, k
    a, b = (k['gpu_rate'], p['gpu_rate']) if k.get('gpu_rate', 0) > 0 and p.get('gpu_rate', 0) > 0 else (k['rate'], p['rate'])
    # the rates are rounded to 3 decimals, vs_peer too
    assert (a - 5e-4) / (b + 5e-4) - 1e-3 <= k['vs_peer'] <= (a + 5e-4) / max(b - 5e-4, 1e-9) + 1e-3, (k, p)
"
    done
fi
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
# the game with density estimation and the filter (timed in the same prepares: never slower) and than
# the whole render (which adds the tone map and the file)
"$FB" bench --json --quiet --generator flame --backend native --points 3145728 > f.json 2> err.txt
check "flame: a chaos-game, a game-de-filter and an end-to-end row, the points asked for" python3 -c "
import json
rows = {r['mode']: r for r in map(json.loads, open('f.json')) if r['generator'] == 'flame'}
g, d, w = rows['chaos-game'], rows['game-de-filter'], rows['end-to-end-zip']
assert g['unit'] == d['unit'] == w['unit'] == 'Mpts/s' and g['backend'] == d['backend'] == 'native', rows
assert all(abs(r['points'] - 3145728) <= 8 for r in (g, d, w)), rows
assert g['rate'] > d['rate'] > 0 and g['rate'] > w['rate'] > 0, rows"
echo 'not json' > bad.json
expect_fail 2 "bad.json:1: not a line of" "" -- bench --compare bad.json --generator fbm --backend native
expect_fail 2 "cannot open" "" -- bench --compare missing.json --generator fbm --backend native
cli_finish
