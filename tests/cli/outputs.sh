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
mkdir adir.exr adir.ply && mkfifo afifo.exr && ln -s victim.txt alink.exr && ln -s victim.txt alink.png
expect_fail 2 "adir.exr: exists and is a directory" "" -- fbm $N --size 16x16 -o adir.exr
expect_fail 2 "afifo.exr: exists and is a FIFO" "" -- fbm $N --size 16x16 -o afifo.exr
expect_fail 2 "alink.exr: exists and is a symbolic link" "" -- fbm $N --size 16x16 -o alink.exr
expect_fail 2 "alink.png: exists and is a symbolic link" p.exr -- fbm $N --size 16x16 -o p.exr --preview alink.png
expect_fail 2 "adir.ply: exists and is a directory" p.exr -- terrain $N --points pts.csv --size 16x16 --mesh adir.ply -o p.exr
expect_fail 2 "/dev/null: exists and is a character device" "" -- constrain $N --size 65x1 --csv /dev/null -o p.exr
expect_fail 2 "-o /dev/null: this writes OpenEXR: name the file .exr" "" -- fbm $N --size 16x16 -o /dev/null
check "the link's target is untouched" test "$(cat victim.txt)" = precious -a -L alink.exr -a -p afifo.exr
check "/dev/null is still a device" test -c /dev/null

# ---- 4. all outputs of a run commit together ----
expect_fail 2 "x.png: named as the preview and as the heightmap" x.png -- fbm $N --size 16x16 -o x.exr --preview x.png --heightmap x.png
expect_fail 2 "named as the preview and as the heightmap" x.png -- fbm $N --size 16x16 -o x.exr --preview x.png --heightmap ./x.png
expect_fail 2 "x.exr: this writes PNG" x.exr -- fbm $N --size 16x16 -o x.exr --preview x.exr
mkdir -p sub
expect_fail 2 "m.png: named as the preview and as the heightmap" x.exr -- terrain $N --points pts.csv --size 16x16 --heightmap m.png --preview sub/../m.png -o x.exr
"$FB" fbm $N --size 16x16 -o c1.exr && "$FB" fbm $N --size 16x16 --seed 2 -o c2.exr
"$FB" compare c1.exr c2.exr --diff-png d.png --flip-png d.png > /dev/null 2> cmp.txt
check "compare: --diff-png and --flip-png on one path is usage (exit 2)" test $? -eq 2 -a ! -e d.png
# A target that turns into a directory while the bake runs: the EXR is not renamed either.
echo old > late.exr
"$FB" julia $N --size 3000x3000 -o late.exr --preview late.png 2> late.txt &
pid=$!
# its outputs are reserved: an anonymous file (O_TMPFILE) held open, or the hidden temporary one
for _ in $(seq 200); do
  { ls -l /proc/$pid/fd 2> /dev/null | grep -q '/#[0-9]* (deleted)' || ls -A | grep -q '^\.fractalbake-tmp\..*\.late\.png\.tmp$'; } && break
  sleep 0.02
done
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

# ---- 6. every signal that ends a run ends it like SIGINT: SIGPIPE, SIGXFSZ ----
rm -f pp.png
"$FB" fbm --backend native --size 512x512 -o - --preview pp.png 2> pipe.txt | true
rc=${PIPESTATUS[0]}
check "SIGPIPE (-o - | true): exit $rc, wanted 141" test $rc -eq 141
check "... no preview, no temporary file" test ! -e pp.png && no_temp_files
check "... no \"wrote\" line" test ! -s pipe.txt
echo old > fsz.exr
(ulimit -f 100 && "$FB" fbm $N --size 1024x1024 -o fsz.exr --preview fsz.png)
rc=$?
check "SIGXFSZ (ulimit -f 100): exit $rc, wanted 153" test $rc -eq 153
check "... the old output untouched, no preview" test "$(cat fsz.exr)" = old -a ! -e fsz.png
check "... no temporary file" no_temp_files
"$FB" scene default 2> /dev/null | head -c 10 > /dev/null
rc=${PIPESTATUS[0]}
check "scene default | head -c 10: exit $rc, wanted 141 (or 0 when it fit the pipe)" test $rc -eq 141 -o $rc -eq 0

