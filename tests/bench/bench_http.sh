#!/bin/bash
# bench_http.sh — facetd over HTTP on 127.0.0.1 (and nowhere else):
#  1. inspect jobs on brilliant.scan-k400.json, 32 concurrent clients, each
#     job a round trip of submit + long-poll to the end + fetch stats
#     (tests/tools/loadgen): jobs/s and job latency p50/p99;
#  2. GET /v1/jobs/{id} under 64 connections (wrk): requests/s, p99;
#  3. resident memory of facetd with 10,000 finished jobs in its store.
# Prints "name: value unit" lines. Usage: bench_http.sh BUILD_DIR
set -u
B=${1:-build}
SECS=${BENCH_SECONDS:-10}
T=$(mktemp -d /tmp/facetd-bench.XXXXXX)
trap 'kill "$PID" 2>/dev/null; wait "$PID" 2>/dev/null; rm -rf "$T"' EXIT
if [ ! -x "$B/facetd" ] || [ ! -x "$B/tools/loadgen" ]; then
    echo "bench_http: build $B/facetd and $B/tools/loadgen first (make bench)"
    exit 1
fi

start() {
    "$B/facetd" --listen 127.0.0.1:0 --state-dir "$T/state" --queue-size 100000 \
        --retention-bytes 64G --log-level notice "$@" >"$T/log" 2>&1 &
    PID=$!
    for i in $(seq 100); do
        PORT=$(sed -n 's|.*listening on http://127\.0\.0\.1:\([0-9]*\).*|\1|p' "$T/log")
        [ -n "$PORT" ] && break
        sleep 0.1
    done
    URL="http://127.0.0.1:$PORT"
}

body() {
    { printf '{"pipeline":["inspect"],"model":'; cat "tests/data/models/$1"; printf '}'; } >"$2"
}

echo "# $(nproc) CPUs; load average $(cut -d' ' -f1-3 /proc/loadavg)"
body brilliant.scan-k400.json "$T/k400.json"
body notch-cube.json "$T/small.json"

start
"$B/tools/loadgen" "$PORT" "$T/k400.json" 32 2 >/dev/null # warm-up
cpu() { awk '{print $14 + $15}' "/proc/$PID/stat"; }
c0=$(cpu)
"$B/tools/loadgen" "$PORT" "$T/k400.json" 32 "$SECS" >"$T/flow"
c1=$(cpu)
njobs=$(sed -n 's/^jobs: //p' "$T/flow")
jobs_s=$(sed -n 's/^jobs_per_s: //p' "$T/flow")
echo "inspect_k400_jobs_per_s (32 clients, submit+wait+stats): $jobs_s jobs/s"
echo "inspect_k400_job_p50: $(sed -n 's/^job_p50_ms: //p' "$T/flow") ms"
echo "inspect_k400_job_p99: $(sed -n 's/^job_p99_ms: //p' "$T/flow") ms"
echo "inspect_k400_errors: $(sed -n 's/^errors: //p' "$T/flow") count"
# CPU time facetd spent per job, independent of what else the machine runs.
per_job=$(awk -v c=$((c1 - c0)) -v n="$njobs" -v hz="$(getconf CLK_TCK)" \
    'BEGIN {printf "%.2f", n ? c * 1000 / hz / n : 0}')
echo "inspect_k400_facetd_cpu_per_job: $per_job ms"
# against parsing and inspecting the same model in-process (target <= 1.5)
if [ -x "$B/bench/bench_inspect" ]; then
    inproc=$("$B/bench/bench_inspect" --parse-inspect-cpu)
    echo "inspect_k400_facetd_cpu_vs_in_process: $(awk -v a="$per_job" -v b="$inproc" \
        'BEGIN {printf "%.2f", (b > 0 ? a / b : 0)}') (facetd $per_job ms, in-process parse+inspect $inproc ms CPU)"
fi

id=$(curl -s "$URL/v1/jobs?limit=1" | grep -o '"id":"[0-9A-Z]*"' | head -n 1 | cut -d'"' -f4)
if command -v wrk >/dev/null; then
    wrk -t2 -c64 -d"${SECS}s" --latency "$URL/v1/jobs/$id" >"$T/wrk" 2>&1
    echo "get_job_requests_per_s (64 connections): $(awk '/^Requests\/sec/ {print $2}' "$T/wrk") req/s"
    echo "get_job_p50: $(awk '$1 == "50%" {print $2}' "$T/wrk")"
    echo "get_job_p99: $(awk '$1 == "99%" {print $2}' "$T/wrk")"
else
    echo "get_job: wrk is not installed (make deps installs it)"
fi

# 10,000 finished jobs (small models), then the daemon's resident set.
have=$(curl -s "$URL/metrics" | awk '$1 == "facetd_jobs{state=\"succeeded\"}" {print $2}')
"$B/tools/loadgen" "$PORT" "$T/small.json" 16 300 $((10000 - have)) submit >"$T/fill"
for i in $(seq 600); do
    q=$(curl -s "$URL/metrics" | awk '$1 == "facetd_queue_depth" {print $2}')
    [ "$q" = 0 ] && break
    sleep 0.2
done
done_jobs=$(curl -s "$URL/metrics" | awk '$1 == "facetd_jobs{state=\"succeeded\"}" {print $2}')
curl -s "$URL/v1/jobs?limit=1000" >/dev/null
echo "small_submit_jobs_per_s (16 clients, submit only): $(sed -n 's/^jobs_per_s: //p' "$T/fill") jobs/s"
echo "finished_jobs_in_store: $done_jobs jobs"
echo "rss_with_finished_jobs: $(awk '/^VmRSS/ {printf "%.1f", $2 / 1024}' /proc/$PID/status) MB"
echo "store_bytes: $(curl -s "$URL/metrics" | awk '$1 == "facetd_store_bytes" {printf "%.1f", $2 / 1048576}') MB"
