#!/bin/bash
# cluster.sh — facetd nodes on one PostgreSQL store (docs/cluster.md),
# all on this machine, database fsync on:
#  1. jobs/s through 1 node (SQLite for reference, then PostgreSQL) and
#     through 3 nodes: inspect jobs on a small model (the store's cost
#     dominates) and "auto" on a 1,059-facet scan (the kernels' cost
#     dominates), closed-loop clients (tests/tools/loadgen) spread over
#     the nodes, each job a submit + long-poll + stats round trip;
#  2. claim latency: from a job's commit to a worker starting it (its
#     created and started times), one job at a time, submitted round-robin
#     to 3 nodes with idle workers: p50, p99;
#  3. a node killed with -9 mid-job: time until another node has finished
#     that job, with the default 30 s lease.
# Prints "name: value unit" lines. Usage: cluster.sh BUILD_DIR
set -u
B=${1:-build}
SECS=${BENCH_SECONDS:-10}
. tests/support/pg.sh
if ! pg_available; then
    echo "cluster: PostgreSQL 15 is not installed ($PGBIN): make deps"
    exit 0
fi
if [ ! -x "$B/facetd" ] || [ ! -x "$B/tools/loadgen" ]; then
    echo "cluster: build $B/facetd and $B/tools/loadgen first (make bench)"
    exit 1
fi
T=$(mktemp -d -t facetd-bench.XXXXXX)
PIDS=()
stop_nodes() {
    local p
    for p in "${PIDS[@]}"; do kill -CONT "$p" 2>/dev/null; kill "$p" 2>/dev/null; done
    for p in "${PIDS[@]}"; do wait "$p" 2>/dev/null; done
    PIDS=()
}
trap 'stop_nodes; pg_cleanup; rm -rf "$T"' EXIT
pg_init "$T" on && pg_start || { echo "cluster: PostgreSQL did not start"; exit 1; }

declare -a PORTS NPID
# nodes N [FLAGS...]: N fresh nodes on the database (emptied first).
nodes() {
    local n=$1 i k port
    shift
    stop_nodes
    PGPASSFILE=$PG_PASSFILE psql -q -h 127.0.0.1 -p "$PGPORT" -U facetd -d postgres \
        -c 'DROP TABLE IF EXISTS facetd_blobs, facetd_jobs, facetd_meta, facetd_schema CASCADE; DROP SEQUENCE IF EXISTS facetd_claim_token; DROP FUNCTION IF EXISTS facetd_notify' \
        >/dev/null 2>&1 </dev/null
    for i in $(seq 1 "$n"); do
        "$B/facetd" --listen 127.0.0.1:0 --state-dir "$T/s$i" --no-scanners \
            --queue-size 100000 --log-level notice --node-name "n$i" "$@" \
            >"$T/log$i" 2>&1 &
        NPID[$i]=$!
        PIDS+=("$!")
    done
    for i in $(seq 1 "$n"); do
        port=""
        for k in $(seq 100); do
            port=$(sed -n 's|.*listening on http://127\.0\.0\.1:\([0-9]*\).*|\1|p' "$T/log$i")
            [ -n "$port" ] && break
            sleep 0.1
        done
        PORTS[$i]=$port
    done
}
pgflags() { echo --store-url "$PG_URL" --store-password-file "$PG_PASSFILE" "$@"; }

body() {
    { printf '{"pipeline":%s,"model":' "$2"; cat "tests/data/models/$1"; printf '}'; } >"$3"
}
body notch-cube.json '["inspect"]' "$T/small.json"
body brilliant.scan-k100.json '"auto"' "$T/auto.json"

# flow N FILE CLIENTS: loadgen on each of the N nodes for SECS; sums.
flow() {
    local n=$1 f=$2 c=$3 i gens=()
    for i in $(seq 1 "$n"); do
        "$B/tools/loadgen" "${PORTS[$i]}" "$f" "$c" "$SECS" >"$T/flow$i" &
        gens+=("$!")
    done
    wait "${gens[@]}"
    awk '/^jobs_per_s:/ {s += $2} /^job_p50_ms:/ {p = p " " $2} /^job_p99_ms:/ {q = q " " $2}
         /^errors:/ {e += $2}
         END {printf "%.1f jobs/s (round trip p50%s ms, p99%s ms, errors %d)\n", s, p, q, e}' \
        "$T"/flow[1-9]
    rm -f "$T"/flow[1-9]
}

