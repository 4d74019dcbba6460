#!/bin/sh
# tools/identity.sh [DIR] — the products of the demo pipeline, one sha256 a file.
# A refactoring with no change of behaviour leaves every line of this output
# unchanged: run it before and after and compare (diff) the two listings.
#   helix trivariate and mesh -> cover -> order -> mdr -> support -> gcode (marlin
#   and klipper) -> preview (svg, png); the twisted-bridge mesh -> slice
#   --polygons, slice --continuous -> gcode -> preview; a direction-field cover.
# Only products are hashed (not the --json figures, which hold timings).
# tools/identity.ref holds the listing of the current behaviour (renewed at stop 40: a splice of two loops leaves
# out the shorter stretch of the other loop by length, not by segment count, so the twisted bridge's continuous
# paths, their G-code and picture changed, nothing else; at stop 39: a face exposed under a
# layer makes that layer and the three above it solid at 0.8 mm skins, as the bed does (it made two more), so
# the twisted bridge's continuous paths, their G-code and picture changed, nothing else; twice at stop 38: the G-code sets E
# back to 0 at a travel once it has reached 100 mm, so the three G-code files gained G92 E0 lines, the moves'
# E unchanged; then section rings lose their needles under 10 um, so the twisted bridge's polygons (area
# -0.004 mm2 over all layers), continuous paths, their G-code and picture changed, nothing else; at stop 35: gcode's min_segment is
# measured on the coordinates as written, so the twisted bridge's continuous G-code changed, nothing else; at
# stop 34: a thin island's perimeter
# whose two sides lie closer than r/4 is printed once along one side, an open stroke started at its end nearer
# the nozzle, not as a loop there and back, so the twisted bridge's continuous paths, their G-code and picture
# changed, nothing else; at stop 33: the part-cooling fan goes
# off for a tube on the bed printed after higher ones, so the helix G-code files gained six M107/M106 pairs and
# their line count, nothing else; twice at stop 30: skin bands are as
# deep as the neighbouring sections' edges reach into a region, not a grid cell deeper, then the support
# corners' bases are r wide, not 2r, so the twisted bridge's continuous paths, their G-code and picture
# changed, nothing else; at stop 29: slice --continuous
# narrows the beads of an island that hold more plastic than its slab, so the twisted bridge's continuous
# paths, their G-code and picture changed, nothing else; at stop 28: order and mdr merge a
# cut point within a nanometre of a vertex into it, so the helix's ordered, mdr and G-code files changed; then
# the estimate's per-axis accelerations, and Klipper's square corner velocity, changed the time in the
# G-code files' headers, nothing else; at
# stop 27: the gcode material grids raise the cells within reach of each segment row by row, not boxes around
# samples, so the helix's travels changed; before, at stop 26: support on the bed and in zigzags, travels over the beads as written, modal Z on
# printing moves, the field's eps comment; the plain build, OpenMP on). Uses ./tools/ampath of the
# current build (AMP_TOOL overrides); DIR defaults to build/identity. Compare listings made in the same DIR:
# the products' header comments name their input files. An OPENMP=0 build covers differently (but the
# same before and after: compare it with an OPENMP=0 build of the old tree).
set -e
A=${AMP_TOOL:-./tools/ampath}
D=${1:-build/identity}
mkdir -p "$D"
rm -f "$D"/*
$A model helix -o "$D/helix.spl" > /dev/null
$A model helix -o "$D/helix.stl" > /dev/null
$A cover "$D/helix.spl" --eps 1 --dir u -o "$D/helix-cover.amp" > /dev/null
$A order "$D/helix-cover.amp" -o "$D/helix-ordered.amp" > /dev/null
$A mdr "$D/helix-ordered.amp" --nominal 0.5 --trivariate "$D/helix.spl" -o "$D/helix-mdr.amp" > /dev/null
$A support "$D/helix-mdr.amp" --mesh "$D/helix.stl" -o "$D/helix.amp" > /dev/null
$A gcode "$D/helix.amp" --printer generic -o "$D/helix.gcode" > /dev/null
$A gcode "$D/helix.amp" --flavor klipper -o "$D/helix-klipper.gcode" > /dev/null
$A preview "$D/helix.amp" -o "$D/helix.svg" > /dev/null
$A preview "$D/helix.amp" -o "$D/helix.png" > /dev/null
$A model twisted-bridge -o "$D/bridge.stl" > /dev/null
$A slice "$D/bridge.stl" --layer 0.2 --polygons -o "$D/bridge-polygons.amp" > /dev/null
$A slice "$D/bridge.stl" --layer 0.2 --continuous -o "$D/bridge-cont.amp" > /dev/null
$A gcode "$D/bridge-cont.amp" -o "$D/bridge-cont.gcode" > /dev/null
$A preview "$D/bridge-cont.amp" -o "$D/bridge-cont.svg" > /dev/null
$A field "$D/helix.stl" --field helix-square --spacing 1 -o "$D/helix-field.amp" > /dev/null
$A check "$D/helix.amp" --trivariate "$D/helix.spl" > /dev/null
cd "$D" && sha256sum -- *
