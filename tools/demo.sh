#!/bin/sh
# make demo: the main job of SPEC §6 on built-in defaults, as far as the pipeline exists.
set -e
A=./tools/ampath
mkdir -p demo
echo "ampath demo ($($A --version))"
printf 'ampath-paths 1\n# a hand-made square spiral, until the covering commands land\npath object 5\n0 0 0.2 0.5\n10 0 0.2 0.5\n10 10 0.2 0.5\n0 10 0.2 0.5\n0 0 0.2 0.5\n' > demo/square.amp
$A info demo/square.amp
echo "demo: the covering, ordering and G-code stages are not built yet; stopped after demo/square.amp"
