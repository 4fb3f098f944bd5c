#!/bin/bash
# restart.sh — durability: facetd is killed with SIGKILL in the middle of
# a burst of submissions and job runs; after a restart on the same state
# directory every job that got a 202 is still there and completes (jobs
# that were running are queued again). Then a graceful SIGTERM with work
# queued leaves that work queued for the next start.
. "$(dirname "$0")/lib.sh" "$@"

start_facetd --workers 1 || { not_ok "facetd starts"; finish; exit 1; }
f=$(body brilliant.scan-k400.json)
mkdir "$T/r"
# Each submission leaves "CODE" in r/N.code and the body in r/N.
printf '%s\n' $(seq 120) | xargs -P 8 -I{} sh -c \
    "curl -s -o '$T/r/{}' -w '%{http_code}' -H 'Content-Type: application/json' --data-binary '@$f' '$URL/v1/jobs' >'$T/r/{}.code' 2>/dev/null" &
load=$!
# Kill once a few jobs were accepted, while the burst goes on.
for i in $(seq $((100 * SLOW))); do
    [ "$(grep -l 202 "$T"/r/*.code 2>/dev/null | wc -l)" -ge 5 ] && break
    sleep 0.05
done
kill -KILL "$PID"
wait "$PID" 2>/dev/null
wait $load
# the jobs the killed facetd had started and not logged as ended: the
# store records an outcome before the log line, so a kill in between
# leaves a finished job that is rightly not run again
LOG1=$LOG
unended=$(sed -n 's/.* job=\([0-9A-Z]*\) started (attempt.*/\1/p' "$LOG1" | sort -u |
    while read -r id; do
        grep -qE "job=$id (succeeded|failed|canceled)" "$LOG1" || echo "$id"
    done)
accepted=""
for c in "$T"/r/*.code; do
    [ "$(cat "$c")" = 202 ] && accepted="$accepted $(jstr id "${c%.code}")"
done
n=$(echo $accepted | wc -w)
check "some submissions were accepted before the kill ($n)" test "$n" -gt 0
check "some were cut off by the kill" test "$n" -lt 120

STATE_KEEP=1 start_facetd --workers 2 || { not_ok "facetd restarts"; finish; exit 1; }
ok "facetd restarts on the same store"
missing=0
for id in $accepted; do
    req GET "/v1/jobs/$id"
    [ "$CODE" = 200 ] || missing=$((missing + 1))
done
expect_eq "every accepted job is still in the store" 0 "$missing"
notdone=0
for id in $accepted; do
    wait_job "$id" 60
    [ "$STATE_OF" = succeeded ] || notdone=$((notdone + 1))
done
expect_eq "every accepted job completes after the restart" 0 "$notdone"
# each unended job is either run again or was finished in the store
running=0 finished=0
for id in $unended; do
    if grep -q "job=$id started (attempt 2" "$LOG"; then
        running=$((running + 1))
    else
        req GET "/v1/jobs/$id"
        [ "$(jnum attempts)" = 1 ] && [ "$(jstr state)" = succeeded ] &&
            finished=$((finished + 1))
    fi
done
expect_eq "each job unended at the kill ran again or had finished" \
    "$(echo $unended | wc -w)" $((running + finished))
if [ "$running" -gt 0 ]; then
    check "the $running job(s) running at the kill were queued again" \
        grep -q "^.*$running job(s) interrupted by the last stop queued again" "$LOG"
else
    check "no job was queued again (none was running at the kill)" \
        sh -c "! grep -q 'interrupted by the last stop' '$LOG'"
fi

# Graceful stop with queued work: it stays queued, and runs after a start.
req GET /metrics
stop_facetd
STATE_KEEP=1 start_facetd --paused || { not_ok "facetd starts paused"; finish; exit 1; }
for i in 1 2 3; do submit notch-cube.json; done
last=$ID
curl -s -o "$T/w" -w '%{http_code}' "$URL/v1/jobs/$last?wait=60" >"$T/wcode" &
w=$!
curl -s -N "$URL/v1/jobs/$last/events" >"$T/ev" &
e=$!
for i in $(seq 50); do [ "$(metric facetd_http_waiting_clients)" = 2 ] && break; sleep 0.1; done
expect_eq "two clients wait on the queued job" 2 "$(metric facetd_http_waiting_clients)"
stop_facetd
expect_eq "SIGTERM with queued jobs and waiting clients exits 0" 0 "$STATUS"
wait $w $e
expect_eq "the long-poll is answered at shutdown with the job" "200 queued" "$(cat "$T/wcode") $(jstr state "$T/w")"
check "the event stream ends at shutdown after the queued state" grep -q '"state":"queued"' "$T/ev"
STATE_KEEP=1 start_facetd --workers 1 || { not_ok "facetd starts again"; finish; exit 1; }
wait_job "$last"
expect_eq "jobs queued at a graceful stop run after the next start" succeeded "$STATE_OF"
finish
