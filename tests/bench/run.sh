#!/bin/sh
# Runs every benchmark binary in BUILD_DIR/bench; each prints its own
# figures. Usage: tests/bench/run.sh BUILD_DIR
set -u
B=${1:-build}
export FACET_BUILD="$B"
status=0
for b in "$B"/bench/bench_*; do
    [ -x "$b" ] || continue
    echo "== $(basename "$b")"
    "$b" || status=1
done
for s in tests/bench/*.sh; do
    [ "$(basename "$s")" = run.sh ] && continue
    [ -f "$s" ] || continue
    echo "== $(basename "$s" .sh)"
    bash "$s" "$B" || status=1
done
exit $status
