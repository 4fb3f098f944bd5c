#!/bin/bash
# scanner_daemon.sh — facetd with mocked USB scanners (fsp-mock on a
# umockdev testbed), driven with curl: a plugged scanner is listed by
# GET /v1/scanners; its 400-contour scan becomes a job with source
# usb:SERIAL whose model and statistics equal what `facet run` gives
# offline with the same pipeline, and the scanner gets a RESULT frame with
# that job's id — over bulk and over hidraw; a corrupted frame is NAKed
# and sent again; a model that does not parse is refused with ABORT;
# unplugging mid-scan makes no job and moves the dropped
# counter while the daemon keeps serving; a re-plugged scanner scans
# again; two scanners scan at once; POST /v1/scanners/{serial}/scan
# starts a scan (404 unknown, 409 busy or offline); SIGHUP applies a new
# pipeline; a scanner job queued when facetd stops still sends its RESULT
# after the restart; a configured pipeline this build cannot run stops
# facetd at start, the default one only keeps the intake off. TAP output.
# Usage: tests/integration/scanner_daemon.sh BUILD_DIR
. "$(dirname "$0")/lib.sh" "$@"
root=$(pwd)
# shellcheck source=../support/mock.sh
. "$root/tests/support/mock.sh"
# shellcheck source=../support/mock_facetd.sh
. "$root/tests/support/mock_facetd.sh"

# The pipeline of the scanner jobs, as `facet run` and facetd's
# Pipeline= (a file) both take it: the post-scan correction, end to end.
PIPELINE_JSON='"auto"'

K400=$root/$MODELS/brilliant.scan-k400.json
K100=$root/$MODELS/brilliant.scan-k100.json
if [ ! -x "$BUILD/fsp-mock" ] || ! command -v jq >/dev/null; then
    echo "1..0 # SKIP needs $BUILD/fsp-mock and jq"
    exit 0
fi
MOCK_DIR=$T/mock
mkdir -p "$MOCK_DIR"
trap 'mock_stop; cleanup' EXIT
PJ=$T/pipeline.json
echo "$PIPELINE_JSON" >"$PJ"
STATE=$T/state
mkdir -p "$STATE"
MLOG=$MOCK_DIR/mock.log

start() { # facetd in the testbed with the scanner pipeline; ARGS...
    mock_facetd_start "$BUILD" "$STATE" --workers 2 --scanner-pipeline "$PJ" "$@" &&
        PIDS+=("$FACETD_PID") && LOG=$FACETD_LOG
}
jobs_of() { # SERIAL: the ids of its jobs, newest first
    curl -s "$URL/v1/jobs?source=usb:$1" | jq -r '.jobs[].id'
}
njobs() { jobs_of "$1" | grep -c .; }
# new_job SERIAL N: waits until SERIAL has more than N jobs; sets ID to
# the newest
new_job() {
    local i
    ID=""
    for i in $(seq 1 $((200 * SLOW))); do
        if [ "$(njobs "$1")" -gt "$2" ]; then
            ID=$(jobs_of "$1" | head -n 1)
            return 0
        fi
        sleep 0.05
    done
    return 1
}
scanner() { # SERIAL FIELD: a field of the scanner in GET /v1/scanners
    curl -s "$URL/v1/scanners" |
        jq -r --arg s "$1" ".scanners[] | select(.serial == \$s) | .$2"
}
wait_scanner() { # SERIAL FIELD VALUE
    local i
    for i in $(seq 1 $((200 * SLOW))); do
        [ "$(scanner "$1" "$2")" = "$3" ] && return 0
        sleep 0.05
    done
    return 1
}
result_for() { # SERIAL JOB: the device got a RESULT naming JOB
    wait_line "$MLOG" "^event $1 result \\{\"job\":\"$2\",\"state\":\"succeeded\"" $((10 * SLOW))
}
normalised() { jq -S 'walk(if type == "object" then del(.ms) else . end)' "$1"; }

