#!/bin/sh
# The fixed suite of the correction's fidelity (docs/kernels/correct-convex.md):
# 300 simulated scans (brilliant, princess, emerald, jubilee96; K = 100 to
# 800; 0-3 µm noise; random view phase and stone azimuth), corrected with
# the convex path and with the merge alone, each compared with its stone
# facet by facet. Prints both tables' totals. Usage: correct_suite.sh BUILD_DIR
set -u
B=${1:-build}
N=${FACET_SUITE:-300}
status=0
for m in auto merge; do
    echo "-- method $m, $N scans"
    "$B/tools/correct_table" --suite "$N" --method "$m" 2>/dev/null || status=1
done
exit $status
