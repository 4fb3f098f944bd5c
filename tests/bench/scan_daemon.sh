#!/bin/bash
# scan_daemon.sh — the scanner intake through facetd, on mocked scanners
# (fsp-mock on umockdev): MB/s of model bytes from a bulk scanner into
# facetd (from the scan's first PROGRESS to the complete model, as facetd
# logs it; best of RUNS), the time facetd takes to parse and store a scan
# before it ACKs it, and the time from SCAN_DONE to the RESULT frame for
# the 400-contour sample with the inspect pipeline (best and median of
# RUNS). Prints "name: value unit" lines.
# Usage: tests/bench/scan_daemon.sh BUILD_DIR [RUNS]
set -u
B=${1:-build}
RUNS=${2:-5}
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root" || exit 1
# shellcheck source=../support/mock.sh
. tests/support/mock.sh
# shellcheck source=../support/mock_facetd.sh
. tests/support/mock_facetd.sh
[ -x "$B/fsp-mock" ] && [ -x "$B/facetd" ] || {
    echo "scan_daemon: $B/fsp-mock or $B/facetd not built"
    exit 1
}
MOCK_DIR=$(mktemp -d)
trap 'mock_stop; rm -rf "$MOCK_DIR"' EXIT
K400=$root/tests/data/models/brilliant.scan-k400.json
# a large valid model: a 60,000-gon prism, 6.4 MB as FMB1
awk -v n=60000 'BEGIN {
    pi = atan2(0, -1)
    for (z = 0; z <= 10; z += 10)
        for (i = 0; i < n; i++)
            printf "v %.9f %.9f %d\n", 50 * cos(2 * pi * i / n), 50 * sin(2 * pi * i / n), z
    printf "f"; for (i = n; i >= 1; i--) printf " %d", i; printf "\n"
    printf "f"; for (i = 1; i <= n; i++) printf " %d", n + i; printf "\n"
    for (i = 1; i <= n; i++) { j = i % n + 1; printf "f %d %d %d %d\n", i, j, n + j, n + i }
}' >"$MOCK_DIR/prism.obj"
"$B/facet" convert "$MOCK_DIR/prism.obj" "$MOCK_DIR/prism.fmb" || exit 1
echo '["inspect"]' >"$MOCK_DIR/pipeline.json"
mkdir -p "$MOCK_DIR/state"
mock_start "$B" || exit 1

# scans SERIAL MODEL FORMAT N: N scans, each awaited until ACKed
scans() {
    local i
    mock_cmd model "$1" "$2" "$3" >/dev/null || return 1
    for i in $(seq 1 "$4"); do
        local n
        n=$(count_lines "$MOCK_DIR/mock.log" "^event $1 done-acked")
        mock_cmd scan "$1" >/dev/null || return 1
        wait_count "$MOCK_DIR/mock.log" "^event $1 done-acked" $((n + 1)) 60 || return 1
    done
}
best() { sort -g | head -n 1; }
most() { sort -g | tail -n 1; }
median() { sort -g | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }

# throughput: paused workers, so only the intake runs
mock_facetd_start "$B" "$MOCK_DIR/state" --paused \
    --scanner-pipeline "$MOCK_DIR/pipeline.json" || exit 1
mock_cmd plug bulk SN-BENCH >/dev/null
wait_line "$FACETD_LOG" 'scanner SN-BENCH connected' 10 || exit 1
scans SN-BENCH "$MOCK_DIR/prism.fmb" fmb1 "$RUNS" || exit 1
rate() { sed -n "s/.*($1 bytes of $2,.*received in [0-9.]* ms (\([0-9.]*\) MB\/s).*/\1/p" "$FACETD_LOG"; }
stored() { sed -n "s/.*($1 bytes of $2,.*stored in \([0-9.]*\) ms).*/\1/p" "$FACETD_LOG"; }
size=$(stat -c %s "$MOCK_DIR/prism.fmb")
echo "facetd_intake_bulk_fmb1_6MB: $(rate "$size" fmb1 | most) MB/s"
echo "facetd_store_fmb1_6MB: $(stored "$size" fmb1 | best) ms"
scans SN-BENCH "$K400" json "$RUNS" || exit 1
size=$(stat -c %s "$K400")
echo "facetd_intake_bulk_k400_json: $(rate "$size" json | most) MB/s"
echo "facetd_parse_store_k400_json: $(sed -n "s/.*($size bytes of json,.*parsed in \([0-9.]*\) ms, stored in \([0-9.]*\) ms).*/\1 \2/p" "$FACETD_LOG" | awk '{print $1 + $2}' | best) ms"
mock_facetd_stop

# SCAN_DONE → RESULT with workers (a new store: the jobs queued above
# stay out of the way)
mkdir -p "$MOCK_DIR/state2"
mock_facetd_start "$B" "$MOCK_DIR/state2" --scanner-pipeline "$MOCK_DIR/pipeline.json" || exit 1
wait_line "$FACETD_LOG" 'scanner SN-BENCH connected' 10 || exit 1
for i in $(seq 1 "$RUNS"); do
    n=$(count_lines "$FACETD_LOG" 'RESULT \(succeeded\) to scanner SN-BENCH [0-9.]* ms')
    scans SN-BENCH "$K400" json 1 || exit 1
    wait_count "$FACETD_LOG" 'RESULT \(succeeded\) to scanner SN-BENCH [0-9.]* ms' $((n + 1)) 30 || exit 1
done
lat() { sed -n 's/.*RESULT (succeeded) to scanner SN-BENCH \([0-9.]*\) ms after.*/\1/p' "$FACETD_LOG"; }
echo "facetd_scan_done_to_result_k400_inspect_best: $(lat | best) ms"
echo "facetd_scan_done_to_result_k400_inspect_median: $(lat | median) ms"
mock_facetd_stop