mock_start "$BUILD" || { not_ok "the testbed starts"; finish; exit 1; }
start || { not_ok "facetd starts in the testbed"; sed 's/^/#   /' "$FACETD_LOG"; finish; exit 1; }
ok "facetd starts in the testbed with the scanner intake"

# --- bulk: plug, list, scan, job, offline equality, RESULT ---------------
mock_cmd plug bulk SN-B1 >/dev/null
wait_scanner SN-B1 state idle
check "a plugged bulk scanner is listed by GET /v1/scanners" \
    test "$(scanner SN-B1 transport)/$(scanner SN-B1 usb_id)" = bulk/1d50:6150

mock_cmd model SN-B1 "$K400" >/dev/null && mock_cmd scan SN-B1 >/dev/null
new_job SN-B1 0 && wait_job "$ID"
B1=$ID
req GET "/v1/jobs/$B1"
expect_eq "its 400-contour scan is a high-priority job with source usb:SN-B1 that succeeds" \
    "usb:SN-B1 high succeeded" "$(jstr source) $(jstr priority) $(jstr state)"
"$BUILD/facet" run "$PJ" "$K400" -o "$T/offline.json" --stats "$T/offline.stats" 2>/dev/null
curl -s -o "$T/served.json" "$URL/v1/jobs/$B1/model?format=json"
curl -s -o "$T/served.stats" "$URL/v1/jobs/$B1/stats"
check "the served model equals facet run's with the same pipeline" \
    cmp -s "$T/served.json" "$T/offline.json"
check "the served statistics equal facet run's (timings aside)" \
    test "$(normalised "$T/served.stats")" = "$(normalised "$T/offline.stats")"
result_for SN-B1 "$B1"
check "the scanner got a RESULT frame naming the job" test $? -eq 0
fb=$(jq -r '.summary.facets_before' "$BODY")
check "the RESULT carries the job's facet counts ($fb before)" \
    grep -qE "^event SN-B1 result .*\"job\":\"$B1\".*\"facets_before\":$fb,\"facets_after\":[0-9]+,\"valid\":true" "$MLOG"
check "the scanner's last job is that job" test "$(scanner SN-B1 last_job)" = "$B1"
lat=$(sed -n "s/.*job=$B1 RESULT (succeeded) to scanner SN-B1 \([0-9.]*\) ms after.*/\1/p" "$LOG")
rate=$(sed -n "s/.*job=$B1 queued from scanner .*received in [0-9.]* ms (\([0-9.]*\) MB\/s).*/\1/p" "$LOG")
echo "# SCAN_DONE to RESULT over bulk: ${lat:-?} ms; intake ${rate:-?} MB/s"
check "the time from SCAN_DONE to RESULT is measured (${lat:-none} ms)" test -n "$lat"

# --- hidraw ----------------------------------------------------------------
mock_cmd plug hid SN-H1 >/dev/null
wait_scanner SN-H1 state idle
mock_cmd model SN-H1 "$K400" >/dev/null && mock_cmd scan SN-H1 >/dev/null
new_job SN-H1 0 && wait_job "$ID"
H1=$ID
curl -s -o "$T/h1.json" "$URL/v1/jobs/$H1/model?format=json"
result_for SN-H1 "$H1"
r=$?
check "the same scan over hidraw gives the same model and a RESULT" \
    test $r -eq 0 -a "$STATE_OF" = succeeded -a "$(scanner SN-H1 transport)" = hid
check "... equal to the bulk one" cmp -s "$T/h1.json" "$T/served.json"

# --- a corrupted frame -------------------------------------------------------
crc0=$(metric facetd_scanner_crc_errors_total)
mock_cmd corrupt SN-B1 model 3 >/dev/null && mock_cmd scan SN-B1 >/dev/null
new_job SN-B1 1 && wait_job "$ID"
curl -s -o "$T/b2.json" "$URL/v1/jobs/$ID/model?format=json"
check "a MODEL frame with a bad CRC is NAKed and sent again; the scan still succeeds" \
    test "$STATE_OF" = succeeded -a "$(metric facetd_scanner_crc_errors_total)" -gt "$crc0"