# ---- 7. names and folders checked before the work; nothing renamed when one cannot be ----
echo old > nm.exr
long=$(printf 'h%.0s' $(seq 300)).r16
expect_fail 2 "file name has 304 bytes, more than the 255" "" -- terrain $N --points pts.csv --size 32x32 -o nm.exr --heightmap "$long"
check "a 304-byte heightmap name: the EXR was left as it was" test "$(cat nm.exr)" = old
expect_fail 2 "cannot create the preview: folder nofolder" "" -- fbm $N --size 16x16 -o nm.exr --preview nofolder/p.png
check "a missing folder: the EXR was left as it was" test "$(cat nm.exr)" = old

# ---- 8. "wrote" only after the commit; every write to standard output checked (exit 3) ----
"$FB" fbm --backend native --size 64x64 -o - > /dev/full 2> full.txt
rc=$?
check "-o - > /dev/full: exit $rc, wanted 3" test $rc -eq 3
check "... one line, no \"wrote\": $(cat full.txt)" test "$(wc -l < full.txt)" -eq 1 -a "$(grep -c wrote full.txt)" -eq 0
"$FB" fbm $N --size 16x16 -o c1.exr
for cmd in "scene default" "plan --tasks 2" "info c1.exr" "compare c1.exr c1.exr" "devices" "--help" "fbm --help" \
  "fbm --size 16x16 --dry-run" "fbm --backend native --size 16x16 -o j.exr --json" "--version"; do
  # shellcheck disable=SC2086
  "$FB" $cmd > /dev/full 2> full.txt
  rc=$?
  check "$cmd > /dev/full: exit $rc, wanted 3" test $rc -eq 3
  check "$cmd > /dev/full: one line naming standard output: $(cat full.txt)" grep -q "standard output: cannot write" full.txt
  # shellcheck disable=SC2086
  "$FB" $cmd >&- 2> full.txt
  rc=$?
  check "$cmd with standard output closed: exit $rc, wanted 3" test $rc -eq 3
  check "$cmd with standard output closed: one line: $(cat full.txt)" grep -q "standard output: cannot write" full.txt
done
rm -f j.exr
"$FB" fbm --backend native --size 16x16 -o k.exr >&- 2> full.txt
check "a bake that writes nothing on standard output is not hurt by closing it" test $? -eq 0 -a -s k.exr

# the summaries name what was written and what ran where
"$FB" terrain --backend native --points pts.csv --size 16x16 --mesh sm.ply -o sm.exr 2> sum.txt
check "terrain's summary names its layer, generator and mesh: $(cat sum.txt)" grep -q "layer terrain (terrain): .*; mesh sm.ply" sum.txt
check "... and the EXR, after the commit" grep -q "^fractalbake: wrote sm.exr" sum.txt
"$FB" constrain --backend native --size 257x1 --csv cs.csv -o cs.exr 2> sum.txt
check "constrain's summary says constrain and names its csv: $(cat sum.txt)" grep -q "(constrain): .*; csv cs.csv" sum.txt
"$FB" ifs --backend native --size 64x64 --points 100000 -o if.exr --quiet && "$FB" tonemap if.exr -o if2.exr --brightness 2 2> sum.txt
check "tonemap's summary names its file: $(cat sum.txt)" grep -q "^fractalbake: wrote if2.exr (tone-mapped)" sum.txt
"$FB" render --set size=64x32 -o jd.exr --json > jd.json
check "--json: the device named is the one each layer ran on" python3 -c "
import json; d = json.load(open('jd.json'))
ok = all((l['backend'] == 'native') == (l['device'] == 'native C') for l in d['layers'])
vk = [l['device'] for l in d['layers'] if l['backend'] == 'vulkan']
ok = ok and d['device'] == (vk[0] if vk else 'native C')
raise SystemExit(0 if ok else 1)"
check "--tasks 1e1 is 10 tasks (integer flags take exponent notation)" sh -c '"$0" plan --tasks 1e1 --set size=64x32 | grep -q "over 10 tasks"' "$FB"

