#!/bin/sh
# Run every test program given on the command line, show Check's output, and
# finish with one summary line "checks: N passed, N failed" (exit 1 on failure).
# One fresh scratch directory per run (fx_tmpdir()): a run never reads an earlier run's files.
#
# The programs run AMP_TEST_JOBS at a time (default: one more than the processors, for the programs that
# mostly wait on a virtual printer), started in the order
# given (the Makefile names the longest first); each one's output is shown as it finishes. Every program
# is independent: its files carry its pid, its printers are its own pseudo-terminals.
AMP_TEST_TMP=$(mktemp -d "${TMPDIR:-/tmp}/ampath-check.XXXXXX") || exit 1
export AMP_TEST_TMP
trap 'rm -rf "$AMP_TEST_TMP"' EXIT
jobs=${AMP_TEST_JOBS:-$(($(getconf _NPROCESSORS_ONLN 2>/dev/null || echo 1) + 1))}
out="$AMP_TEST_TMP/out"
mkdir "$out" || exit 1

# one log and one exit code per program, numbered in the order given
n=0
for t in "$@"; do
    n=$((n + 1))
    printf '%s %s\n' "$n" "$t"
done | xargs -P "$jobs" -L 1 sh -c '"$2" > "$0/$1.log" 2>&1; echo $? > "$0/$1.rc"; grep -v "^Running suite" "$0/$1.log"' "$out"

passed=0; failed=0; broken=""
n=0
for t in "$@"; do
    n=$((n + 1))
    rc=$(cat "$out/$n.rc" 2>/dev/null || echo 127)
    line=$(grep -E '^[0-9]+%: Checks: ' "$out/$n.log" | tail -n 1)
    if [ -n "$line" ]; then
        c=$(printf '%s' "$line" | sed -E 's/.*Checks: ([0-9]+).*/\1/')
        f=$(printf '%s' "$line" | sed -E 's/.*Failures: ([0-9]+).*/\1/')
        e=$(printf '%s' "$line" | sed -E 's/.*Errors: ([0-9]+).*/\1/')
        passed=$((passed + c - f - e)); failed=$((failed + f + e))
    fi
    if [ "$rc" -ne 0 ]; then
        broken="$broken $(basename "$t")"
        [ -z "$line" ] && failed=$((failed + 1))
    fi
done
[ -n "$broken" ] && echo "failing programs:$broken"
echo "checks: $passed passed, $failed failed"
[ -z "$broken" ] && [ $failed -eq 0 ]
