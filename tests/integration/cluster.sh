# cluster.sh — three facetd nodes sharing one PostgreSQL store: a
# throwaway database (initdb into a temporary directory as an unprivileged
# user, a free loopback port, scram passwords through a libpq password
# file), 60 jobs round-robin over the nodes, one node killed with -9 while
# it runs a job (that job and every other accepted one succeed on the
# survivors with facet run's result), an idempotent retry answered by
# another node, and the database stopped and started (503, then
# recovery). Skipped when the PostgreSQL 15 binaries are missing.
. "$(dirname "$0")/lib.sh" "$@"

# no request may hang the test (a frozen node, a database going away)
export CURL_HOME=$T
echo 'max-time = 30' >"$T/.curlrc"
. tests/support/pg.sh
if ! pg_available; then
    skip "PostgreSQL 15 is not installed ($PGBIN): make deps installs postgresql-15"
    finish
    exit
fi
trap 'cleanup; pg_cleanup' EXIT
if ! pg_init "$T" off || ! pg_start; then
    not_ok "a throwaway PostgreSQL starts" "$(tail -n 5 "$PGD/initdb.log" "$PGD/log" 2>/dev/null)"
    finish
    exit
fi
ok "a throwaway PostgreSQL runs on 127.0.0.1:$PGPORT"
DB=$PG_URL

NODE_FLAGS=(--workers 1 --store-url "$DB" --store-password-file "$T/pgpass"
    --job-lease 2s --no-scanners)
check "a password in the URL is refused" \
    bash -c "! '$FACETD' --listen 127.0.0.1:0 --state-dir '$T' --no-scanners \
        --store-url 'postgresql://facetd:secret-pw@127.0.0.1:$PGPORT/postgres' >'$T/pw.log' 2>&1 && grep -q 'carries a password' '$T/pw.log'"
# three nodes starting at once: the schema is made once
declare -a NURL NPID NLOG
# the nodes start paused, so that all 60 jobs are queued before any runs
for i in 1 2 3; do
    printf '[Jobs]\nPaused=yes\n' >"$T/node$i.conf"
    NLOG[$i]=$T/node$i.log
    "$FACETD" -c "$T/node$i.conf" --listen 127.0.0.1:0 --state-dir "$T/state$i" "${NODE_FLAGS[@]}" \
        --node-name "node$i" >"${NLOG[$i]}" 2>&1 &
    NPID[$i]=$!
    PIDS+=("$!")
done
up=0
for i in 1 2 3; do
    for _ in $(seq 1 $((100 * SLOW))); do
        PORT=$(sed -n 's|.*listening on http://127\.0\.0\.1:\([0-9]*\).*|\1|p' "${NLOG[$i]}" | head -n 1)
        [ -n "$PORT" ] && break
        sleep 0.1
    done
    NURL[$i]="http://127.0.0.1:$PORT"
    for _ in $(seq 1 $((50 * SLOW))); do
        [ "$(curl -s -o /dev/null -w '%{http_code}' "${NURL[$i]}/readyz")" = 200 ] &&
            { up=$((up + 1)); break; }
        sleep 0.1
    done
done
LOG=${NLOG[1]}
expect_eq "three nodes started together are ready" 3 "$up"
expect_eq "the schema was created once" 1 \
    "$(cat "${NLOG[@]}" | grep -c 'schema at version 1')"

"$BUILD/facet" run <(echo '"auto"') "$MODELS/brilliant.scan-k100.json" \
    -o "$T/offline.json" 2>/dev/null
f=$(body brilliant.scan-k100.json '"auto"')
t0=$(date +%s%N)
ids=()
bad=0
for k in $(seq 0 59); do
    i=$((k % 3 + 1))
    CODE=$(curl -s -o "$T/sub" -w '%{http_code}' -H 'Content-Type: application/json' \
        --data-binary "@$f" "${NURL[$i]}/v1/jobs")
    if [ "$CODE" = 202 ]; then ids+=("$(jstr id "$T/sub")"); else bad=$((bad + 1)); fi
done
expect_eq "60 jobs submitted round-robin are accepted" "60/0" "${#ids[@]}/$bad"
# node 3 alone runs first: with all three claiming from one queue of
# 25 ms jobs, node 3 could run too few of them, too briefly, for the
# loop below to find one running (a failure seen on a loaded machine);
# the others start once it is dead
printf '[Jobs]\nPaused=no\n' >"$T/node3.conf"
kill -HUP "${NPID[3]}"
t0=$(date +%s%N)

