#!/bin/sh
# Runs every libFuzzer target in FUZZ_DIR for SECONDS each, on a corpus
# kept in FUZZ_DIR/corpus/NAME (seeded from tests/fuzz/seeds/NAME when it
# exists), and prints the executions and the coverage each run reached.
# Usage: tests/fuzz/run.sh FUZZ_DIR SECONDS
set -u
dir=${1:-build/fuzz}
secs=${2:-60}
status=0
for f in "$dir"/fuzz_*; do
    [ -x "$f" ] || continue
    name=$(basename "$f")
    corpus="$dir/corpus/$name"
    mkdir -p "$corpus"
    seeds="tests/fuzz/seeds/$name"
    [ -d "$seeds" ] || seeds=""
    log="$dir/$name.log"
    echo "== $name: ${secs} s"
    # shellcheck disable=SC2086
    "$f" -max_total_time="$secs" -print_final_stats=1 -timeout=10 \
        -rss_limit_mb=2048 -artifact_prefix="$dir/$name-" \
        "$corpus" $seeds >"$log" 2>&1
    rc=$?
    grep -E '^stat::number_of_executed_units|^stat::average_exec_per_sec|^stat::peak_rss_mb' "$log"
    grep -E '^#[0-9]+.*(DONE|cov:)' "$log" | tail -n 1
    if [ $rc -ne 0 ]; then
        echo "$name: FAILED (exit $rc), see $log"
        grep -E 'ERROR|SUMMARY' "$log" | head -n 5
        status=1
    fi
done
exit $status
