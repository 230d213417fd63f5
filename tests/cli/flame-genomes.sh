#!/bin/bash
# Issue 42's measure of coverage: 40 genomes as flam3-genome makes them with default settings (its
# own choice of variations, symmetry and xforms; seeds 100 to 139), 192 x 192, each rendered by
# flam3-render twice and by fractalbake (tests/cli/flame-measure.bash): at least 39 render, and every
# one that does is no farther from flam3 than 1.5 times flam3's distance from itself with another
# isaac_seed. Not run (77) without flam3-utils.
# Usage: flame-genomes.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
. "$HERE/flame-measure.bash"

refused=0
for seed in $(seq 100 139); do
    run_case "plain_$seed" "$seed" - 192
    [ $? -eq 2 ] && refused=$((refused + 1))
done
[ "$refused" -le 1 ] && ok || bad "$refused of 40 default flam3-genome genomes refused"

cli_finish
