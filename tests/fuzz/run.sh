#!/bin/sh
# make fuzz: run every libFuzzer target for SECONDS each on a seed corpus made from the
# built-in models by the tool itself (no binary blobs in the repository), and fail as soon
# as a target fails: a crash, an ASan report, or a UBSan report (the targets are built with
# -fno-sanitize-recover=undefined, so any undefined behaviour stops the run).
#   usage: sh tests/fuzz/run.sh AMPATH SECONDS OUTDIR fuzz_binary...
# Each target's full log is OUTDIR/NAME.log; the reproducer is written to OUTDIR (crash-*).
set -u
tool=$1; secs=$2; out=$3; shift 3
seeds=$out/seeds
rm -rf "$seeds" && mkdir -p "$seeds/amp" "$seeds/spl" "$seeds/stl" || exit 1

# Small seeds: under libFuzzer's 64 KiB max_len, so that they survive whole.
gen() { "$tool" "$@" >/dev/null 2>&1 || { echo "fuzz: seed generation failed: ampath $*" >&2; exit 1; }; }
for m in helix torus-quarter vase; do
    gen model "$m" -o "$seeds/spl/$m.spl"
done
gen model twisted-bridge -o "$out/tb.stl"
gen model helix --tol 1 -o "$out/helix.stl"
gen slice "$out/tb.stl" --layer 2 -o "$out/tb.amp"
gen cover vase --eps 5 -o "$out/vase.amp"
gen order "$out/vase.amp" -o "$out/vase-ordered.amp"
for f in tb helix; do
    # a binary STL cut to its first 16 triangles: 80-byte header, count 16, 16 x 50 bytes
    { head -c 80 "$out/$f.stl"; printf '\020\000\000\000'; tail -c +85 "$out/$f.stl" | head -c 800; } \
        > "$seeds/stl/$f-16.stl"
done
for f in tb vase vase-ordered; do
    # the header and the first three paths of a real .amp file
    awk '/^path /{n++} n<=3' "$out/$f.amp" > "$seeds/amp/$f-3.amp"
done
printf 'ampath-paths 1\n# two paths\npath object 2\n0 0 0 0.2\n1 0 0 0.2\npath support 2 0.3\n0 1 0 0.2\n1 1 0 0.2\n' \
    > "$seeds/amp/tiny.amp"

for f in "$@"; do
    name=$(basename "$f")
    case $name in
        fuzz_amp) s=$seeds/amp ;;
        fuzz_spl) s=$seeds/spl ;;
        fuzz_stl) s=$seeds/stl ;;
        *) s=$seeds ;;
    esac
    mkdir -p "$out/corpus-$name"
    echo "== $f for $secs s (seeds: $(ls "$s" | wc -l) in $s)"
    "$f" -max_total_time="$secs" -max_len=65536 -artifact_prefix="$out/" "$out/corpus-$name" "$s" \
        > "$out/$name.log" 2>&1
    rc=$?
    tail -n 3 "$out/$name.log"
    if [ "$rc" -ne 0 ]; then
        echo "fuzz: $name FAILED (exit $rc); the report:" >&2
        grep -E -A 12 'ERROR: |runtime error|deadly signal|==[0-9]+==' "$out/$name.log" | head -n 40 >&2
        echo "fuzz: full log $out/$name.log; reproducer $(ls -t "$out"/crash-* "$out"/timeout-* "$out"/oom-* 2>/dev/null | head -n 1)" >&2
        exit 1
    fi
done
echo "fuzz: all targets ran without a finding"
