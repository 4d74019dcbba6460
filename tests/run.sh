#!/bin/sh
# Run every test program given on the command line, show Check's output, and
# finish with one summary line "checks: N passed, N failed" (exit 1 on failure).
# One fresh scratch directory per run (fx_tmpdir()): a run never reads an earlier run's files.
AMP_TEST_TMP=$(mktemp -d "${TMPDIR:-/tmp}/ampath-check.XXXXXX") || exit 1
export AMP_TEST_TMP
trap 'rm -rf "$AMP_TEST_TMP"' EXIT
passed=0; failed=0; broken=""
for t in "$@"; do
    out=$("$t" 2>&1); rc=$?
    printf '%s\n' "$out" | grep -v '^Running suite' 
    line=$(printf '%s\n' "$out" | grep -E '^[0-9]+%: Checks: ' | tail -n 1)
    if [ -n "$line" ]; then
        n=$(printf '%s' "$line" | sed -E 's/.*Checks: ([0-9]+).*/\1/')
        f=$(printf '%s' "$line" | sed -E 's/.*Failures: ([0-9]+).*/\1/')
        e=$(printf '%s' "$line" | sed -E 's/.*Errors: ([0-9]+).*/\1/')
        passed=$((passed + n - f - e)); failed=$((failed + f + e))
    fi
    if [ $rc -ne 0 ]; then
        broken="$broken $(basename "$t")"
        [ -z "$line" ] && failed=$((failed + 1))
    fi
done
[ -n "$broken" ] && echo "failing programs:$broken"
echo "checks: $passed passed, $failed failed"
[ -z "$broken" ] && [ $failed -eq 0 ]