# ---- 9. SIGKILL: nothing visible, and (O_TMPFILE) nothing at all; concurrent runs: whole sets ----
mkdir -p kill && echo old > kill/k.exr
(cd kill && exec "$FB" terrain $N --points ../pts.csv --insert 400000 --size 1024x1024 -o k.exr --preview k.png --mesh k.ply --heightmap k.r16) &
pid=$!
sleep 0.5
kill -KILL $pid
wait $pid
rc=$?
check "SIGKILL: exit $rc, wanted 137" test $rc -eq 137
check "SIGKILL: the folder holds the old output and nothing else: $(ls -A kill | tr '\n' ' ')" test "$(ls -A kill)" = k.exr -a "$(cat kill/k.exr)" = old
# 12 runs at once, each writing the same EXR and preview with its own seed, 8 rounds: the pair in
# place is always one run's (the EXR's stored seed names the run; its preview must be that run's)
mkdir -p race
for k in $(seq 12); do "$FB" fbm $N --size 96x96 --seed $k -o race/ref$k.exr --preview race/ref$k.png; done
mixed=0
for round in $(seq 8); do
  for k in $(seq 12); do "$FB" fbm $N --size 96x96 --seed $k -o race/o.exr --preview race/o.png & done
  wait
  seed=$("$FB" info race/o.exr | sed -n 's/.*fractalbake\/seed[^0-9]*\([0-9]*\).*/\1/p' | head -1)
  if [ -z "$seed" ] || ! cmp -s race/o.png "race/ref$seed.png" || ! cmp -s race/o.exr "race/ref$seed.exr"; then mixed=$((mixed + 1)); fi
done
check "concurrent runs writing one set of paths: $mixed of 8 rounds left files of two runs" test $mixed -eq 0
check "... no temporary file" no_temp_files race
# a file system without flock (NFS with no lock manager: ENOLCK, here from a shim): the commit goes
# ahead unlocked and says so in a warning line, rather than silently
printf '#include <errno.h>\nint flock(int fd, int op) { (void)fd; (void)op; errno = ENOLCK; return -1; }\n' > noflock.c
if ${CC:-cc} -shared -fPIC -o noflock.so noflock.c 2> /dev/null; then
  LD_PRELOAD=$PWD/noflock.so ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}verify_asan_link_order=0 "$FB" fbm --backend native --size 16x16 -o nf.exr 2> nf.txt
  rc=$?
  check "no flock: the bake commits (exit $rc)" test $rc -eq 0 -a -s nf.exr
  check "... and warns that it committed unlocked: $(head -1 nf.txt)" grep -q "cannot lock the folder for the commit (flock: No locks available): committing unlocked" nf.txt
  "$FB" fbm --backend native --size 16x16 -o lk.exr 2> lk.txt
  check "... a folder that locks: no such line" test "$(grep -c 'cannot lock' lk.txt)" = 0
else
  echo "no C compiler: the no-flock case was not run"
fi