check "... with the whole model" cmp -s "$T/b2.json" "$T/served.json"
grep -qE '^event SN-B1 nak [0-9]+' "$MLOG"
check "the device saw the NAK" test $? -eq 0
result_for SN-B1 "$ID" >/dev/null

# --- a model that does not parse --------------------------------------------
echo 'not a model' >"$T/bad.json"
ref0=$(metric 'facetd_scanner_scans_refused_total{reason="invalid_model"}')
ab0=$(count_lines "$MLOG" '^event SN-B1 aborted')
n0=$(njobs SN-B1)
mock_cmd model SN-B1 "$T/bad.json" >/dev/null && mock_cmd scan SN-B1 >/dev/null
wait_count "$MLOG" '^event SN-B1 aborted' $((ab0 + 1)) $((10 * SLOW))
check "a scan whose model does not parse is refused: ABORT instead of the ACK, no job" \
    test $? -eq 0 -a "$(njobs SN-B1)" -eq "$n0" -a \
         "$(metric 'facetd_scanner_scans_refused_total{reason="invalid_model"}')" -gt "$ref0"
mock_cmd model SN-B1 "$K400" >/dev/null

# --- unplugged mid-scan ----------------------------------------------------
drop0=$(metric 'facetd_scanner_scans_total{outcome="dropped"}')
n0=$(njobs SN-B1)
mock_cmd unplug-after SN-B1 5 >/dev/null && mock_cmd scan SN-B1 >/dev/null
wait_scanner SN-B1 state offline
check "a scanner unplugged mid-scan is listed offline" test $? -eq 0
sleep 0.3
check "its partial scan makes no job" test "$(njobs SN-B1)" -eq "$n0"
check "the dropped-scan counter moves" \
    test "$(metric 'facetd_scanner_scans_total{outcome="dropped"}')" -gt "$drop0"
check "the daemon keeps serving" \
    test "$(curl -s -o /dev/null -w '%{http_code}' "$URL/readyz")" = 200
req POST /v1/scanners/SN-B1/scan
expect_eq "POST /v1/scanners/{serial}/scan to an offline scanner is 409" "409 scanner-offline" \
    "$CODE $(jstr type | sed 's/.*://')"
mock_cmd plug bulk SN-B1 >/dev/null
wait_scanner SN-B1 state idle
mock_cmd model SN-B1 "$K100" >/dev/null && mock_cmd scan SN-B1 >/dev/null
new_job SN-B1 "$n0" && wait_job "$ID" && result_for SN-B1 "$ID"
check "a re-plugged scanner scans again" test $? -eq 0

# --- two at once -------------------------------------------------------------
nb=$(njobs SN-B1)
nh=$(njobs SN-H1)
mock_cmd model SN-B1 "$K400" >/dev/null
JB=; JH=
mock_cmd scan SN-B1 >/dev/null && mock_cmd scan SN-H1 >/dev/null
new_job SN-B1 "$nb" && JB=$ID && new_job SN-H1 "$nh" && JH=$ID &&
    wait_job "$JB" && wait_job "$JH" && result_for SN-B1 "$JB" && result_for SN-H1 "$JH"
r=$?
check "two scanners scan at once, each gets its own RESULT" test $r -eq 0
if [ $r -ne 0 ]; then # what each side saw, for the failure's reader
    echo "# jobs: SN-B1 $nb -> $(njobs SN-B1) (${JB:-none}), SN-H1 $nh -> $(njobs SN-H1) (${JH:-none})"
    tail -n 30 "$MLOG" | sed 's/^/#   mock: /'
    tail -n 30 "$LOG" | sed 's/^/#   facetd: /'
