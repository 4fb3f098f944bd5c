#!/bin/bash
# correct_vs_inspect.sh — the correction's speed against the inspection's
# (docs/kernels/correct-convex.md): the whole `facet correct` process
# against the whole `facet inspect --threads 1` process on the same scan,
# for the k400 and k800 sample scans (3,612 and 4,404 vertices) and a
# simulated jubilee96 scan of 2,400 views (7,962 vertices). A figure is
# the CPU time (user + system) of REP runs of one command in a row, per
# run, the best of RUNS rounds (default 5) with the two commands
# interleaved: a shared machine moves single times by 2×. Prints
# "name: value" lines and the target (≤ 5×).
# Usage: correct_vs_inspect.sh BUILD_DIR
set -u
B=${1:-build}
RUNS=${BENCH_RUNS:-5}
REP=10
T=$(mktemp -d /tmp/facet-correct-speed.XXXXXX)
trap 'rm -rf "$T"' EXIT
echo "# $(nproc) CPUs; load average $(cut -d' ' -f1-3 /proc/loadavg)"
"$B/tools/scansim" --cut jubilee96 --k 2400 --seed 3 --scan "$T/jub.json" \
    >/dev/null || exit 1

# Milliseconds of CPU per run of the command, over REP runs in a row.
cpu_ms() {
    local TIMEFORMAT='%3U %3S'
    { time for _ in $(seq "$REP"); do "$@" >/dev/null || exit 1; done; } \
        2>&1 | awk -v n="$REP" '{printf "%.3f\n", ($1 + $2) * 1000 / n}'
}

status=0
for s in tests/data/models/brilliant.scan-k400.json:k400 \
         tests/data/models/brilliant.scan-k800.json:k800 \
         "$T/jub.json:jubilee96_k2400"; do
    f=${s%:*} name=${s##*:} bc=1e9 bi=1e9
    for _ in $(seq "$RUNS"); do
        c=$(cpu_ms "$B/facet" correct "$f" -o "$T/out.json") || status=1
        i=$(cpu_ms "$B/facet" inspect --threads 1 "$f") || status=1
        bc=$(awk -v a="$c" -v b="$bc" 'BEGIN {print (a < b) ? a : b}')
        bi=$(awk -v a="$i" -v b="$bi" 'BEGIN {print (a < b) ? a : b}')
    done
    awk -v n="$name" -v c="$bc" -v i="$bi" 'BEGIN {
        printf "correct_vs_inspect_%s: correct %.2f ms, inspect %.2f ms, " \
               "ratio %.2f (target <= 5)\n", n, c, i, c / i }'
done
exit $status
