#!/bin/bash
# robustness.sh — bad input never crashes or hangs the CLI or facetd, and
# facetd keeps serving: the reproducible defects found by attacking both
# as users would. CLI: models without facets through the kernels, outputs
# that are FIFOs or a full disk, a prism with 20,000-gon caps. facetd
# (loopback only, bounded loops): malformed requests over a raw socket,
# malformed and degenerate job bodies, the collapse_clusters job that
# crashed the worker, cancel/delete/get races on running jobs, event
# streams and long polls dropped mid-way, idle and slow connections.
# After each attack /livez answers; at the end a normal job succeeds and
# the log (sanitized builds: leaks included) holds no sanitizer report.
. "$(dirname "$0")/lib.sh" "$@"
FACET="$BUILD/facet"

# cli_run NAME WANT_STATUS GREP_MESSAGE ARGS...: runs facet, checks the
# exit status, the message and that no sanitizer spoke.
cli_run() {
    local d=$1 want=$2 msg=$3; shift 3
    timeout $((20 * SLOW)) "$FACET" "$@" >"$T/cli.out" 2>"$T/cli.err"
    local rc=$?
    if grep -qE 'Sanitizer|runtime error' "$T/cli.err"; then
        not_ok "$d" "sanitizer report:" "$(grep -m 3 -E 'ERROR|runtime error' "$T/cli.err")"
    elif [ "$rc" != "$want" ]; then
        not_ok "$d" "exit $rc, want $want" "$(head -c 300 "$T/cli.err")"
    elif [ -n "$msg" ] && ! grep -q -- "$msg" "$T/cli.err"; then
        not_ok "$d" "message lacks '$msg'" "$(head -c 300 "$T/cli.err")"
    else
        ok "$d"
    fi
}

printf '{"format":"facet-model/1","vertices":[],"facets":[]}' >"$T/empty.json"
printf '{"format":"facet-model/1","vertices":[[0,0,0],[1,0,0],[0,1,0]],"facets":[]}' \
    >"$T/nofacets.json"
cli_run "correct: an empty model is refused by name" 1 "no facets" \
    correct "$T/empty.json" -o "$T/out.json"
cli_run "correct: a model without facets is refused by name" 1 "no facets" \
    correct "$T/nofacets.json" -o "$T/out.json"
cli_run "merge --auto: an empty model gives an empty result" 0 "" \
    merge "$T/empty.json" --auto -o "$T/out.json"
cli_run "move: no vertex to move in an empty model" 1 "out of range (0 vertices)" \
    move "$T/empty.json" --vertex 0 --by 0.1,0,0 -o "$T/out.json"
cli_run "move: a vertex in no facet" 1 "" \
    move "$T/nofacets.json" --vertex 0 --by 0.1,0,0 -o "$T/out.json"
cli_run "inspect: an empty model is inspected" 0 "" inspect "$T/empty.json"
check "inspect: the empty model has no facets" grep -q '"facets": 0' "$T/cli.out"

mkfifo "$T/fifo"
cat "$T/fifo" >"$T/fifo.out" &
cli_run "convert into a FIFO writes through it" 0 "" \
    convert "$MODELS/notch-cube.json" "$T/fifo" --to json
wait $!
check "the FIFO is still a FIFO" test -p "$T/fifo"
check "the model came through the FIFO" grep -q '"facet-model/1"' "$T/fifo.out"
if [ -c /dev/full ]; then
    "$FACET" cut "$MODELS/notch-cube.json" --plane 0,0,1,-1 -o "$T/cut.json" \
        >/dev/full 2>"$T/full.err"
    rc=$?
    expect_eq "a full standard output fails the command" "1 yes" \
        "$rc $(grep -q 'No space left' "$T/full.err" && echo yes)"
else
    skip "no /dev/full"
fi

# a prism with 20,000-gon caps: each side quad meets both caps' boxes
awk 'BEGIN { n = 20000; pi = atan2(0, -1)
    printf "{\"format\":\"facet-model/1\",\"vertices\":["
    for (z = 0; z < 2; z++) for (i = 0; i < n; i++)
        printf "%s[%.17g,%.17g,%d]", (z || i) ? "," : "", cos(2*pi*i/n), sin(2*pi*i/n), z
    printf "],\"facets\":[{\"vertices\":["
    for (i = n - 1; i >= 0; i--) printf "%s%d", i < n - 1 ? "," : "", i
    printf "]},{\"vertices\":["
    for (i = 0; i < n; i++) printf "%s%d", i ? "," : "", n + i
    printf "]}"
    for (i = 0; i < n; i++)
        printf ",{\"vertices\":[%d,%d,%d,%d]}", i, (i+1)%n, n+(i+1)%n, n+i
    printf "]}" }' >"$T/prism.json"
