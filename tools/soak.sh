#!/bin/sh
# make soak — the bridge's soak test at full size, against the virtual printer:
#   1. SOAK_LINES (default 100000) moves with 1 % of the bytes corrupted in both directions;
#   2. the same job with 0.5 % corrupted commands and three printer resets, resumed with
#      --resume-from until done (printer-to-host corruption is left out here: an ok lost just
#      before a reset makes that line's fate unknowable to any host, docs/bridge.md "Limits");
#   3. the same job unplugged eight times (the printer keeps running its queue, the oks of it are
#      lost) with 0.2 % of the bytes corrupted both ways: one run, reconnecting each time.
# Each passes only when the moves the printer executed equal the job's, in order, once each.
set -e
N=${SOAK_LINES:-100000}
V=./tools/ampath-vprinter
B=./bridge/ampath-bridge
T=${TMPDIR:-/tmp}/ampath-soak-$$
mkdir -p "$T"
trap 'kill $VP 2>/dev/null || true; rm -rf "$T"' EXIT
awk -v n="$N" 'BEGIN { print "G90"; print "M82"; print "G92 E0";
    for (i = 1; i <= n; i++) printf "G1 X%.2f Y%.2f E%.4f F%d\n", 100 + 40 * sin(i * 0.1), 100 + 40 * cos(i * 0.13), 0.01 * i, 1200 + i % 7 }' > "$T/job.gcode"
# a failed run's job, executed log and protocol logs stay for a look (the temporary directory goes)
keep() { K=${TMPDIR:-/tmp}/ampath-soak-failed-$$; cp -r "$T" "$K"; echo "soak: logs kept in $K"; }
moves() { grep -o 'G1 X.*' "$1" | sed 's/ *;.*//' | grep ' E'; }

run() { # name, vprinter options, more bridge options
    rm -f "$T/link" "$T/ran.log"
    $V --link "$T/link" --log "$T/ran.log" $2 > /dev/null 2>&1 &
    VP=$!
    i=0
    while [ ! -e "$T/link" ] && [ $i -lt 50 ]; do sleep 0.1; i=$((i + 1)); done
    start=$(date +%s)
    resume=1 runs=0 rc=1
    while [ $rc = 1 ] && [ $runs -lt 10 ]; do
        rc=0
        $B "$T/link" "$T/job.gcode" --quiet --baud 1000000 --timeout 0.1 --boot-wait 0.2 \
            --resume-from $resume --log "$T/bridge-$runs.log" $3 > "$T/out" 2>&1 || rc=$?
        runs=$((runs + 1))
        if [ $rc = 1 ]; then
            resume=$(sed -n 's/.*resume with --resume-from \([0-9]*\).*/\1/p' "$T/out" | head -n 1)
            [ -n "$resume" ] || { cat "$T/out"; exit 1; }
        fi
    done
    kill $VP 2>/dev/null || true
    wait $VP 2>/dev/null || true
    [ $rc = 0 ] || { echo "soak $1: bridge exit $rc"; cat "$T/out"; keep; exit 1; }
    moves "$T/job.gcode" > "$T/want"
    moves "$T/ran.log" > "$T/got"
    if cmp -s "$T/want" "$T/got"; then
        echo "soak $1: $N moves executed exactly once, in order ($runs run(s), $(($(date +%s) - start)) s)"
    else
        echo "soak $1: FAILED: executed moves differ from the job:"; diff "$T/want" "$T/got" | head -n 10
        keep; exit 1
    fi
}

run "1% corrupted bytes both ways" "--corrupt-in 0.01 --corrupt-out 0.01 --seed 21 --wait-ms 20"
K=$((N / 4))
run "0.5% corrupted commands, three resets" \
    "--corrupt-in 0.005 --seed 22 --reset-after $K --reset-after $K --reset-after $K --wait-ms 20"
H=""
for i in 1 2 3 4 5 6 7 8; do H="$H --hangup-after $((N * i / 9))"; done
run "unplugged 8 times, 0.2% corrupted bytes both ways" \
    "$H --hangup-secs 0.3 --corrupt-in 0.002 --corrupt-out 0.002 --seed 23 --wait-ms 20" "--reconnect 30"
