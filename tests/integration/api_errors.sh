#!/bin/bash
# api_errors.sh — every error the API gives, each as an RFC 9457 problem
# (application/problem+json with type, title, status, detail): 400
# malformed JSON with line and column, 400 bad arguments, 401 without the
# token, 404, 405 with Allow, 409 no result yet, 413 body too large (by
# Content-Length and by a chunked body), 415, 422 with every error listed
# by place, 429 too many waiting clients, 503 queue full with Retry-After.
# The workers start paused (Paused=yes), so queued jobs stay queued.
. "$(dirname "$0")/lib.sh" "$@"

start_facetd --paused --queue-size 3 --max-body 500K --max-waiters 1 \
    --max-wait 30s || { not_ok "facetd starts"; finish; exit 1; }

# problem STATUS DESCRIPTION: the last response is that problem.
problem() {
    if [ "$CODE" != "$1" ]; then
        not_ok "$2" "status $CODE, want $1" "$(head -c 300 "$BODY")"
    elif [ "$(header Content-Type)" != "application/problem+json" ]; then
        not_ok "$2" "Content-Type $(header Content-Type)"
    elif ! grep -q "\"status\":$1," "$BODY" || ! grep -q '"type":"urn:facetd:problem:' "$BODY" ||
         ! grep -q '"title":' "$BODY" || ! grep -q '"detail":' "$BODY"; then
        not_ok "$2" "not a problem document: $(head -c 300 "$BODY")"
    else
        ok "$2"
    fi
}

printf '{"model": {"format": "facet-model/1",\n  "vertices": [[0,0,0],, ]}}' >"$T/bad.json"
post_json /v1/jobs "$T/bad.json"
problem 400 "malformed JSON is 400"
check "the error names line and column" grep -q '"line":2,"column":' "$BODY"
check "the detail names the line" grep -q '"detail":"line 2, column' "$BODY"
printf '{"pipeline":["inspect"],"pipeline":["inspect"]}' >"$T/dup.json"
post_json /v1/jobs "$T/dup.json"
problem 400 "a duplicate key is 400"
check "the error says duplicate" grep -q 'duplicate object key' "$BODY"

req GET "/v1/jobs?limit=0"
problem 400 "limit=0 is 400"
req GET "/v1/jobs?status=finished"
problem 400 "an unknown status filter is 400"
req GET "/v1/jobs?after=xyz"
problem 400 "an invalid after= cursor is 400"
f=$(body notch-cube.json)
post_json /v1/jobs "$f" -H "Idempotency-Key: $(printf 'k%.0s' $(seq 300))"
problem 400 "an overlong Idempotency-Key is 400"

req GET /nowhere
problem 404 "an unknown path is 404"
req GET /v1/jobs/01ARZ3NDEKTSV4RRFFQ69G5FAV
problem 404 "an unknown job is 404"
req GET /v1/jobs/not-a-job/stats
problem 404 "a malformed job id is 404"

req PUT /v1/jobs
problem 405 "PUT /v1/jobs is 405"
expect_eq "405 carries Allow" "GET, HEAD, POST, OPTIONS" "$(header Allow)"
req DELETE /v1/version
problem 405 "DELETE /v1/version is 405"
expect_eq "its Allow lists GET" "GET, HEAD, OPTIONS" "$(header Allow)"
req POST /v1/jobs/01ARZ3NDEKTSV4RRFFQ69G5FAV -H 'Content-Type: application/json' -d '{}'
problem 405 "POST on a job is 405"
req OPTIONS /v1/jobs/01ARZ3NDEKTSV4RRFFQ69G5FAV
expect_eq "OPTIONS answers 204 with Allow" "204 GET, HEAD, DELETE, OPTIONS" "$CODE $(header Allow)"

req POST /v1/jobs -H 'Content-Type: text/plain' --data-binary "@$f"
problem 415 "a text/plain body is 415"
req POST /v1/jobs -H 'Content-Type: application/json; charset=utf-8' --data-binary "@$f"
expect_eq "application/json with a charset is accepted" 202 "$CODE"
queued_id=$(jstr id)

big=$(body brilliant.scan-k800.json)
# With Expect: 100-continue, as a client sending a large body should: the
# 413 then comes before the body is sent. Without it the refusal races the
# upload, and the close of a socket with unread bytes may reset the
# connection before the client reads the answer.
post_json /v1/jobs "$big" -H 'Expect: 100-continue'
problem 413 "a body over MaxBody (by Content-Length) is 413"
req POST /v1/jobs -H 'Content-Type: application/json' -H 'Transfer-Encoding: chunked' --data-binary "@$big"
problem 413 "a chunked body over MaxBody is 413"

