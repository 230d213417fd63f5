#!/usr/bin/env bash
# The suite's EXR verdicts do not hang on exrinfo's exit status: Debian 12's exrinfo (OpenEXR 3.1.5)
# exits with a random status on valid files. Here an exrinfo that prints what the real one prints and
# exits with a random status stands first on PATH: valid_exr passes every valid file every time, and
# exr_strict refuses a truncated file, a file that is not an EXR and a missing one every time.
# Usage: verdicts.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
mkdir bin
cat > bin/exrinfo << SH
#!/usr/bin/env bash
$(command -v exrinfo) "\$@"
exit \$((RANDOM % 256))
SH
chmod +x bin/exrinfo
PATH="$T/bin:$PATH"
N="--backend native --quiet"
"$FB" fbm --size 40x24 --octaves 3 $N -o one.exr
printf '%s' '{"size": [40, 24], "parts": "per-layer", "layers": [{"type": "fbm", "name": "a", "octaves": 2},
 {"type": "fbm", "name": "b", "octaves": 3, "hurst": 0.3}]}' > mp.json
"$FB" render mp.json $N -o mp.exr
head -c 400 one.exr > cut.exr
head -c "$(($(stat -c %s mp.exr) / 2))" mp.exr > halfmp.exr
cp "$ROOT/README.md" text.exr
codes=""
before=$fail
for i in $(seq 20); do
  valid_exr one.exr
  valid_exr mp.exr
  exr_strict cut.exr && bad "a truncated header passed exr_strict"
  exr_strict text.exr && bad "a text file passed exr_strict"
  exr_strict none.exr && bad "a missing file passed exr_strict"
  # a file whose header is whole but whose pixels are cut: the full decode refuses it
  exrmaketiled halfmp.exr t.exr > /dev/null 2>&1 && bad "a file cut in its pixels decoded"
  exrinfo one.exr > /dev/null 2>&1
  codes="$codes $?"
done
[ $fail -eq $before ] && ok
# the stand-in did exit with other statuses than 0, so the runs above did meet a random status
[ -n "$(echo "$codes" | tr ' ' '\n' | grep -v '^0$' | grep .)" ] && ok || bad "the stand-in exrinfo always exited 0: $codes"
cli_finish
