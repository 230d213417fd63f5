#!/bin/bash
# scripts/gpu-check.sh on lavapipe at a tiny scale (its verdicts say nothing of a GPU here; what is
# tested is the check itself): the summary ends in one PASS or FAIL line per target and the exit
# status follows them; a step cut by its limit says "cut at N s" and fails; a gpu test that is not
# run (exit 77: here no Vulkan driver for the tests step) is a failure, not a pass; bench rows missing
# for a kernel fail it. Not run (77) without a Vulkan device.
# Usage: gpu-check.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
require_vulkan
FB_BUILD_DIR=$(dirname "$FB")
export FB_BUILD_DIR FB_GPU_CHECK_ALLOW_CPU=1 FB_GPU_CHECK_SCALE=64
gc() { bash "$ROOT/scripts/gpu-check.sh" "$@" > /dev/null 2> "$T/gc.err"; }

# devices and one gpu test: every target passes, the summary ends in their lines, exit 0
FB_GPU_CHECK_STEPS="devices tests" FB_GPU_CHECK_TESTS='^vkc$' FB_GPU_CHECK_LIMIT_devices=300 \
    FB_GPU_CHECK_LIMIT_tests=300 gc correctness a
rc=$?
check "devices and vkc: exit 0 (exit $rc: $(tail -3 a/summary.txt | tr '\n' ' '))" test $rc -eq 0
check "... the last lines: one verdict a target" test "$(tail -3 a/summary.txt | cut -d: -f1 | tr '\n' ,)" = \
    "PASS devices,PASS subnormals,PASS tests,"
check "... the test counted" grep -q '^PASS tests: 1 of 1 gpu tests passed' a/summary.txt
check "... the step lines before them, and the total" grep -q '^total [0-9]* s$' a/summary.txt

# the same test without a Vulkan driver: it is not run (77), and that fails the step
VK_DRIVER_FILES=$T/none.json VK_ICD_FILENAMES=$T/none.json FB_GPU_CHECK_STEPS=tests FB_GPU_CHECK_TESTS='^vkc$' \
    FB_GPU_CHECK_LIMIT_tests=300 gc correctness b
rc=$?
check "a skipped test: exit 1 (exit $rc)" test $rc -eq 1
check "... FAIL tests, 1 skipped: $(tail -1 b/summary.txt)" grep -q '^FAIL tests: 0 of 1 passed, 1 skipped' b/summary.txt

# a step cut by its limit
FB_GPU_CHECK_STEPS=golden FB_GPU_CHECK_LIMIT_golden=1 gc correctness c
rc=$?
check "golden cut at 1 s: exit 1 (exit $rc)" test $rc -eq 1
check "... its step line and verdict say so: $(tail -1 c/summary.txt)" \
    test "$(grep -c 'cut at 1 s' c/summary.txt)" -eq 2 -a "$(tail -1 c/summary.txt | cut -d: -f1)" = "FAIL golden"

# the speed call: the flame's rate from the device's timestamps (FAIL: not the target's size); bench
# cut before any kernel row, so each kernel fails
FB_GPU_CHECK_STEPS="flame bench" FB_GPU_CHECK_LIMIT_flame=300 FB_GPU_CHECK_LIMIT_bench=1 gc speed d
rc=$?
check "speed: exit 1 (exit $rc)" test $rc -eq 1
check "... the flame's verdict with a rate: $(grep flame-10G d/summary.txt)" \
    grep -qE '^FAIL flame-10G: 32x32 quality 15: [0-9.e+-]+ G points/s by the device' d/summary.txt
check "... a rate above zero" test -z "$(grep -E '^FAIL flame-10G: .*: 0 G' d/summary.txt)"
check "... bench cut at 1 s" grep -q '^bench *cut at 1 s' d/summary.txt
check "... every kernel without its row fails" test "$(grep -c '^FAIL kernel .*: cut at 1 s; no kernel row' d/summary.txt)" -eq 5
check "... the verdicts are the last lines" test "$(tail -6 d/summary.txt | grep -cE '^(PASS|FAIL) ')" -eq 6

check "bad usage: exit 2" test "$(bash "$ROOT/scripts/gpu-check.sh" both e 2> /dev/null; echo $?)" -eq 2
cli_finish