# A KILL between the renames of a commit (a rename shim that stops the process before its second
# rename of a temporary file): the EXR is new, the preview, mesh and heightmap old, their hidden
# temporary files left. The next run that writes into the folder removes them, with one line naming
# the incomplete set and the files it did not replace (that a live run's are left alone, whatever its
# pid: tests/test_output.c).
cat > stoprename.c << 'C'
#define _GNU_SOURCE
#include <dlfcn.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
int rename(const char *from, const char *to)
{
    static int n;
    int (*real)(const char *, const char *) = (int (*)(const char *, const char *))dlsym(RTLD_NEXT, "rename");
    const char *stop = getenv("STOP_BEFORE_RENAME");
    size_t len = strlen(from);
    if (stop && len > 4 && !strcmp(from + len - 4, ".tmp") && ++n == atoi(stop)) raise(SIGKILL);
    return real(from, to);
}
C
if ${CC:-cc} -shared -fPIC -o stoprename.so stoprename.c -ldl 2> /dev/null; then
  mkdir kr
  for f in k.exr k.png k.ply k.r16; do echo old > kr/$f; done
  # (anonymous files too are given their hidden names before the first rename)
  (cd kr && STOP_BEFORE_RENAME=2 LD_PRELOAD=$T/stoprename.so ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}verify_asan_link_order=0 \
    exec "$FB" terrain $N --points ../pts.csv --size 64x64 -o k.exr --preview k.png --mesh k.ply --heightmap k.r16)
  rc=$?
  check "KILL between renames: exit $rc, wanted 137" test $rc -eq 137
  check "  the EXR is new, the rest old" sh -c '! grep -q old kr/k.exr && grep -q old kr/k.png && grep -q old kr/k.ply && grep -q old kr/k.r16'
  left=$(ls -A kr | grep -c '\.tmp$')
  check "  three temporary files left ($left)" test "$left" -eq 3
  set_id=$(ls -A kr | sed -n 's/^\.fractalbake-tmp\.[^.]*\.[0-9a-f]\{16\}\.[0-9]*\.\([0-9a-f]\{16\}\)\..*\.k\.png\.tmp$/\1/p')
  "$FB" fbm --backend native --size 16x16 -o kr/next.exr 2> next.txt
  check "  the next run into the folder bakes" test $? -eq 0 -a -s kr/next.exr
  check "  and removed them: $(ls -A kr | tr '\n' ' ')" test "$(ls -A kr | grep -c '^\.fractalbake-tmp\..*\.k\.[a-z0-9]*\.tmp$')" -eq 0
  check "  one line naming the set $set_id: $(cat next.txt)" \
    test "$(grep -c "removed 3 temporary files of an incomplete set of outputs in kr (set $set_id of process" next.txt)" -eq 1
  check "  and what was not replaced" grep -q "k.ply, k.png, k.r16 were not replaced by that run" next.txt
  check "  no other warning" test "$(grep -c warning next.txt)" -eq 1
  "$FB" fbm --backend native --size 16x16 -o kr/again.exr 2> again.txt
  check "  a third run says nothing of it" test "$(grep -c warning again.txt)" -eq 0
  check "  no temporary file at all" no_temp_files kr
else
  echo "no C compiler: the KILL between renames was not run"
fi

# A cluster's shared folder: another node's live run (its pid dead here, its lock not seen through
# NFS), and a user's files that look like temporary files (the earlier form with a dead pid; the
# prefix alone): none is removed; the other node's run is named in one line with the command that
# removes its files once it is over, and that command removes them and nothing else.
mkdir shared
dead=$(sh -c 'echo $$')
for f in ".fractalbake-tmp.node17.0123456789abcdef.$dead.00000000000000aa.00000001.sky.exr.tmp" \
  ".sky.exr.$dead.0123456789abcdef.0badcafe.tmp" ".fractalbake-tmp.notes" "sky.exr.tmp"; do
  echo "user's" > "shared/$f"
done
"$FB" fbm --backend native --size 16x16 -o shared/mine.exr 2> shared.txt
check "a bake beside another node's temporary files: exit $?" test -s shared/mine.exr
check "  none removed: $(ls -A shared | tr '\n' ' ')" test "$(grep -l "user's" shared/.fractalbake-tmp.* shared/.sky.exr.* shared/sky.exr.tmp | wc -l)" -eq 4
check "  one line naming the other node's run: $(cat shared.txt)" \
  test "$(grep -c "left 1 temporary file in shared of process $dead on host node17 (set 00000000000000aa, for sky.exr): made on another host" shared.txt)" -eq 1 -a "$(grep -c warning shared.txt)" -eq 1
cmd=$(sed -n 's/.*remove it by hand: //p' shared.txt)
sh -c "$cmd"
check "  its command ($cmd) removes that run's file alone" test "$(ls -A shared | wc -l)" -eq 4 -a ! -e "shared/.fractalbake-tmp.node17.0123456789abcdef.$dead.00000000000000aa.00000001.sky.exr.tmp"

# ---- 10. inputs that are not regular files are refused at once; so are empty constraint sets ----
mkfifo fifo.csv
timeout 20 "$FB" terrain $N --points fifo.csv --size 16x16 -o f.exr 2> fifo.txt
rc=$?
check "a FIFO as --points: exit $rc, wanted 2 at once" test $rc -eq 2
check "... one line naming the FIFO: $(cat fifo.txt)" grep -q "fifo.csv: is a FIFO with nothing written to it (expected the points file)" fifo.txt
printf 'x,y,z\n0,0,0\n10,0,1\n0,10,2\n' > three.csv
"$FB" terrain $N --points <(cat three.csv) --size 16x16 -o sub.exr
check "a pipe with a writer (<(...)) is read" test $? -eq 0 -a -s sub.exr
"$FB" terrain $N --points pts.csv --size 16x16 -o st.exr
mv pts.csv pts.keep && mkfifo pts.csv
timeout 20 "$FB" render $N --from st.exr --set layers.terrain.points=pts.csv -o st2.exr 2> fifo.txt
rc=$?
check "a FIFO named by a stored scene (--from): exit $rc, wanted 2 at once" test $rc -eq 2 -a ! -e st2.exr
rm pts.csv && mv pts.keep pts.csv
# ulimit -v: not under a sanitizer (its shadow memory alone is terabytes of address space)
if ! sanitized; then
  (ulimit -v 400000 && "$FB" constrain $N --size 64x64 --points /dev/zero -o z.exr 2> zero.txt)
  rc=$?
  check "/dev/zero as constraint points under ulimit -v: exit $rc, wanted 2" test $rc -eq 2 -a ! -e z.exr
  check "... one line: $(cat zero.txt)" grep -q "/dev/zero: is a character device, not a regular file or a pipe" zero.txt

  # ---- 11. the memory limit knows ulimit -v, and the Vulkan driver's needs ----
  (ulimit -v 600000 && timeout 60 "$FB" terrain --backend native --points pts.csv --insert 5000000 --size 512x512 -o big5.exr 2> as.txt)
  rc=$?
  check "5e6 insertions under ulimit -v 600000: refused at once (exit $rc, wanted 2)" test $rc -eq 2
  check "... naming the address-space limit: $(cat as.txt)" grep -q "the address-space limit, ulimit -v" as.txt
  if have_vulkan; then
    (ulimit -v 300000 && "$FB" julia --backend vulkan --size 1024x512 -o jv.exr 2> as.txt)
    rc=$?
    check "Vulkan under ulimit -v 300000: exit $rc, wanted 2 (not a crash in the driver)" test $rc -eq 2 -a ! -e jv.exr
    check "... one line: $(cat as.txt)" grep -q "a Vulkan driver needs about" as.txt
    (ulimit -v 300000 && "$FB" julia --size 256x128 -o ja.exr --quiet 2> as.txt)
    check "--backend auto under ulimit -v 300000 bakes natively" test $? -eq 0 -a -s ja.exr
  fi
  # a Vulkan driver's address space cannot fit and the bake cannot either: the error alone, not the
  # fallback warning beside it (the warning comes once the bake is known to fit)
  (ulimit -v 200000 && "$FB" julia --size 1024x512 -o j2.exr 2> as.txt)
  rc=$?
  check "auto under ulimit -v 200000, too small for the bake too: exit $rc, wanted 2" test $rc -eq 2 -a ! -e j2.exr
  check "... one line, the error: $(cat as.txt)" test "$(wc -l < as.txt)" = 1 -a "$(grep -c 'more than --max-memory' as.txt)" = 1
fi
check "no temporary file after the faults" no_temp_files

# ---- 11b. standard output is an output: never an input's file (1<>, >>) ----
"$FB" fbm $N --size 16x16 -o so.exr && cp so.exr soA.exr && cp so.exr soB.exr
sum=$(cat so.exr soA.exr | md5sum)
echo '{"size": [16, 8], "layers": [{"name": "n", "type": "fbm"}]}' > so.json
cp so.json so0.json
try_stdout() { # WHAT FILE COMMAND...: exit 2, one line naming FILE, nothing written
  local what=$1 file=$2
  shift 2
  "$@" 2> so.txt
  local rc=$?
  check "$what: exit $rc, wanted 2" test $rc -eq 2
  check "  one line naming $file: $(cat so.txt)" \
    test "$(wc -l < so.txt)" -eq 1 -a "$(grep -c "^fractalbake: $file: is an input of this run .* and also its standard output" so.txt)" -eq 1
}
try_stdout "render --from so.exr -o - 1<> so.exr" so.exr sh -c '"$0" render --from so.exr -o - 1<> so.exr' "$FB"
try_stdout "render --from so.exr -o - >> so.exr" so.exr sh -c '"$0" render --from so.exr -o - >> so.exr' "$FB"
try_stdout "compare soA.exr soB.exr --report - 1<> soA.exr" soA.exr sh -c '"$0" compare soA.exr soB.exr --report - 1<> soA.exr' "$FB"
try_stdout "info so.exr >> so.exr" so.exr sh -c '"$0" info so.exr >> so.exr' "$FB"
try_stdout "render so.json -o - 1<> so.json" so.json sh -c '"$0" render so.json -o - 1<> so.json' "$FB"
try_stdout "render --from so.exr -o x.exr --json >> so.exr" so.exr sh -c '"$0" render --from so.exr -o x.exr --json >> so.exr' "$FB"
check "  the inputs unchanged" test "$(cat so.exr soA.exr | md5sum)" = "$sum"
check "  the scene unchanged, no x.exr" sh -c 'cmp -s so.json so0.json && test ! -e x.exr'
"$FB" render --from so.exr -o - > so-copy.exr 2> /dev/null
check "standard output into another file is fine" test $? -eq 0 -a -s so-copy.exr
check "no temporary file" no_temp_files

# ---- 12. a documented maximum runs, tells how far it is, and stops at once on Ctrl-C ----
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
