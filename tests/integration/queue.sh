#!/bin/bash
# queue.sh — the queue's behaviour over HTTP: idempotent submissions,
# priorities, cancel of queued and running jobs, an event stream that
# follows a job from queued to succeeded, a SIGHUP reload that unpauses
# the workers, and 200 concurrent submissions that all complete.
. "$(dirname "$0")/lib.sh" "$@"

conf="$T/facetd.conf"
printf '[Jobs]\nPaused=yes\nWorkers=1\nQueueSize=500\n[Server]\nKeepAlive=300ms\n' >"$conf"
start_facetd -c "$conf" || { not_ok "facetd starts"; finish; exit 1; }
expect_eq "workers start paused" 1 "$(metric facetd_workers_paused)"

# An event stream of a queued job stays open with keep-alive comments.
submit notch-cube.json
timeout $((2 * SLOW)) curl -s -N "$URL/v1/jobs/$ID/events" >"$T/ka"
check "an idle event stream sends keep-alive comments" grep -q '^: keep-alive' "$T/ka"
check "and the job's current state first" grep -q '"state":"queued"' "$T/ka"
req DELETE "/v1/jobs/$ID"
req DELETE "/v1/jobs/$ID"

# Idempotency.
f=$(body notch-cube.json '["inspect"]' '"label":"idem"')
post_json /v1/jobs "$f" -H 'Idempotency-Key: order-17'
first=$(jstr id)
expect_eq "the first submission with a key is 202" 202 "$CODE"
post_json /v1/jobs "$f" -H 'Idempotency-Key: order-17'
expect_eq "a retry with the same key and body is 202" 202 "$CODE"
expect_eq "the retry returns the first job" "$first" "$(jstr id)"
expect_eq "the retry is marked replayed" true "$(header Idempotent-Replayed)"
g=$(body l-prism.json)
post_json /v1/jobs "$g" -H 'Idempotency-Key: order-17'
expect_eq "the same key with another body is 422" 422 "$CODE"
check "the problem names the key" grep -q 'idempotency-key-reused' "$BODY"
req GET "/v1/jobs?status=queued"
expect_eq "only one job was queued for the key" 1 "$(grep -o '"label":"idem"' "$BODY" | wc -l)"

# Priorities: a high-priority job submitted last runs first.
submit notch-cube.json; normal1=$ID
hf=$(body notch-cube.json '["inspect"]' '"priority":"high"')
post_json /v1/jobs "$hf"; high=$(jstr id)
expect_eq "priority high is accepted" high "$(jstr priority)"

# Cancel a queued job.
submit l-prism.json; victim=$ID
req DELETE "/v1/jobs/$victim"
expect_eq "DELETE of a queued job is 200" "200 canceled" "$CODE $(jstr state)"
req DELETE "/v1/jobs/$victim"
expect_eq "DELETE of the canceled job removes it (204)" 204 "$CODE"

# An event stream opened while the job is queued follows it to the end,
# woken by the reload that unpauses the workers.
timeout $((20 * SLOW)) curl -s -N "$URL/v1/jobs/$normal1/events" >"$T/events" &
sse=$!
sleep 0.5
printf '[Jobs]\nPaused=no\nWorkers=1\nQueueSize=500\n' >"$conf"
kill -HUP "$PID"
wait_job "$normal1"
expect_eq "after the reload the queued job runs" succeeded "$STATE_OF"
wait $sse
check "the stream began with the queued state" grep -q '"state":"queued"' "$T/events"
check "the stream saw it succeed" grep -q '"state":"succeeded"' "$T/events"
expect_eq "the stream's events are state changes" \
    "$(grep -c '^event: state' "$T/events")" "$(grep -c '^event:' "$T/events")"
check "the log reports the reload" grep -q 'configuration reloaded' "$LOG"
expect_eq "workers are no longer paused" 0 "$(metric facetd_workers_paused)"
h_line=$(grep -n "job=$high started" "$LOG" | cut -d: -f1)
n_line=$(grep -n "job=$normal1 started" "$LOG" | cut -d: -f1)
check "the high-priority job started before the older normal one" \
    test -n "$h_line" -a -n "$n_line" -a "${h_line:-0}" -lt "${n_line:-0}"
wait_job "$first"
expect_eq "the idempotent job ran once and succeeded" "succeeded 1" "$STATE_OF $(jnum attempts)"

# A running job: DELETE asks it to stop. Inspection is fast, so the job
# may finish first; either way the answer is consistent.
submit brilliant.scan-k800.json
run_id=$ID
req DELETE "/v1/jobs/$run_id"
case "$CODE" in
    200) expect_eq "DELETE before it started cancels it" canceled "$(jstr state)" ;;
    202) wait_job "$run_id"
         check "a running job asked to stop ends canceled or succeeded" \
             grep -q '"state":"\(canceled\|succeeded\)"' "$BODY" ;;
    204) ok "the job had already finished: DELETE removed it" ;;
    *) not_ok "DELETE of a running job" "status $CODE" ;;
esac

# 200 concurrent submissions: every one is accepted and completes.
printf '%s\n' $(seq 200) | xargs -P 32 -I{} curl -s -o /dev/null \
    -w '%{http_code}\n' -H 'Content-Type: application/json' \
    --data-binary "@$f" "$URL/v1/jobs" >"$T/codes"
expect_eq "200 concurrent submissions are all 202" 200 "$(grep -c '^202$' "$T/codes")"
end=$((SECONDS + 60 * SLOW))
while [ $SECONDS -lt $end ]; do
    q=$(metric 'facetd_jobs{state="queued"}'); r=$(metric 'facetd_jobs{state="running"}')
    [ "$q" = 0 ] && [ "$r" = 0 ] && break
    sleep 0.2
done
check "the queue drains" test "$q" = 0 -a "$r" = 0
check "all of them succeeded" test "$(metric 'facetd_jobs{state="succeeded"}')" -ge 203
expect_eq "none failed" 0 "$(metric 'facetd_jobs{state="failed"}')"

# Retention: finished jobs older than RetentionAge go (applied on reload).
sleep 1.1
printf '[Jobs]\nWorkers=1\nQueueSize=500\n[Store]\nRetentionAge=1s\n' >"$conf"
kill -HUP "$PID"
for i in $(seq 50); do grep -q 'retention deleted' "$LOG" && break; sleep 0.1; done
check "retention deletes finished jobs past RetentionAge" grep -q 'retention deleted' "$LOG"
expect_eq "no finished job is left" 0 "$(metric 'facetd_jobs{state="succeeded"}')"
finish