# 422: each problem listed with its place.
printf '{"model":{"format":"facet-model/1","vertices":[[0,0,0],[1,0,0],[0,1,0]],"facets":[{"vertices":[0,1,9]}]},"pipeline":["inspect"]}' >"$T/m.json"
post_json /v1/jobs "$T/m.json"
problem 422 "a model with an index out of range is 422"
check "the error names the model's place" grep -q '"path":"model.facets\[0\].vertices\[2\]"' "$BODY"
printf '{"model":{"format":"facet-model/1","vertices":[],"facets":[]},"pipeline":[{"op":"merge_facets","max_angle_deg":"1"}],"priority":"urgent","colour":1}' >"$T/m2.json"
post_json /v1/jobs "$T/m2.json"
problem 422 "several errors are one 422"
check "the list names the pipeline parameter" grep -q '"path":"pipeline\[0\].max_angle_deg","message":"expected a number"' "$BODY"
check "the list names the priority" grep -q '"path":"priority"' "$BODY"
check "the list names the unknown member" grep -q '"path":"colour"' "$BODY"
# a name of the last release is still run, with a deprecation warning
f2=$(body notch-cube.json '["inspect", "fill_holes"]')
post_json /v1/jobs "$f2"
expect_eq "a deprecated op name is accepted" 202 "$CODE"
check "the reply warns that it is deprecated" grep -q "op 'fill_holes' is deprecated: use 'fill'" "$BODY"
check "the stored pipeline has the current name" grep -q '"op":"fill"' "$BODY"
req DELETE "/v1/jobs/$(jstr id)"
f3=$(body notch-cube.json '["inspect", "flatten"]')
post_json /v1/jobs "$f3"
problem 422 "an unknown op is 422"
check "it names the op's place" grep -q '"path":"pipeline\[1\]","message":"unknown operation' "$BODY"
printf '{"pipeline":["inspect"]}' >"$T/nomodel.json"
post_json /v1/jobs "$T/nomodel.json"
problem 422 "a job without a model is 422"
printf '[1,2]' >"$T/arr.json"
post_json /v1/jobs "$T/arr.json"
problem 422 "a body that is not an object is 422"
printf '{"format":"facet-model/1","vertices":[[0,0,0]],"facets":[{"vertices":[0,0,0]}]}' >"$T/insp.json"
post_json /v1/inspect "$T/insp.json"
problem 422 "POST /v1/inspect with an invalid model is 422"

# 409: the job is queued (the workers are paused), it has no result.
req GET "/v1/jobs/$queued_id/model"
problem 409 "the model of a queued job is 409"
req GET "/v1/jobs/$queued_id/stats"
problem 409 "the stats of a queued job are 409"

# 429: one waiter allowed; a second long-poll is refused.
curl -s -o /dev/null "$URL/v1/jobs/$queued_id?wait=20" &
waiter=$!
for i in $(seq 50); do
    [ "$(metric facetd_http_waiting_clients)" = 1 ] && break; sleep 0.1
done
expect_eq "a long-poll is suspended (one waiting client)" 1 "$(metric facetd_http_waiting_clients)"
req GET "/v1/jobs/$queued_id?wait=5"
problem 429 "a second waiting client is 429"
check "429 carries Retry-After" test -n "$(header Retry-After)"
req GET "/v1/jobs/$queued_id/events"
problem 429 "an event stream beyond the limit is 429"
req DELETE "/v1/jobs/$queued_id"
expect_eq "DELETE of a queued job answers 200" 200 "$CODE"
expect_eq "it is canceled at once" canceled "$(jstr state)"
wait $waiter
expect_eq "the cancel wakes the long-poll" 0 "$(metric facetd_http_waiting_clients)"
req GET "/v1/jobs/$queued_id/model"
problem 409 "the model of a canceled job is 409"

# 503: queue size 3.
codes=""
for i in 1 2 3 4; do post_json /v1/jobs "$f"; codes="$codes $CODE"; done
expect_eq "the fourth queued job is refused" " 202 202 202 503" "$codes"
problem 503 "a full queue is 503"
check "503 carries Retry-After" test -n "$(header Retry-After)"
check "metrics count the refusal" test "$(metric 'facetd_jobs_rejected_total{reason="queue_full"}')" -ge 1
check "metrics count 503 on /v1/jobs" test "$(metric 'facetd_http_requests_total{route="/v1/jobs",code="503"}')" -ge 1
stop_facetd

# 401: a token protects everything but the health checks.
start_facetd --api-token s3cret || { not_ok "facetd starts with a token"; finish; exit 1; }
req GET /v1/jobs
problem 401 "no token is 401"
expect_eq "401 asks for a bearer token" 'Bearer realm="facetd"' "$(header WWW-Authenticate)"
req GET /v1/jobs -H 'Authorization: Bearer s3cre'
problem 401 "a wrong token is 401"
req GET /metrics -H 'Authorization: Bearer s3cret'
expect_eq "the right token is accepted" 200 "$CODE"
req GET /livez
expect_eq "/livez needs no token" 200 "$CODE"
req GET /readyz
expect_eq "/readyz needs no token" 200 "$CODE"
stop_facetd

# A non-loopback address without a token does not start.
"$FACETD" --listen 0.0.0.0:0 --state-dir "$T/x" >"$T/pub.log" 2>&1
expect_eq "a public address without a token exits with 2" 2 $?
check "it says why" grep -q 'requires an API token' "$T/pub.log"
finish