# kill node 3 while it runs a job: frozen first, so that the job is
# known to be still running when the -9 lands — whichever job node 3 is
# running once frozen (the one seen before may have finished meanwhile)
node3_running() {
    curl -s "${NURL[1]}/v1/jobs?status=running&limit=100" |
        jq -r '.jobs[] | select(.node == "node3") | .id' | head -n 1
}
victim=""
for _ in $(seq 1 200); do
    if [ -n "$(node3_running)" ]; then
        kill -STOP "${NPID[3]}"
        victim=$(node3_running)
        [ -n "$victim" ] && break
        kill -CONT "${NPID[3]}"
    fi
    sleep 0.02
done
kill -9 "${NPID[3]}"
tk=$(date +%s%N)
check "node 3 was running a job when killed with -9" test -n "$victim"
for i in 1 2; do
    printf '[Jobs]\nPaused=no\n' >"$T/node$i.conf"
    kill -HUP "${NPID[$i]}"
done

URL=${NURL[1]}
wait_job "$victim" 30
req GET "/v1/jobs/$victim"
expect_eq "the killed node's job succeeds on another node" \
    "succeeded yes" "$(jstr state) $( [ "$(jstr node)" != node3 ] && echo yes)"
check "it ran a second time" test "$(jnum attempts)" -ge 2
fin=$(jq -r '.finished // empty' "$BODY")
[ -n "$fin" ] && echo "# death to finished elsewhere: $(( ($(date -d "$fin" +%s%N) - tk) / 1000000 )) ms (lease 2 s)"

same=0 states=""
for id in "${ids[@]}"; do
    wait_job "$id" 60
    [ "$STATE_OF" = succeeded ] || states="$states $id:$STATE_OF"
    curl -s -o "$T/served.json" "${NURL[2]}/v1/jobs/$id/model?format=json"
    cmp -s "$T/served.json" "$T/offline.json" && same=$((same + 1))
done
t1=$(date +%s%N)
expect_eq "every accepted job succeeded" "" "$states"
expect_eq "every result equals facet run's" 60 "$same"
echo "# 60 jobs through 3 nodes (one killed): $(( (t1 - t0) / 1000000 )) ms"
req GET "/v1/jobs?status=succeeded&limit=100"
check "the survivors ran the rest" \
    test "$(jq '[.jobs[] | select(.node == "node1" or .node == "node2")] | length' "$BODY")" -ge 40

# fencing: node 2 freezes mid-run past its lease, node 1 runs the job
# again; when node 2 thaws its result is refused, so the job keeps one
setpaused() { printf '[Jobs]\nPaused=%s\n' "$2" >"$T/node$1.conf"; kill -HUP "${NPID[$1]}"; }
heavy=$(body brilliant.scan-k800.json '["auto","auto","auto","auto"]')
frozen=""
for _ in 1 2 3 4 5; do
    setpaused 1 yes
    URL=${NURL[2]}
    post_json /v1/jobs "$heavy"
    ID=$(jstr id)
    URL=${NURL[1]} # node 2 will not answer while frozen
    for _ in $(seq 1 200); do
        req GET "/v1/jobs/$ID"
        [ "$(jstr state)" != queued ] && break
        sleep 0.01
    done
    if [ "$(jstr state)" = running ]; then
        kill -STOP "${NPID[2]}"
        req GET "/v1/jobs/$ID"
        if [ "$(jstr state)" = running ]; then frozen=$ID; break; fi
        kill -CONT "${NPID[2]}"
    fi
    setpaused 1 no
    wait_job "$ID" 30
done
setpaused 1 no
check "node 2 froze while running a job" test -n "$frozen"
URL=${NURL[1]}
wait_job "$frozen" 30
kill -CONT "${NPID[2]}"
expect_eq "the frozen node's job succeeds on node 1 once the lease ran out" \
    "succeeded node1" "$STATE_OF $(jstr node)"
v1=$(jnum version)
for _ in $(seq 1 50); do
    grep -q "job=$frozen.*\(lease on\|outcome not recorded\)" "${NLOG[2]}" && break
    sleep 0.1
done
check "node 2, thawed, is told its lease is gone" \
    grep -q "job=$frozen.*\(lease on\|outcome not recorded\)" "${NLOG[2]}"
req GET "/v1/jobs/$frozen"
expect_eq "its late result was refused: the job is unchanged" \
    "succeeded node1 $v1" "$(jstr state) $(jstr node) $(jnum version)"
