#!/bin/sh
# Proof that `make fuzz` fails on a finding: build the targets with a planted
# defect and expect make to fail, once for a crash (trap) and once for undefined behaviour
# (a signed overflow, reported by UBSan). Run by `make fuzz-selftest`.
set -u
for plant in trap ubsan; do
    log=build/fuzz-plant-$plant.log
    if ${MAKE:-make} --no-print-directory fuzz FUZZ_PLANT=$plant FUZZ_SECONDS=${FUZZ_SECONDS:-10} >"$log" 2>&1; then
        echo "fuzz-selftest: make fuzz FUZZ_PLANT=$plant succeeded: a finding does not fail the target" >&2
        exit 1
    fi
    case $plant in
        trap) want='deadly signal' ;;
        ubsan) want='runtime error: signed integer overflow' ;;
    esac
    if ! grep -q "$want" "$log"; then
        echo "fuzz-selftest: make fuzz FUZZ_PLANT=$plant failed, but not on the plant ('$want' missing, see $log)" >&2
        exit 1
    fi
    echo "fuzz-selftest: FUZZ_PLANT=$plant: make fuzz failed on the planted $plant, as it must"
done
