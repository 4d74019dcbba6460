#!/bin/sh
# make demo — docs/interfaces.md §6: the main job on built-in defaults, end to end.
#   helix model -> cover ([P1 §4.1]) -> order for the default head (§5.1) -> MDR (§5.2)
#   -> support (§5.3) -> independent checks -> G-code (docs/interfaces.md §5) -> pictures
#   -> stream through ampath-bridge to the virtual printer, and compare what it executed.
# Everything lands in demo/. Options through the environment:
#   DEMO_EPS (default 1 mm), DEMO_DIR (default u: curves along the helix, as in paper Fig. 11),
#   DEMO_PRINTER (default generic; any `ampath printer list` name or a slicer .ini).
set -e
A=./tools/ampath
B=./bridge/ampath-bridge
V=./tools/ampath-vprinter
D=demo
EPS=${DEMO_EPS:-1}
DIR=${DEMO_DIR:-u}
mkdir -p $D
rm -f $D/*.amp $D/*.gcode $D/*.log $D/*.json

# value of a JSON number field: num FILE NAME
num() { sed -n "s/.*\"$2\":\([-0-9.e+]*\).*/\1/p" "$1" | head -n 1; }
step() { printf '%-9s %s\n' "$1" "$2"; }

echo "ampath demo ($($A --version)) — helix, eps $EPS mm, default head (z_offs 0.5 mm, theta 72 deg)"
$A model helix -o $D/helix.spl > /dev/null
$A model helix -o $D/helix.stl --json > $D/model.json
step model "helix trivariate $D/helix.spl and its boundary mesh $D/helix.stl ($(num $D/model.json triangles) triangles)"

$A cover $D/helix.spl --eps "$EPS" --dir "$DIR" --json -o $D/helix-cover.amp > $D/cover.json
step cover "$(num $D/cover.json surfaces) iso-surfaces, $(num $D/cover.json curves) curves, $(num $D/cover.json length_mm | cut -d. -f1) mm (Algorithm 1, arc-length bound)"

$A order $D/helix-cover.amp --json -o $D/helix-ordered.amp > $D/order.json
step order "$(num $D/order.json fragments) fragments -> $(num $D/order.json paths_out) gouge-free paths: $(num $D/order.json subdivisions_improved) subdivisions"

$A mdr $D/helix-ordered.amp --nominal 0.5 --trivariate $D/helix.spl --json -o $D/helix-mdr.amp > $D/mdr.json
step mdr "deposition radius $(num $D/mdr.json radius_lo | cut -c1-5)..$(num $D/mdr.json radius_hi | cut -c1-5) mm, over-coverage $(num $D/mdr.json over_coverage | cut -c1-5)"

$A support $D/helix-mdr.amp --mesh $D/helix.stl --json -o $D/helix.amp > $D/support.json
step support "$(num $D/support.json support_paths) support paths under the overhangs ($(num $D/support.json conflicts) fragments with no gouge-free slot left out)"

$A check $D/helix.amp --trivariate $D/helix.spl --json > $D/check.json || {
    echo "demo: ampath check FAILED on $D/helix.amp:"; cat $D/check.json; exit 1; }
GAP=$(sed -n 's/.*"coverage":{[^}]*"coverage_gap_mm":\([0-9.e+-]*\).*/\1/p' $D/check.json)
step check "coverage gap $(echo "$GAP" | cut -c1-6) mm <= eps $EPS mm, no gouging, no crossing (independent checkers)"

$A gcode $D/helix.amp --printer "${DEMO_PRINTER:-generic}" --json -o $D/helix.gcode > $D/gcode.json
$A preview $D/helix.amp -o $D/helix.png
$A preview $D/helix.amp -o $D/helix.svg
step gcode "$D/helix.gcode for printer $(sed -n 's/.*"printer":"\([^"]*\)".*/\1/p' $D/gcode.json): $(num $D/gcode.json lines) lines ($(num $D/gcode.json lines_saved) segments saved by the 0.01 mm simplification), centred on the bed; pictures $D/helix.png, $D/helix.svg"

T=$(num $D/gcode.json time_s | cut -d. -f1)
echo
echo "paths:           $(num $D/order.json paths_out) object + $(num $D/support.json support_paths) support"
echo "subdivisions:    $(num $D/order.json subdivisions_improved)"
echo "coverage error:  $(echo "$GAP" | cut -c1-6) mm (eps $EPS mm)"
TT=$(num $D/gcode.json travel_time_s | cut -d. -f1)
echo "print length:    $(num $D/gcode.json print_length_mm | cut -d. -f1) mm extruding, $(num $D/gcode.json travel_length_mm | cut -d. -f1) mm travel ($(num $D/gcode.json travel_per_print_length | cut -c1-4) x)"
echo "estimated time:  $((T / 3600)) h $((T % 3600 / 60)) min, of which travel $((TT / 60)) min ($(((200 * TT / (T > 0 ? T : 1) + 1) / 2)) %); filament $(num $D/gcode.json filament_mm | cut -d. -f1) mm"
echo "travels:         $(num $D/gcode.json travels) ($(num $D/gcode.json direct_hops) direct hops without retraction or lift, $(num $D/gcode.json retractions) retractions); targets: <= 0.5 x, <= 30 %"
echo

# Stream the job to the virtual printer (docs/interfaces.md §8) through a pseudo-terminal, then compare.
LINK=/tmp/ampath-demo-printer-$$
$V --link $LINK --log $D/printer.log > /dev/null 2>&1 &
VP=$!
trap 'kill $VP 2>/dev/null || true; rm -f $LINK' EXIT
i=0
while [ ! -e $LINK ] && [ $i -lt 50 ]; do sleep 0.1; i=$((i + 1)); done
$B $LINK $D/helix.gcode --boot-wait 0.2 --quiet
kill $VP 2>/dev/null; wait $VP 2>/dev/null || true
SENT=$(grep -c '^G[01] ' $D/helix.gcode || true)
DONE=$(grep -c '^[0-9]* G[01] ' $D/printer.log || true)
OFFBED=$(grep -c '# out of bed' $D/printer.log || true)
echo "virtual printer: executed $DONE of $SENT moves of $D/helix.gcode, $OFFBED outside its 220 x 220 x 250 bed"
[ "$SENT" = "$DONE" ] && [ "$OFFBED" = 0 ]