check "node 2 logged no success for it" \
    bash -c "! grep -q 'job=$frozen succeeded' '${NLOG[2]}'"

# an idempotent retry sent to another node returns the same job
g=$(body notch-cube.json '["inspect"]')
post_json /v1/jobs "$g" -H 'Idempotency-Key: cluster-7'
first=$(jstr id)
URL=${NURL[2]}
post_json /v1/jobs "$g" -H 'Idempotency-Key: cluster-7'
expect_eq "an idempotent retry on another node returns the same job" \
    "202 $first true" "$CODE $(jstr id) $(header Idempotent-Replayed)"

wait_job "$first" 30
curl -s -o "$T/a.obj" "${NURL[1]}/v1/jobs/$first/model?format=obj"
curl -s -o "$T/b.obj" "${NURL[2]}/v1/jobs/$first/model?format=obj"
check "every node serves a job's model in another format" \
    bash -c "[ -s '$T/a.obj' ] && cmp -s '$T/a.obj' '$T/b.obj' && grep -q '^f ' '$T/a.obj'"
req DELETE "/v1/jobs/$first"
del=$CODE
URL=${NURL[1]}
req GET "/v1/jobs/$first"
expect_eq "a job deleted on one node is gone on the other" "204 404" "$del $CODE"

# a waiter on node 2 hears a job node 1 queued and node 1 ran
URL=${NURL[1]}
submit l-prism.json
req GET "/v1/jobs/$ID" # warm
URL=${NURL[2]}
req GET "/v1/jobs/$ID?wait=20"
expect_eq "?wait= on another node sees the job end" succeeded "$(jstr state)"
curl -s -N --max-time 10 "${NURL[2]}/v1/jobs/$ID/events" >"$T/events" 2>/dev/null
check "its event stream on another node ends with the final state" \
    grep -q 'succeeded' "$T/events"
curl -s "${NURL[2]}/metrics" >"$T/metrics"
check "/metrics has the shared queue depth and names the node" \
    grep -q '^facetd_queue_depth 0' "$T/metrics" &&
    grep -q '^facetd_cluster_node{node="node2"} 1' "$T/metrics"

# the database stops: 503, then it comes back and so do the nodes
pg_stop
sleep 0.5
URL=${NURL[1]}
req GET /readyz
expect_eq "/readyz is 503 while the database is down" 503 "$CODE"
post_json /v1/jobs "$g"
expect_eq "a submission is 503 with Retry-After while it is down" \
    "503 yes" "$CODE $( [ -n "$(header Retry-After)" ] && echo yes)"
pg_start
ready=0
for _ in $(seq 1 100); do
    [ "$(curl -s -o /dev/null -w '%{http_code}' "${NURL[1]}/readyz")" = 200 ] &&
        [ "$(curl -s -o /dev/null -w '%{http_code}' "${NURL[2]}/readyz")" = 200 ] &&
        { ready=1; break; }
    sleep 0.1
done
expect_eq "both nodes are ready again once the database is back" 1 "$ready"
# a client honours Retry-After: a node may still be reconnecting
for _ in 1 2 3 4 5; do
    submit brilliant.scan-k100.json '"auto"'
    [ "$CODE" = 503 ] || break
    sleep "$(header Retry-After)"
done
code=$CODE
wait_job "$ID" 30
expect_eq "a job submitted after the outage succeeds" "202 succeeded" "$code $STATE_OF"
# the queue bound is the cluster's queue; a used key still answers
printf '[Jobs]\nPaused=yes\nQueueSize=1\n' >"$T/node1.conf"
kill -HUP "${NPID[1]}"
setpaused 2 yes
sleep 0.5
URL=${NURL[1]}
post_json /v1/jobs "$g" -H 'Idempotency-Key: cluster-full'
kept=$(jstr id)
post_json /v1/jobs "$g"
full=$CODE
post_json /v1/jobs "$g" -H 'Idempotency-Key: cluster-full'
expect_eq "a full shared queue is 503; a retry of a queued key still returns its job" \
    "503 202 $kept" "$full $CODE $(jstr id)"
setpaused 1 no
setpaused 2 no
wait_job "$kept" 30
expect_eq "the job kept in the full queue runs once unpaused" succeeded "$STATE_OF"
# KEEP=1 keeps the database directory with the nodes' logs in it
[ -n "${KEEP:-}" ] && cp "${NLOG[@]}" "$PGD/"
finish
