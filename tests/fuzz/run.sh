#!/bin/sh
# Runs every libFuzzer target in FUZZ_DIR for SECONDS each (or until RUNS
# executions when RUNS is given: then SECONDS is only an upper bound), on
# a corpus kept in FUZZ_DIR/corpus/NAME (seeded from tests/fuzz/seeds/NAME
# when it exists), and prints the executions, the time and the coverage
# each run reached.
# Usage: tests/fuzz/run.sh FUZZ_DIR SECONDS [RUNS [TARGET...]]
set -u
dir=${1:-build/fuzz}
secs=${2:-60}
runs=${3:-}
[ $# -gt 3 ] && shift 3 || set --
status=0
targets=${*:-$(cd "$dir" && ls -d fuzz_* 2>/dev/null)}
for name in $targets; do
    f="$dir/$name"
    [ -x "$f" ] || continue
    corpus="$dir/corpus/$name"
    mkdir -p "$corpus"
    seeds="tests/fuzz/seeds/$name"
    [ -d "$seeds" ] || seeds=""
    log="$dir/$name.log"
    echo "== $name: ${runs:+$runs executions, at most }${secs} s"
    start=$(date +%s)
    # shellcheck disable=SC2086
    "$f" -max_total_time="$secs" ${runs:+-runs=$runs} -print_final_stats=1 -timeout=10 \
        -rss_limit_mb=2048 -artifact_prefix="$dir/$name-" \
        "$corpus" $seeds >"$log" 2>&1
    rc=$?
    echo "wall: $(( $(date +%s) - start )) s"
    grep -E '^stat::number_of_executed_units|^stat::average_exec_per_sec|^stat::peak_rss_mb' "$log"
    grep -E '^#[0-9]+.*(DONE|cov:)' "$log" | tail -n 1
    if [ $rc -ne 0 ]; then
        echo "$name: FAILED (exit $rc), see $log"
        grep -E 'ERROR|SUMMARY' "$log" | head -n 5
        status=1
    fi
done
exit $status
