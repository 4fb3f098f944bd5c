#!/bin/sh
# Runs every unit test binary (cmocka, TAP output) and every integration
# test script (TAP output), then prints "N passed, N failed, N skipped"
# ("ok ... # SKIP reason" is a skip, not a pass; the reasons are listed).
# Usage: tests/run.sh BUILD_DIR [FILTER]
set -u
B=${1:-build}
FILTER=${2:-}
pass=0
fail=0
skipped=0
log=$(mktemp)
skips=$(mktemp)
trap 'rm -f "$log" "$skips"' EXIT

count() { # $1 = name; reads TAP from $log
    p=$(grep '^ok ' "$log" | grep -vc '# *SKIP')
    k=$(grep '^ok ' "$log" | grep -c '# *SKIP')
    f=$(grep -c '^not ok ' "$log")
    pass=$((pass + p))
    skipped=$((skipped + k))
    fail=$((fail + f))
    grep '^ok .*# *SKIP' "$log" | sed "s/^/# $1: /" >>"$skips"
    if [ "$f" -gt 0 ]; then
        grep -B2 -A12 '^not ok ' "$log" | head -n 80
    fi
}

export CMOCKA_MESSAGE_OUTPUT=TAP
export FACET_BUILD="$B"
for t in "$B"/tests/test_*; do
    [ -x "$t" ] || continue
    case "$t" in *"$FILTER"*) ;; *) continue ;; esac
    name=$(basename "$t")
    start=$(date +%s%N)
    "$t" >"$log" 2>&1
    rc=$?
    count "$name"
    if [ $rc -ne 0 ] && ! grep -q '^not ok ' "$log"; then
        echo "$name: exited with status $rc"
        tail -n 30 "$log"
        fail=$((fail + 1))
    fi
    printf '# %-40s %6d ms\n' "$name" $((($(date +%s%N) - start) / 1000000))
done
for t in tests/integration/*.sh; do
    [ -f "$t" ] || continue
    [ "$(basename "$t")" = lib.sh ] && continue # shared helpers, not a test
    case "$t" in *"$FILTER"*) ;; *) continue ;; esac
    name=$(basename "$t" .sh)
    start=$(date +%s%N)
    bash "$t" "$B" >"$log" 2>&1
    rc=$?
    count "$name"
    if [ $rc -ne 0 ] && ! grep -q '^not ok ' "$log"; then
        echo "$name: exited with status $rc"
        tail -n 30 "$log"
        fail=$((fail + 1))
    fi
    printf '# %-40s %6d ms\n' "$name" $((($(date +%s%N) - start) / 1000000))
done
cat "$skips"
echo "$pass passed, $fail failed, $skipped skipped"
[ "$fail" -eq 0 ]