fi
check "both connected" test "$(metric facetd_scanner_devices_connected)" -eq 2

# --- START_SCAN over HTTP ----------------------------------------------------
nh=$(njobs SN-H1)
req POST /v1/scanners/SN-H1/scan -H 'Content-Type: application/json' --data '{"mode":"quick"}'
expect_eq "POST /v1/scanners/SN-H1/scan is 202" "202 quick" "$CODE $(jstr requested_mode)"
wait_scanner SN-H1 state scanning
req POST /v1/scanners/SN-H1/scan
expect_eq "a second one while it scans is 409" "409 scanner-busy" "$CODE $(jstr type | sed 's/.*://')"
new_job SN-H1 "$nh" && wait_job "$ID" && result_for SN-H1 "$ID"
check "the scan it started becomes a job and a RESULT" test $? -eq 0
req POST /v1/scanners/SN-NOPE/scan
expect_eq "an unknown serial is 404" "404 scanner-not-found" "$CODE $(jstr type | sed 's/.*://')"
req POST /v1/scanners/SN-H1/scan -H 'Content-Type: application/json' --data '{"mode":"slow"}'
expect_eq "a bad mode is 422" "422 mode" "$CODE $(jq -r '.errors[0].path' "$BODY")"

# --- SIGHUP reads the pipeline again ------------------------------------------
echo '["inspect", "inspect"]' >"$PJ"
kill -HUP "$FACETD_PID"
i=0
while [ "$(scanner SN-H1 'pipeline | length')" != 2 ] && [ $i -lt $((100 * SLOW)) ]; do
    sleep 0.05
    i=$((i + 1))
done
check "SIGHUP applies a changed scanner pipeline" test "$(scanner SN-H1 'pipeline | length')" = 2
echo "$PIPELINE_JSON" >"$PJ"
kill -HUP "$FACETD_PID"

check "metrics count frames both ways" \
    test "$(metric 'facetd_scanner_frames_total{direction="in"}')" -gt 0 -a \
         "$(metric 'facetd_scanner_frames_total{direction="out"}')" -gt 0
check "metrics count completed scans and RESULT latencies" \
    test "$(metric 'facetd_scanner_scans_total{outcome="completed"}')" -ge 7 -a \
         "$(metric facetd_scanner_result_latency_seconds_count)" -ge 7

# --- a restart between the scan and the end of its job -----------------------
mock_facetd_stop
start --paused || { not_ok "facetd restarts paused"; finish; exit 1; }
wait_scanner SN-B1 state idle
nb=$(njobs SN-B1)
nres=$(count_lines "$MLOG" '^event SN-B1 result ')
acks=$(count_lines "$MLOG" '^event SN-B1 done-acked')
mock_cmd model SN-B1 "$K100" >/dev/null && mock_cmd scan SN-B1 >/dev/null
new_job SN-B1 "$nb"
JR=$ID
wait_count "$MLOG" '^event SN-B1 done-acked' $((acks + 1)) 10
req GET "/v1/jobs/$JR"
expect_eq "a scan taken while the workers are paused is stored, queued and ACKed" \
    "queued $((acks + 1))" "$(jstr state) $(count_lines "$MLOG" '^event SN-B1 done-acked')"
mock_facetd_stop
check "facetd stops cleanly with a scanner job queued" test "${FACETD_STATUS:-1}" = 0
start || { not_ok "facetd restarts"; finish; exit 1; }
wait_job "$JR"
result_for SN-B1 "$JR"
check "after the restart that job runs and its scanner still gets the RESULT" test $? -eq 0
check "... exactly once" test "$(count_lines "$MLOG" '^event SN-B1 result ')" -eq $((nres + 1))
mock_facetd_stop
check "facetd stops cleanly" test "${FACETD_STATUS:-1}" = 0
! grep -qE 'Sanitizer|runtime error' "$MOCK_DIR"/facetd.*.log
check "no sanitizer report" test $? -eq 0
mock_stop

finish
