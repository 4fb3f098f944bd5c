#!/bin/bash
# scan_intake.sh — intake throughput: MB/s of model bytes from a mocked
# scanner (fsp-mock on umockdev) through unmodified libusb (bulk) and
# hidapi (hidraw) into the scanner library, measured by scan_watch from
# the scan's first PROGRESS to its completion (best of RUNS scans).
# Prints "name: value unit" lines.
# Usage: tests/bench/scan_intake.sh BUILD_DIR [RUNS]
set -u
B=${1:-build}
RUNS=${2:-5}
root=$(cd "$(dirname "$0")/../.." && pwd)
# shellcheck source=../support/mock.sh
. "$root/tests/support/mock.sh"
[ -x "$B/fsp-mock" ] && [ -x "$B/tools/scan_watch" ] || {
    echo "scan_intake: $B/fsp-mock or $B/tools/scan_watch not built"
    exit 1
}
MOCK_DIR=$(mktemp -d)
trap 'exec 7>&- 2>/dev/null; mock_stop; rm -rf "$MOCK_DIR"' EXIT
WATCH=$MOCK_DIR/watch.log
head -c $((16 << 20)) /dev/urandom >"$MOCK_DIR/big.model"
head -c $((1 << 20)) /dev/urandom >"$MOCK_DIR/small.model"
mkfifo "$MOCK_DIR/watch.in"
exec 7<>"$MOCK_DIR/watch.in"
mock_start "$B" -- sh -c "exec '$B/tools/scan_watch' <'$MOCK_DIR/watch.in' \
    >'$WATCH' 2>'$MOCK_DIR/watch.err'" || exit 1
wait_line "$WATCH" '^started' 10 || exit 1

# best SERIAL MODEL RUNS: scans RUNS times and prints the best MB/s
best() {
    local serial=$1 model=$2 runs=$3 i
    mock_cmd model "$serial" "$model" >/dev/null || return 1
    for i in $(seq 1 "$runs"); do
        mock_cmd scan "$serial" >/dev/null || return 1
        wait_count "$MOCK_DIR/mock.log" "^event $serial done-acked" "$i" 120 ||
            return 1
    done
    grep -E "^scan $serial " "$WATCH" | sed 's/.*mbps=\([0-9.]*\).*/\1/' |
        sort -g | tail -n 1
}

mock_cmd plug bulk SN-BENCH-B >/dev/null &&
    wait_line "$WATCH" '^device SN-BENCH-B ' 10 || exit 1
echo "scan_intake_bulk_16MiB: $(best SN-BENCH-B "$MOCK_DIR/big.model" "$RUNS") MB/s"
mock_cmd plug hid SN-BENCH-H >/dev/null &&
    wait_line "$WATCH" '^device SN-BENCH-H ' 10 || exit 1
echo "scan_intake_hid_1MiB: $(best SN-BENCH-H "$MOCK_DIR/small.model" 2) MB/s"