start=$SECONDS
cli_run "inspect: a 20,000-gon prism in bounded time" 0 "" inspect "$T/prism.json"
check "the prism is valid" grep -q '"valid": true' "$T/cli.out"
check "in under $((10 * SLOW)) s" test $((SECONDS - start)) -lt $((10 * SLOW))

start_facetd --workers 2 --max-connections 64 --connection-timeout 3s \
    --max-body 4M || { not_ok "facetd starts"; finish; exit 1; }

alive() { [ "$(curl -s -o /dev/null -w '%{http_code}' --max-time 5 "$URL/livez")" = 200 ]; }
# raw BYTES...: one request over a raw socket (printf format), the first
# line of the answer in RAW (empty when the server closed).
raw() {
    RAW=""
    exec 3<>"/dev/tcp/127.0.0.1/$PORT" || return 0
    printf "$@" >&3 2>/dev/null
    IFS= read -r -t $((5 * SLOW)) RAW <&3
    RAW=${RAW%$'\r'}
    exec 3<&- 3>&-
}
# attack DESCRIPTION WANT_PREFIX BYTES...: raw request, then /livez.
attack() {
    local d=$1 want=$2; shift 2
    raw "$@"
    if [ -n "$want" ] && [ "${RAW#"$want"}" = "$RAW" ]; then
        not_ok "$d" "answer '$RAW', want '$want...'"
    elif ! alive; then
        not_ok "$d" "facetd no longer answers /livez"
    else
        ok "$d"
    fi
}

attack "garbage request line" "" '\001\002\377 garbage\r\n\r\n'
attack "HTTP/0.9" "HTTP/1.1 505" 'GET /livez HTTP/0.9\r\n\r\n'
attack "path traversal is a 404" "HTTP/1.1 404" \
    'GET /v1/jobs/%%2e%%2e%%2f%%2e%%2e%%2fetc%%2fpasswd HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n'
attack "NUL and bad escapes in the query" "HTTP/1.1 400" \
    'GET /v1/jobs?status=%%00%%zz&limit=%%ff HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n'
big=$(head -c 200000 /dev/zero | tr '\0' a)
attack "a 200 KB header is 431" "HTTP/1.1 431" \
    "GET /livez HTTP/1.1\r\nHost: x\r\nX-Big: $big\r\n\r\n"
attack "a bad chunk size is 400" "HTTP/1.1 400" \
    'POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nTransfer-Encoding: chunked\r\n\r\nzz\r\n{}\r\n0\r\n\r\n'
attack "a huge Content-Length is 413" "HTTP/1.1 413" \
    'POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: 99999999999999999999\r\n\r\n'
attack "a negative Content-Length is 400" "HTTP/1.1 400" \
    'POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Length: -5\r\n\r\n'

# job bodies: malformed, degenerate, and the one that crashed a worker
cube='{"format":"facet-model/1","vertices":[[0,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]],"facets":[{"vertices":[0,3,2,1]},{"vertices":[4,5,6,7]},{"vertices":[0,1,5,4]},{"vertices":[1,2,6,5]},{"vertices":[2,3,7,6]},{"vertices":[3,0,4,7]}]}'
# post DESCRIPTION WANT_CODE BODY
post() {
    printf '%s' "$3" >"$T/post.json"
    post_json /v1/jobs "$T/post.json"
    if [ "$CODE" != "$2" ]; then not_ok "$1" "status $CODE, want $2" "$(head -c 300 "$BODY")"
    elif ! alive; then not_ok "$1" "facetd no longer answers /livez"
    else ok "$1"; fi
}
post "duplicate keys are 400" 400 "{\"model\":$cube,\"model\":$cube}"
post "nesting 100,000 deep is 400" 400 "{\"model\":$(head -c 100000 /dev/zero | tr '\0' '[')}"
post "invalid UTF-8 is 400" 400 "$(printf '{"label":"\377\376","model":%s}' "$cube")"
post "an unknown op is 422" 422 "{\"model\":$cube,\"pipeline\":[\"flatten\"]}"
post "a parameter of the wrong type is 422" 422 \
    "{\"model\":$cube,\"pipeline\":[{\"op\":\"collapse_clusters\",\"radius\":[]}]}"
ids=()
for i in 1 2 3; do
    post "collapse_clusters job $i is accepted" 202 \
        "{\"model\":$cube,\"pipeline\":[\"inspect\",{\"op\":\"collapse_clusters\",\"radius\":0.$i},\"inspect\"]}"
    ids+=("$(jstr id)")
