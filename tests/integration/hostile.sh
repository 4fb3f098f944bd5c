#!/bin/bash
# hostile.sh — the probe's classes of hostile requests replayed against
# one facetd: URLs that are not UTF-8, ambiguous framing, over-long
# queries, garbage request lines, bodies that are malformed, too large,
# or name what the model lacks, inspections with unknown members, plus
# ordinary requests, while 300 slow clients trickle header bytes from
# another address. Reports the statuses, the RSS before and after and
# /livez's latency meanwhile; no request may get a 500 or no answer.
# HOSTILE_REQUESTS (default 12000) sets the count. HTTP/0.9 is 505 by
# design; the only other 5xx allowed is 503.
. "$(dirname "$0")/lib.sh" "$@"
RAW="$BUILD/tools/rawhttp"
COUNT=${HOSTILE_REQUESTS:-12000}

start_facetd --no-scanners --workers 1 --header-timeout 3s --max-body 4M ||
    { not_ok "facetd starts"; finish; exit 1; }
rss() { awk '/^VmRSS/ {print $2}' "/proc/$PID/status"; }

cube='{"format":"facet-model/1","vertices":[[0,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]],"facets":[{"vertices":[0,3,2,1]},{"vertices":[4,5,6,7]},{"vertices":[0,1,5,4]},{"vertices":[1,2,6,5]},{"vertices":[2,3,7,6]},{"vertices":[3,0,4,7]}]}'
# post PATH BODY: a POST with a correct Content-Length
post() {
    printf 'POST %s HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: %d\r\nConnection: close\r\n\r\n%s' \
        "$1" "${#2}" "$2"
}
get() { printf 'GET %s HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n' "$1"; }
q=$(for i in $(seq 1000); do printf 'a%d=1&' "$i"; done)
long=$(for i in $(seq 150); do printf '%%C3%%A9'; done)
{
    get '/x%FF'; printf '\n%%%%\n'
    get '/v1/jobs/%FF'; printf '\n%%%%\n'
    get "/$long"; printf '\n%%%%\n'
    printf 'POST /v1/scanners/%%FF/scan HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n'; printf '\n%%%%\n'
    printf 'POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: 3\r\nContent-Length: 50\r\n\r\nabc'; printf '\n%%%%\n'
    printf 'POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nTransfer-Encoding: gzip\r\n\r\nabc'; printf '\n%%%%\n'
    printf "GET /v1/jobs?$q HTTP/1.1\r\nHost: x\r\n\r\n"; printf '\n%%%%\n'
    printf '\001\002\377 garbage\r\n\r\n'; printf '\n%%%%\n'
    printf 'GET /livez HTTP/0.9\r\n\r\n'; printf '\n%%%%\n'
    printf 'POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: 99999999999\r\n\r\n'; printf '\n%%%%\n'
    post /v1/jobs '{"model": [1,,2]}'; printf '\n%%%%\n'
    post /v1/jobs "{\"model\":$cube,\"pipeline\":[\"flatten\"]}"; printf '\n%%%%\n'
    post /v1/jobs "{\"model\":$cube,\"extra\":1}"; printf '\n%%%%\n'
    post /v1/jobs "{\"model\":$cube,\"pipeline\":[{\"op\":\"move\",\"vertex\":99,\"to\":[0,0,0]}]}"; printf '\n%%%%\n'
    post /v1/inspect "{\"model\":$cube,\"x\":1}"; printf '\n%%%%\n'
    post /v1/inspect "$cube"; printf '\n%%%%\n'
    get /v1/jobs/01ARZ3NDEKTSV4RRFFQ69G5FAV; printf '\n%%%%\n'
    get '/v1/jobs?limit=5'; printf '\n%%%%\n'
    get /readyz; printf '\n%%%%\n'
    get /livez
} >"$T/requests"

rss0=$(rss)
"$RAW" slow "$PORT" 127.0.0.2 300 $((20 * SLOW)) >"$T/slow.out" &
slow=$!
"$RAW" replay "$PORT" "$T/requests" "$COUNT" 8 >"$T/replay.out" &
replay=$!
lat="$T/livez"
: >"$lat"
end=$((SECONDS + 3))
while kill -0 "$replay" 2>/dev/null || [ $SECONDS -lt $end ]; do
    curl -s -o /dev/null -m 5 -w '%{http_code} %{time_total}\n' "$URL/livez" >>"$lat"
    sleep 0.2
done
wait "$replay"
kill "$slow" 2>/dev/null; wait "$slow" 2>/dev/null
rss1=$(rss)
sed 's/^/# /' "$T/replay.out"
read -r _ sent _ secs <"$T/replay.out"
n5=$(awk '$1 == "status" && $2 >= 500 && $2 != 503 && $2 != 505 {n += $3} END {print n + 0}' "$T/replay.out")
n0=$(awk '$1 == "status" && $2 == "000" {n += $3} END {print n + 0}' "$T/replay.out")
read -r probes bad worst <<<"$(awk '{n++; if ($1 != 200) b++; if ($2 > w) w = $2} END {print n + 0, b + 0, w + 0}' "$lat")"
echo "# RSS before ${rss0} kB, after ${rss1} kB"
echo "# /livez meanwhile: $probes probes, $bad not 200, slowest ${worst} s"
check "$sent requests replayed in ${secs} s" test "$sent" -eq "$COUNT"
expect_eq "no request got a 500 (or any 5xx but 503, 505)" 0 "$n5"
expect_eq "every request was answered (status 000 is no answer)" 0 "$n0"
check "every /livez probe was 200 within 1 s ($probes probes, slowest ${worst} s)" \
    awk -v b="$bad" -v w="$worst" -v s="$SLOW" 'BEGIN {exit !(b == 0 && w < s)}'
case "$BUILD" in
*asan*) skip "RSS under AddressSanitizer (its quarantine keeps freed memory: ${rss0} -> ${rss1} kB)" ;;
*) check "the RSS grew by under 64 MB (${rss0} -> ${rss1} kB)" test $((rss1 - rss0)) -lt 65536 ;;
esac
check "facetd still serves" test "$(curl -s -m 5 -o /dev/null -w '%{http_code}' "$URL/livez")" = 200
finish
