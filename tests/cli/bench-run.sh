#!/usr/bin/env bash
# bench/run.sh installs nothing and writes no tracked file: run in a copy of bench/ with stand-ins for
# the build, the compilers and the package tools on PATH (apt-get and sudo record that they were
# called), it appends its lines to build/bench-results.jsonl or --out, never to bench/results.jsonl.
# Usage: bench-run.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
mkdir -p repo/build repo/scripts stubs
cp -r "$ROOT/bench" repo/
printf '#!/bin/sh\necho "setup.sh was run" >> %s/called\n' "$T" > repo/scripts/setup.sh
printf '#!/bin/sh\necho "{\\"generator\\": \\"stub\\"}"\n' > repo/build/fractalbake
for tool in apt-get apt sudo; do printf '#!/bin/sh\necho "%s $*" >> %s/called\n' "$tool" "$T" > stubs/$tool; done
# the compilers make a program that prints one JSON line; dpkg-query: nothing is installed
printf '#!/bin/sh\nwhile [ $# -gt 0 ]; do [ "$1" = -o ] && out=$2; shift; done\nprintf "#!/bin/sh\\necho {}\\n" > "$out"; chmod +x "$out"\n' > stubs/gcc
cp stubs/gcc stubs/g++
printf '#!/bin/sh\nexit 1\n' > stubs/dpkg-query
chmod +x repo/scripts/setup.sh repo/build/fractalbake stubs/*
before=$(cksum < repo/bench/results.jsonl)
PATH="$T/stubs:$PATH" bash repo/bench/run.sh > out.txt 2> err.txt && ok || bad "bench/run.sh failed: $(cat err.txt)"
check "bench/run.sh installs nothing and runs no setup" test ! -e called
check "bench/run.sh leaves bench/results.jsonl as it was" test "$(cksum < repo/bench/results.jsonl)" = "$before"
check "bench/run.sh appends to build/bench-results.jsonl" grep -q '"result": {"generator": "stub"}' repo/build/bench-results.jsonl
check "bench/run.sh says which peers it leaves out" grep -q "libcgal-dev is not installed" err.txt
PATH="$T/stubs:$PATH" bash repo/bench/run.sh --out "$T/mine.jsonl" > /dev/null 2>&1 && ok || bad "bench/run.sh --out failed"
check "--out names the file" test "$(grep -c '"result"' mine.jsonl)" -ge 5
PATH="$T/stubs:$PATH" bash repo/bench/run.sh --out bench/results.jsonl > /dev/null 2> err.txt
[ $? -eq 2 ] && grep -q "a tracked file" err.txt && ok || bad "bench/run.sh --out bench/results.jsonl was not refused"
check "a refused --out leaves the tracked file" test "$(cksum < repo/bench/results.jsonl)" = "$before"
cli_finish
