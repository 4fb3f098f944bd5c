#!/bin/bash
# hostile_http.sh — what a hostile client gets at the HTTP layer: a URL
# that is not UTF-8 (or is cut mid-character) is a 404 problem, never a
# 500; framing the server cannot read (two different Content-Length,
# a Transfer-Encoding other than chunked, both) and a query of more
# arguments than MaxQueryArgs are answered 400 at once and the connection
# closed; 1,100 clients that trickle one header byte a second from one
# address neither lock out a client from another address (served within
# 5 s) nor outlive the header deadline.
. "$(dirname "$0")/lib.sh" "$@"
RAW="$BUILD/tools/rawhttp"

start_facetd --no-scanners --header-timeout 3s || {
    not_ok "facetd starts"; finish; exit 1; }

# problem_of PATH [curl args]: status and whether the body is a problem
url_problem() {
    req GET "$1"
    if [ "$CODE" = 404 ] && grep -q '"status":404,' "$BODY" &&
       [ "$(header Content-Type)" = application/problem+json ]; then
        ok "$2"
    else
        not_ok "$2" "status $CODE" "$(head -c 200 "$BODY")"
    fi
}
url_problem '/x%FF' "GET /x%FF is a 404 problem"
check "... quoting the byte escaped" grep -q 'x\\\\xFF' "$BODY"
url_problem '/v1/jobs/%FF' "GET /v1/jobs/%FF is a 404 problem"
long=/$(for i in $(seq 150); do printf '%%C3%%A9'; done)
url_problem "$long" "a URL of 150 'é' cut mid-character in the detail is a 404 problem"
req POST '/v1/scanners/%FF%FE/scan'
check "POST /v1/scanners/%FF%FE/scan is not a 500 ($CODE)" test "$CODE" != 500 -a "$CODE" != 000

# framing STATUS_WANT DESCRIPTION BYTES: raw request, the answer must come
# at once and the server must close the connection
framing() {
    local want=$1 d=$2; shift 2
    printf "$@" | "$RAW" send "$PORT" $((4000 * SLOW)) >"$T/raw.out" 2>"$T/raw.err"
    local rc=$? first ms
    first=$(head -n 1 "$T/raw.out" | tr -d '\r')
    ms=$(awk '{print $2}' "$T/raw.err")
    if [ "$first" != "HTTP/1.1 $want Bad Request" ]; then
        not_ok "$d" "answer '$first'"
    elif [ $rc -ne 0 ] || [ "$ms" -gt $((1000 * SLOW)) ]; then
        not_ok "$d" "connection $(cat "$T/raw.err") (want closed at once)"
    else
        ok "$d ($ms ms)"
    fi
}
framing 400 "two different Content-Length: 400 and closed" \
    'POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: 3\r\nContent-Length: 50\r\n\r\nabc'
framing 400 "Transfer-Encoding: gzip: 400 and closed" \
    'POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nTransfer-Encoding: gzip\r\n\r\nabc'
framing 400 "Transfer-Encoding and Content-Length together: 400 and closed" \
    'POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nTransfer-Encoding: chunked\r\nContent-Length: 5\r\n\r\n0\r\n\r\n'
q=$(for i in $(seq 1000); do printf 'a%d=1&' "$i"; done)
framing 400 "1,000 query arguments: 400 and closed" "GET /v1/jobs?$q HTTP/1.1\r\nHost: x\r\n\r\n"
check "... naming the limit" grep -q '1000 query arguments; the limit is 100' "$T/raw.out"
req GET "/v1/jobs?limit=5&status=queued"
expect_eq "a query within the limit is served" 200 "$CODE"
printf 'POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: 2\r\nContent-Length: 2\r\nConnection: close\r\n\r\n{}' |
    "$RAW" send "$PORT" 4000 >"$T/raw.out" 2>/dev/null
check "a repeated equal Content-Length is read (422, not 400)" \
    grep -q '^HTTP/1.1 422' "$T/raw.out"

# 1,100 slow clients from 127.0.0.2, probes from 127.0.0.1
"$RAW" slow "$PORT" 127.0.0.2 1100 $((8 * SLOW)) >"$T/slow.out" &
slow=$!
sleep 2
served=0 worst=0
for i in 1 2 3 4 5; do
    t=$(curl -s -o /dev/null -m 5 -w '%{http_code} %{time_total}' "$URL/livez")
    [ "${t% *}" = 200 ] && served=$((served + 1))
    worst=$(awk -v a="$worst" -v b="${t#* }" 'BEGIN {print (b > a) ? b : a}')
    sleep 0.5
done
wait "$slow"
expect_eq "under 1,100 slow clients 5 of 5 probes are served within 5 s (slowest ${worst} s)" 5 "$served"
read -r _ conn _ closed _ open _ _ _ last <"$T/slow.out"
check "the slow clients connected ($conn) and the server closed every one ($closed, $open open)" \
    test "$conn" = 1100 -a "$closed" = 1100 -a "$open" = 0
check "the last was closed by the 3 s header deadline (${last} s)" \
    awk -v l="$last" -v s="$SLOW" 'BEGIN {exit !(l >= 2.5 && l <= 5 * s)}'
check "facetd still serves" test "$(curl -s -m 5 -o /dev/null -w '%{http_code}' "$URL/livez")" = 200

finish
