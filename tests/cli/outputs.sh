#!/usr/bin/env bash
# A run writes the files its command line names and nothing else, all together or none: stored
# scenes choose no outputs, temporary files are exclusive and unpredictable, only regular files are
# replaced, a late failure or a signal leaves nothing. Usage: outputs.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
N="--backend native --quiet"
printf 'x,y,z\n0,0,0\n10,0,1\n0,10,2\n10,10,3\n5,5,1\n' > pts.csv

# ---- 1. a stored scene chooses no output path ----
"$FB" terrain $N --points pts.csv --size 32x32 --mesh victim.ply -o a.exr
check "the terrain mesh is written when asked" test -s victim.ply
rm -f victim.ply
"$FB" render --backend native --from a.exr -o b.exr 2> from.txt
check "--from bakes" test -s b.exr
check "--from wrote the stored scene's mesh" test ! -e victim.ply
check "--from says which outputs it dropped" grep -q "not writing the stored scene's outputs (layers.terrain.mesh=victim.ply)" from.txt
check "--from: one warning line" test "$(grep -c warning from.txt)" -eq 1
"$FB" render $N --from a.exr -o c.exr --set layers.terrain.mesh=again.ply
check "--set names a dropped output back" test -s again.ply
"$FB" constrain $N --size 257x1 --csv v.csv --plot v.png -o k.exr
check "constrain writes its csv and plot" test -s v.csv -a -s v.png
rm -f v.csv v.png
"$FB" render $N --from k.exr -o k2.exr
check "--from wrote the stored csv or plot" test ! -e v.csv -a ! -e v.png -a -s k2.exr

# ---- 2. temporary files: exclusive, unpredictable names, mode 0666 less the umask ----
echo precious > victim.txt
last=$(cat /proc/sys/kernel/ns_last_pid 2> /dev/null || echo $$)
for p in $(seq $((last + 1)) $((last + 400))); do ln -s victim.txt ".o.exr.$p.tmp"; done
"$FB" fbm $N --size 64x64 -o o.exr
check "a planted symlink at a predictable temporary name was written through" test "$(cat victim.txt)" = precious
check "the output is a regular file" test -f o.exr -a ! -L o.exr
find . -maxdepth 1 -name '.o.exr.*.tmp' -type l -delete
for m in 027 000 077; do
  (umask $m && "$FB" fbm $N --size 16x16 -o m$m.exr --preview m$m.png)
  want=$(printf '%o' $((0666 & ~8#$m)))
  check "umask $m: mode $(stat -c %a m$m.exr), wanted $want" test "$(stat -c %a m$m.exr)" = "$want" -a "$(stat -c %a m$m.png)" = "$want"
done

# ---- 3. only regular files are replaced ----
mkdir adir adir.ply && mkfifo afifo && ln -s victim.txt alink
expect_fail 2 "adir: exists and is a directory" "" -- fbm $N --size 16x16 -o adir
expect_fail 2 "afifo: exists and is a FIFO" "" -- fbm $N --size 16x16 -o afifo
expect_fail 2 "alink: exists and is a symbolic link" "" -- fbm $N --size 16x16 -o alink
expect_fail 2 "alink: exists and is a symbolic link" p.exr -- fbm $N --size 16x16 -o p.exr --preview alink
expect_fail 2 "adir.ply: exists and is a directory" p.exr -- terrain $N --points pts.csv --size 16x16 --mesh adir.ply -o p.exr
expect_fail 2 "/dev/null: exists and is a character device" "" -- fbm $N --size 16x16 -o /dev/null
check "the link's target is untouched" test "$(cat victim.txt)" = precious -a -L alink -a -p afifo
check "/dev/null is still a device" test -c /dev/null

# ---- 4. all outputs of a run commit together ----
expect_fail 2 "x: named as the output and as the preview" x -- fbm $N --size 16x16 -o x --preview x
expect_fail 2 "named as the output and as the preview" x -- fbm $N --size 16x16 -o x --preview ./x
expect_fail 2 "x.exr: this writes PNG" x.exr -- fbm $N --size 16x16 -o x.exr --preview x.exr
mkdir -p sub
expect_fail 2 "m.ply: named as the preview and as the mesh" x.exr -- terrain $N --points pts.csv --size 16x16 --mesh m.ply --preview sub/../m.ply -o x.exr
"$FB" fbm $N --size 16x16 -o c1.exr && "$FB" fbm $N --size 16x16 --seed 2 -o c2.exr
"$FB" compare c1.exr c2.exr --diff d.exr --diff-png d.exr > /dev/null 2> cmp.txt
check "compare: --diff and --diff-png on one path is usage (exit 2)" test $? -eq 2 -a ! -e d.exr
# A target that turns into a directory while the bake runs: the EXR is not renamed either.
echo old > late.exr
"$FB" julia $N --size 3000x3000 -o late.exr --preview late.png 2> late.txt &
pid=$!
for _ in $(seq 200); do ls -A | grep -q '^\.late\.png\..*\.tmp$' && break; sleep 0.02; done
mkdir late.png
wait $pid
rc=$?
check "a preview path turned directory: exit $rc, wanted 2" test $rc -eq 2
check "... the EXR was left as it was" test "$(cat late.exr)" = old
check "... no temporary file left" no_temp_files
check "... one line naming the preview" grep -q "late.png: exists and is a directory" late.txt
rmdir late.png
# A side output that cannot be written (the file size limit): nothing is renamed, the old EXR stays.
echo old > big.exr
(trap '' XFSZ; ulimit -f 512; "$FB" terrain $N --points pts.csv --insert 200000 --size 32x32 --mesh big.ply -o big.exr 2> big.txt)
rc=$?
check "a mesh that cannot be written: exit $rc, wanted 3" test $rc -eq 3
check "... the EXR was left as it was" test "$(cat big.exr)" = old -a ! -e big.ply
check "... no temporary file left" no_temp_files
check "... one line naming the mesh" grep -q "big.ply: cannot write the mesh" big.txt

# ---- 5. a signal leaves nothing ----
echo old > sig.exr
for sig in INT TERM HUP; do
  for at in 0.05 0.6 1.5; do
    "$FB" julia $N --size 4096x4096 -o sig.exr --preview sig.png &
    pid=$!
    sleep $at
    kill -$sig $pid
    wait $pid
    rc=$?
    want=$((128 + $(kill -l $sig)))
    check "SIG$sig at $at s: exit $rc, wanted $want" test $rc -eq $want
    check "SIG$sig at $at s: the old output is untouched" test "$(cat sig.exr)" = old -a ! -e sig.png
    check "SIG$sig at $at s: no temporary file left" no_temp_files
  done
done

# ---- 10. a documented maximum runs, tells how far it is, and stops at once on Ctrl-C ----
"$FB" ifs --help | grep -q "1e14 takes days: progress is shown and Ctrl-C stops it" && ok || bad "ifs --help says nothing of 1e14"
"$FB" ifs --backend native --points 1e14 --size 128x128 -o long.exr 2> long.txt &
pid=$!
sleep 10.5
kill -INT $pid
t0=$(date +%s%N)
wait $pid
rc=$?
ms=$((($(date +%s%N) - t0) / 1000000))
check "ifs --points 1e14, Ctrl-C: exit $rc, wanted 130" test $rc -eq 130
check "... stopped in $ms ms, wanted under 1000" test $ms -lt 1000
check "... a progress line for the log after 10 s" grep -q "chaos game: .*% (.* of 1e+14 pts, .* left)" long.txt
check "... nothing left" test ! -e long.exr && no_temp_files

cli_finish
