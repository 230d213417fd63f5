# Shared by the tests/cli/*.sh scripts: a private scratch folder, pass/fail counters, and checks.
# Source it after setting nothing; call `cli_init "$@"` first and `cli_finish` last.
# Usage of a script: SCRIPT.sh PATH/TO/fractalbake
set -u

cli_init() {
  FB=$(realpath "$1")
  HERE=$(cd "$(dirname "${BASH_SOURCE[1]}")" && pwd)
  ROOT=$(cd "$HERE/../.." && pwd)
  T=$(mktemp -d "${TMPDIR:-/tmp}/fb-cli-XXXXXX")
  trap 'rm -rf "$T"' EXIT
  cd "$T" || exit 1
  export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$T}
  pass=0
  fail=0
}

ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*" >&2; }

# check DESCRIPTION COMMAND...: passes when the command succeeds
check() {
  local what=$1
  shift
  if "$@"; then ok; else bad "$what"; fi
}

# no_temp_files [DIR]: no hidden temporary output (".NAME.XXXX.tmp") left in DIR (default: here)
no_temp_files() {
  ! ls -A "${1:-.}" | grep -q '\.tmp$'
}

# expect_fail CODE PATTERN OUTFILE -- ARGS: exit CODE, exactly one stderr line matching PATTERN,
# no OUTFILE and no temporary file left
expect_fail() {
  local code=$1 pat=$2 out=$3
  shift 4
  "$FB" "$@" > "$T/stdout" 2> "$T/stderr"
  local rc=$? lines
  lines=$(wc -l < "$T/stderr")
  if [ $rc -ne "$code" ]; then bad "$* : exit $rc, wanted $code ($(cat "$T/stderr"))"; return; fi
  if [ "$lines" -ne 1 ]; then bad "$* : $lines stderr lines, wanted 1: $(cat "$T/stderr")"; return; fi
  if ! grep -q -- "$pat" "$T/stderr"; then bad "$* : stderr lacks '$pat': $(cat "$T/stderr")"; return; fi
  if [ -n "$out" ] && [ -e "$out" ]; then bad "$* : left $out behind"; return; fi
  if ! no_temp_files "$T"; then bad "$* : left a temporary file"; return; fi
  ok
}

# have_vulkan: a Vulkan device (lavapipe at least) answers
have_vulkan() {
  "$FB" devices 2> /dev/null | grep -q '^0 '
}

# require_vulkan: a script that compares backends is not run (77) where no Vulkan device exists
require_vulkan() {
  if ! have_vulkan; then
    echo "no Vulkan device: not run"
    exit 77
  fi
}

# sanitized: whether $FB is an AddressSanitizer build, whose shadow memory (terabytes reserved) rules
# out ulimit -v and whose overheads rule out bounds on time and memory
sanitized() {
  ldd "$FB" | grep -q libasan
}

# require_blender: a script that drives Blender is not run (77) where Blender is not installed
require_blender() {
  if ! command -v blender > /dev/null; then
    echo "no blender: not run"
    exit 77
  fi
}

# blender_test NAME ARGS...: tests/blender/test_NAME.py in Blender (headless, factory settings), with the
# repository's root and ARGS after its `--`; shows the script's ok and FAIL lines, and passes when it exits 0
blender_test() {
  local name=$1 rc
  shift
  blender -b --factory-startup --python-exit-code 1 -P "$ROOT/tests/blender/test_$name.py" -- "$ROOT" "$@" \
    > "blender-$name.log" 2>&1
  rc=$?
  grep -E '^(ok|FAIL) ' "blender-$name.log"
  [ $rc -eq 0 ] && ok || bad "tests/blender/test_$name.py: exit $rc: $(grep -E 'FAIL|Error' "blender-$name.log" | head -5)"
}

# exr_strict FILE: OpenEXRCore's strict header check, read from what exrinfo prints, never from its
# exit status: Debian 12's exrinfo (OpenEXR 3.1.5) exits with a random status on valid files. A file
# it accepts prints "File 'FILE':" and one dataWindow a part, and nothing on stderr; one it refuses
# prints nothing on stdout. exrheader (the C++ library's header read) exits reliably.
exr_strict() {
  local out err
  out=$(exrinfo --strict "$1" 2> "$T/strict.err") || true
  err=$(cat "$T/strict.err")
  rm -f "$T/strict.err"
  [ -z "$err" ] && [ "$(printf '%s\n' "$out" | head -n 1)" = "File '$1':" ] &&
    printf '%s\n' "$out" | grep -q '^ *dataWindow: ' && exrheader "$1" > /dev/null 2>&1
}

# valid_exr FILE: strict header check and a full decode through the OpenEXR C++ library
valid_exr() {
  if exr_strict "$1" && exrmaketiled "$1" "$T/tiled.exr" > /dev/null 2>&1; then ok; else bad "$1 is not a valid EXR"; fi
  rm -f "$T/tiled.exr"
}

# png_wh FILE: a PNG's width and height
png_wh() { printf '%d %d' "0x$(od -An -tx1 -j16 -N4 "$1" | tr -d ' ')" "0x$(od -An -tx1 -j20 -N4 "$1" | tr -d ' ')"; }

# cli_finish: the closing line CTest's log shows; exit 1 on any failure
cli_finish() {
  echo "$pass passed, $fail failed"
  [ "$fail" -eq 0 ]
}