echo "# $(nproc) CPUs; load average $(cut -d' ' -f1-3 /proc/loadavg)"
nodes 1 --workers 2
echo "sqlite_1_node_inspect_small: $(flow 1 "$T/small.json" 8)"
echo "sqlite_1_node_auto_k100: $(flow 1 "$T/auto.json" 4)"
nodes 1 --workers 2 $(pgflags)
echo "pg_1_node_inspect_small: $(flow 1 "$T/small.json" 8)"
echo "pg_1_node_auto_k100: $(flow 1 "$T/auto.json" 4)"
nodes 3 --workers 2 $(pgflags)
echo "pg_3_nodes_inspect_small: $(flow 3 "$T/small.json" 3)"
echo "pg_3_nodes_auto_k100: $(flow 3 "$T/auto.json" 2)"

# claim latency: one job at a time, round-robin, idle workers
nodes 3 --workers 1 $(pgflags)
for k in $(seq 0 199); do
    i=$((k % 3 + 1))
    id=$(curl -s -H 'Content-Type: application/json' --data-binary "@$T/small.json" \
        "http://127.0.0.1:${PORTS[$i]}/v1/jobs" | jq -r .id)
    curl -s -o /dev/null "http://127.0.0.1:${PORTS[$(( (k + 1) % 3 + 1))]}/v1/jobs/$id?wait=10"
done
curl -s "http://127.0.0.1:${PORTS[1]}/v1/jobs?limit=200" |
    jq -r '.jobs[] | def ms(t): (t[0:19] + "Z" | fromdate) * 1000 + (t[20:23] | tonumber);
           ms(.started) - ms(.created)' | sort -n >"$T/lat"
awk '{v[NR] = $1} END {printf "claim_latency_p50: %d ms\nclaim_latency_p99: %d ms (n %d, commit to start, ms clock)\n",
     v[int(NR * 0.5 + 0.5)], v[int(NR * 0.99 + 0.5)], NR}' "$T/lat"

# a node killed mid-job, default lease
nodes 2 --workers 1 $(pgflags)
heavy=$T/heavy.json
body brilliant.scan-k800.json '["auto","auto","auto","auto"]' "$heavy"
victim=""
for _ in 1 2 3 4 5 6 7 8 9 10; do
    id=$(curl -s -H 'Content-Type: application/json' --data-binary "@$heavy" \
        "http://127.0.0.1:${PORTS[1]}/v1/jobs" | jq -r .id)
    for _ in $(seq 100); do
        j=$(curl -s "http://127.0.0.1:${PORTS[2]}/v1/jobs/$id")
        [ "$(jq -r .state <<<"$j")" != queued ] && break
        sleep 0.01
    done
    if [ "$(jq -r .node <<<"$j")" = n1 ]; then
        kill -STOP "${NPID[1]}"
        if [ "$(curl -s "http://127.0.0.1:${PORTS[2]}/v1/jobs/$id" | jq -r .state)" = running ]; then
            victim=$id
            break
        fi
        kill -CONT "${NPID[1]}"
    fi
    curl -s -o /dev/null "http://127.0.0.1:${PORTS[2]}/v1/jobs/$id?wait=20"
done
if [ -n "$victim" ]; then
    kill -9 "${NPID[1]}"
    tk=$(date +%s%N)
    j=$(curl -s "http://127.0.0.1:${PORTS[2]}/v1/jobs/$victim?wait=60")
    fin=$(jq -r '.finished // empty' <<<"$j")
    echo "node_death_to_job_finished_elsewhere: $(( ($(date -d "$fin" +%s%N) - tk) / 1000000 )) ms (lease 30 s; job $(jq -r .state <<<"$j") on $(jq -r .node <<<"$j"), attempt $(jq -r .attempts <<<"$j"))"
else
    echo "node_death_to_job_finished_elsewhere: no job caught running on node 1"
fi
