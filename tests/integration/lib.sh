# lib.sh — shared helpers of the integration tests (sourced, bash).
#
# Each test script starts its own facetd on a free loopback port (the
# daemon binds 127.0.0.1:0 and logs the port it got) with a temporary
# state directory, talks to it with curl, and prints TAP ("ok N - ...",
# a "1..N" plan at the end). Usage in a script:
#   . "$(dirname "$0")/lib.sh" "$@"      # $1 = build dir (build, build/asan)
#   start_facetd --workers 1             # sets URL, PID, STATE, LOG
#   check "description" test-command ...
#   finish
if [ "${BASH_SOURCE[0]}" = "$0" ]; then
    echo "1..0 # SKIP lib.sh is the helper the other scripts source"
    exit 0
fi
set -u
BUILD=${1:-build}
FACETD="$BUILD/facetd"
MODELS=tests/data/models
T=$(mktemp -d /tmp/facetd-it.XXXXXX)
N=0
FAILED=0
PIDS=()
# ASan builds start and run slower.
case "$BUILD" in *asan*) SLOW=3 ;; *) SLOW=1 ;; esac

ok() { N=$((N + 1)); echo "ok $N - $1"; }
not_ok() {
    N=$((N + 1)); FAILED=$((FAILED + 1)); echo "not ok $N - $1"
    shift
    for line in "$@"; do echo "#   $line"; done
}
skip() { N=$((N + 1)); echo "ok $N # SKIP $1"; }
# check DESCRIPTION COMMAND...: ok when the command succeeds.
check() {
    local d=$1; shift
    if "$@"; then ok "$d"; else not_ok "$d" "failed: $*"; fi
}
# expect_eq DESCRIPTION WANT GOT
expect_eq() {
    if [ "$2" = "$3" ]; then ok "$1"; else not_ok "$1" "want: $2" "got:  $3"; fi
}

# start_facetd [FLAGS...]: a new facetd with its own state directory
# (STATE, reused when STATE_KEEP is set), log LOG; sets URL, PORT, PID.
start_facetd() {
    if [ -z "${STATE_KEEP:-}" ]; then STATE=$(mktemp -d "$T/state.XXXXXX"); fi
    LOG=$(mktemp "$T/log.XXXXXX")
    "$FACETD" --listen 127.0.0.1:0 --state-dir "$STATE" "$@" >"$LOG" 2>&1 &
    PID=$!
    PIDS+=("$PID")
    local i
    for i in $(seq 1 $((100 * SLOW))); do
        PORT=$(sed -n 's|.*listening on http://127\.0\.0\.1:\([0-9]*\).*|\1|p' "$LOG" | head -n 1)
        [ -n "$PORT" ] && break
        if ! kill -0 "$PID" 2>/dev/null; then
            echo "# facetd exited at start-up:"; sed 's/^/#   /' "$LOG"; return 1
        fi
        sleep 0.1
    done
    if [ -z "$PORT" ]; then echo "# facetd did not start"; sed 's/^/#   /' "$LOG"; return 1; fi
    URL="http://127.0.0.1:$PORT"
    for i in $(seq 1 $((50 * SLOW))); do
        [ "$(curl -s -o /dev/null -w '%{http_code}' "$URL/readyz")" = 200 ] && return 0
        sleep 0.1
    done
    echo "# facetd never became ready"; return 1
}

# stop_facetd [SIGNAL]: stops the last facetd (TERM by default), waits.
stop_facetd() {
    kill "-${1:-TERM}" "$PID" 2>/dev/null
    wait "$PID" 2>/dev/null
    STATUS=$?
}

# body MODEL [PIPELINE_JSON] [EXTRA_MEMBERS]: a job request in a file;
# prints its path.
body() {
    local f
    f=$(mktemp "$T/body.XXXXXX")
    { printf '{"pipeline":%s,%s"model":' "${2:-[\"inspect\"]}" "${3:+$3,}"
      cat "$MODELS/$1"; printf '}'; } >"$f"
    echo "$f"
}

# req METHOD PATH [curl args...]: sets CODE, BODY (file), HDRS (file).
req() {
    local m=$1 p=$2; shift 2
    BODY=$(mktemp "$T/resp.XXXXXX"); HDRS=$(mktemp "$T/hdrs.XXXXXX")
    CODE=$(curl -s -X "$m" -o "$BODY" -D "$HDRS" -w '%{http_code}' "$@" "$URL$p")
}
# post_json PATH FILE [curl args...]
post_json() {
    local p=$1 f=$2; shift 2
    req POST "$p" -H 'Content-Type: application/json' --data-binary "@$f" "$@"
}

# Fields of the compact JSON facetd writes (first occurrence of the key).
jstr() { grep -o "\"$1\":\"[^\"]*\"" "${2:-$BODY}" | head -n 1 | cut -d'"' -f4; }
jnum() { grep -o "\"$1\":[-0-9.eE+a-z]*" "${2:-$BODY}" | head -n 1 | cut -d: -f2; }
header() { grep -i "^$1:" "${2:-$HDRS}" | head -n 1 | cut -d' ' -f2- | tr -d '\r'; }

# submit MODEL [PIPELINE]: posts a job, sets ID (empty on failure).
submit() {
    local f; f=$(body "$@")
    post_json /v1/jobs "$f"
    ID=""
    [ "$CODE" = 202 ] && ID=$(jstr id)
}

# wait_job ID [SECONDS]: long-polls until the job ends; sets STATE_OF.
wait_job() {
    local end=$((SECONDS + ${2:-30} * SLOW))
    STATE_OF=""
    while [ $SECONDS -lt $end ]; do
        req GET "/v1/jobs/$1?wait=10"
        STATE_OF=$(jstr state)
        case "$STATE_OF" in succeeded|failed|canceled) return 0 ;; esac
    done
    return 1
}

# metric NAME_WITH_LABELS: its value in /metrics (0 when absent).
metric() {
    local v
    v=$(curl -s "$URL/metrics" | awk -v n="$1" '$1 == n {print $2; exit}')
    echo "${v:-0}"
}

finish() {
    local p
    for p in "${PIDS[@]}"; do kill -TERM "$p" 2>/dev/null; done
    for p in "${PIDS[@]}"; do wait "$p" 2>/dev/null; done
    echo "1..$N"
    if [ "$FAILED" -gt 0 ] && [ -n "${LOG:-}" ]; then
        echo "# last facetd log:"; tail -n 20 "$LOG" | sed 's/^/#   /'
    fi
    rm -rf "$T"
    [ "$FAILED" -eq 0 ]
}
# Whatever ends the script (a failed start, a signal, a reader that went
# away), no facetd outlives it.
cleanup() {
    local p
    for p in "${PIDS[@]}"; do kill -KILL "$p" 2>/dev/null; done
    rm -rf "$T"
}
trap cleanup EXIT
trap 'exit 130' INT TERM
trap '' PIPE