done
for id in "${ids[@]}"; do
    wait_job "$id" 20
    expect_eq "collapse_clusters job succeeds" succeeded "$STATE_OF"
done
post "an empty model with auto is accepted" 202 \
    '{"model":{"format":"facet-model/1","vertices":[],"facets":[]}}'
id=$(jstr id)
wait_job "$id" 20
expect_eq "... and fails by name" "failed yes" \
    "$STATE_OF $(grep -q 'no facets' "$BODY" && echo yes)"
post "all vertices equal: inspect is accepted" 202 \
    '{"pipeline":["inspect"],"model":{"format":"facet-model/1","vertices":[[1,1,1],[1,1,1],[1,1,1],[1,1,1]],"facets":[{"vertices":[0,1,2]},{"vertices":[0,3,1]},{"vertices":[1,3,2]},{"vertices":[2,3,0]}]}}'
id=$(jstr id)
wait_job "$id" 20
expect_eq "... and reports an invalid model" "succeeded yes" \
    "$STATE_OF $(grep -q '"valid":false' "$BODY" && echo yes)"

# an idle facetd sleeps: the scanners' RESULT sender once waited on a
# condition variable of the wrong clock and spun a core
ticks() { awk '{print $14 + $15}' "/proc/$PID/stat"; }
t0=$(ticks); sleep 2; t1=$(ticks)
check "idle for 2 s, facetd uses under 0.3 s of CPU ($((t1 - t0)) ticks)" \
    test $((t1 - t0)) -lt 30

# races: cancel, delete, get, wait and events on the same running jobs
ids=()
for i in 1 2 3 4 5 6; do submit brilliant.scan-k800.json '"auto"'; ids+=("$ID"); done
pids=()
for id in "${ids[@]}"; do
    for k in 1 2; do
        curl -s -o /dev/null --max-time 2 -X DELETE "$URL/v1/jobs/$id" & pids+=($!)
        curl -s -o /dev/null --max-time 2 "$URL/v1/jobs/$id" & pids+=($!)
        curl -s -o /dev/null --max-time 0.3 "$URL/v1/jobs/$id?wait=30" & pids+=($!)
        curl -s -o /dev/null -N --max-time 0.3 "$URL/v1/jobs/$id/events" & pids+=($!)
        curl -s -o /dev/null --max-time 2 "$URL/v1/jobs/$id/model?format=stl" & pids+=($!)
    done
done
wait "${pids[@]}"
check "cancel/delete/get races leave facetd serving" alive
for id in "${ids[@]}"; do curl -s -o /dev/null --max-time 2 -X DELETE "$URL/v1/jobs/$id"; done

# event streams and long polls dropped mid-way, on running jobs
submit brilliant.scan-k800.json '"auto"'
for k in 1 2 3 4 5; do
    curl -s -o /dev/null -N --max-time 0.2 -H "Last-Event-ID: $((k - 3))" "$URL/v1/jobs/$ID/events"
    curl -s -o /dev/null --max-time 0.2 "$URL/v1/jobs/$ID?wait=30"
done
check "dropped event streams and long polls leave facetd serving" alive

# idle connections within the limit, then a slow sender
for fd in $(seq 10 39); do eval "exec $fd<>/dev/tcp/127.0.0.1/$PORT"; done
check "30 idle connections: /livez still answers" alive
for fd in $(seq 10 39); do eval "exec $fd<&- $fd>&-"; done
exec 3<>"/dev/tcp/127.0.0.1/$PORT"
for part in 'GET /li' 'vez HTTP/1.1\r\n' 'Host: x\r\n' 'Connection: close\r\n\r\n'; do
    printf "$part" >&3; sleep 0.2
done
IFS= read -r -t 5 RAW <&3; exec 3<&- 3>&-
expect_eq "a slow sender is answered" "HTTP/1.1 200 OK" "${RAW%$'\r'}"
exec 3<>"/dev/tcp/127.0.0.1/$PORT"
printf 'POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: 1000\r\n\r\n{"mo' >&3
RAW=""; IFS= read -r -t $((10 * SLOW)) RAW <&3; exec 3<&- 3>&-
check "a stalled body is dropped after the timeout, facetd serving" alive

submit notch-cube.json
wait_job "$ID" 20
expect_eq "after all that a normal job succeeds" succeeded "$STATE_OF"
stop_facetd
expect_eq "facetd stops cleanly" 0 "$STATUS"
if grep -qE 'Sanitizer|runtime error' "$LOG"; then
    not_ok "no sanitizer report in the facetd log" "$(grep -m 3 -E 'ERROR|runtime error' "$LOG")"
else
    ok "no sanitizer report in the facetd log"
fi
finish
