#!/bin/bash
# api_jobs.sh — the life of a job over HTTP: submit (202 + Location),
# long-poll to the end, the result in every model format (each parses
# back), the statistics, ETags and 304, listing with filters and pages,
# the event stream, and /metrics counters that move with the traffic.
. "$(dirname "$0")/lib.sh" "$@"

start_facetd --workers 2 || { not_ok "facetd starts"; finish; exit 1; }
ok "facetd starts and is ready"

req GET /livez
expect_eq "/livez answers 200" 200 "$CODE"
req GET /v1/version
check "/v1/version lists the inspect op" grep -q '"ops":\["inspect"' "$BODY"

jobs_before=$(metric 'facetd_http_requests_total{route="/v1/jobs",code="202"}')
submit brilliant.scan-k400.json
expect_eq "POST /v1/jobs answers 202" 202 "$CODE"
expect_eq "Location names the job" "/v1/jobs/$ID" "$(header Location)"
expect_eq "a new job is queued" queued "$(jstr state)"
check "the job id is a ULID" test ${#ID} -eq 26

K400=$ID
wait_job "$ID"
expect_eq "the job succeeds" succeeded "$STATE_OF"
expect_eq "progress is 1 at the end" 1.0 "$(jnum progress)"
check "the summary says the scan is valid" grep -q '"valid":true' "$BODY"
check "the summary counts 1808 facets before" grep -q '"facets_before":1808' "$BODY"
check "the job links its model and stats" grep -q "\"model\":\"/v1/jobs/$ID/model\"" "$BODY"

for fmt in json poly obj stl stl-ascii ply ply-ascii ase fmb1 off; do
    req GET "/v1/jobs/$ID/model?format=$fmt"
    out="$T/model.$fmt"
    cp "$BODY" "$out"
    if [ "$CODE" != 200 ] || [ ! -s "$out" ]; then
        not_ok "model as $fmt" "status $CODE"; continue
    fi
    case $fmt in
        ase) grep -q '\*3DSMAX_ASCIIEXPORT' "$out" && ok "model as ase" || not_ok "model as ase" ;;
        *)
            ext=$fmt
            case $fmt in stl-ascii) ext=stl ;; ply-ascii) ext=ply ;; fmb1) ext=fmb ;; esac
            mv "$out" "$out.$ext"
            if "$BUILD/facet" convert "$out.$ext" "$T/back.json" 2>"$T/err"; then
                ok "model as $fmt ($(header Content-Type)) reads back"
            else
                not_ok "model as $fmt reads back" "$(cat "$T/err")"
            fi ;;
    esac
done
req GET "/v1/jobs/$ID/model"
check "the default format is facet-model/1 JSON" grep -q '"format":"facet-model/1"' "$BODY"
cmp -s "$BODY" "$MODELS/brilliant.scan-k400.json"
check "inspect returns the model byte for byte" test $? -eq 0
etag=$(header ETag)
req GET "/v1/jobs/$ID/model" -H "If-None-Match: $etag"
expect_eq "If-None-Match with the model's ETag gives 304" 304 "$CODE"
req GET "/v1/jobs/$ID/model?format=obj" -H "If-None-Match: $etag"
expect_eq "another format has another ETag" 200 "$CODE"
req GET "/v1/jobs/$ID/model?format=dxf"
expect_eq "an unknown format is 400" 400 "$CODE"

req GET "/v1/jobs/$ID/stats"
expect_eq "GET stats answers 200" 200 "$CODE"
check "stats hold the op report" grep -q '"ops":\[{"op":"inspect"' "$BODY"
check "stats hold the inspection before" grep -q '"before":{"vertices":3612' "$BODY"
check "stats list self-intersections" grep -q '"self_intersections":{"count":0' "$BODY"
etag=$(header ETag)
req GET "/v1/jobs/$ID/stats" -H "If-None-Match: W/$etag"
expect_eq "stats revalidate with 304 (weak comparison)" 304 "$CODE"
req GET "/v1/jobs/$ID"
etag=$(header ETag)
req GET "/v1/jobs/$ID" -H "If-None-Match: $etag"
expect_eq "an unchanged job revalidates with 304" 304 "$CODE"

# Listing: newest first, filters, pages.
submit notch-cube.json; a=$ID
submit l-prism.json; b=$ID
wait_job "$a"; wait_job "$b"
req GET "/v1/jobs?limit=2"
first=$(grep -o '"id":"[0-9A-Z]*"' "$BODY" | head -n 1 | cut -d'"' -f4)
expect_eq "the list is newest first" "$b" "$first"
next=$(jstr next)
check "a full page links the next one" test -n "$next"
req GET "$next"
check "the next page holds the oldest job" grep -q "\"id\":\"$K400\"" "$BODY"
req GET "/v1/jobs?status=succeeded&source=http&limit=100"
expect_eq "filtering by status and source" 3 "$(grep -o '"state":"succeeded"' "$BODY" | wc -l)"
req GET "/v1/jobs?status=running"
check "no job is running now" grep -q '"jobs":\[\]' "$BODY"

# Event stream of a finished job: its final state, then the end.
timeout $((10 * SLOW)) curl -s -N "$URL/v1/jobs/$a/events" >"$T/events"
check "events of a finished job end with its final state" \
    grep -q '^event: state' "$T/events"
check "event ids are job versions" grep -q '^id: [0-9]' "$T/events"
timeout $((10 * SLOW)) curl -s -N -H "Last-Event-ID: 999" "$URL/v1/jobs/$a/events" >"$T/events2"
check "Last-Event-ID at the newest version sends nothing more" test ! -s "$T/events2"

jobs_after=$(metric 'facetd_http_requests_total{route="/v1/jobs",code="202"}')
expect_eq "metrics count the 202s" 3 "$((jobs_after - jobs_before))"
check "metrics count succeeded jobs" test "$(metric 'facetd_jobs_finished_total{state="succeeded"}')" -ge 3
check "metrics time the inspect op" test "$(metric 'facetd_op_duration_seconds_count{op="inspect"}')" -ge 3
check "metrics show the store size" test "$(metric facetd_store_bytes)" -gt 0
check "metrics show jobs by state" test "$(metric 'facetd_jobs{state="succeeded"}')" -ge 3
check "metrics count received bytes" test "$(metric facetd_http_received_bytes_total)" -gt 400000

# DELETE of a finished job removes it and its results.
req DELETE "/v1/jobs/$a"
expect_eq "DELETE of a finished job answers 204" 204 "$CODE"
req GET "/v1/jobs/$a"
expect_eq "the deleted job is gone" 404 "$CODE"

stop_facetd
expect_eq "SIGTERM stops facetd cleanly" 0 "$STATUS"
check "the log says it stopped" grep -q 'stopped' "$LOG"
finish
