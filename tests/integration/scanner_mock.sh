#!/bin/bash
# scanner_mock.sh — the scanner library, through unmodified libusb,
# hidapi and libudev, against mocked scanners (fsp-mock on a umockdev
# testbed): a 400-contour scan over bulk and over hidraw arrives byte for
# byte, a corrupted frame is NAKed and sent again, a wrong model CRC is
# NAKed three times and dropped, unplugging mid-scan drops only that
# partial scan, a re-plugged scanner scans again, two scanners scan at
# once, a silent scanner is given up, START_SCAN from the host works,
# RESULTs reach a scanner in the order of its scans, and an idle intake
# does not spin. TAP output.
# Usage: tests/integration/scanner_mock.sh BUILD_DIR
set -u
B=${1:-build}
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
# shellcheck source=../support/mock.sh
. "$root/tests/support/mock.sh"
MODEL=$root/tests/data/models/brilliant.scan-k400.json
SMALL=$root/tests/data/models/brilliant.scan-k100.json

MOCK_DIR=$(mktemp -d)
WATCH=$MOCK_DIR/watch.log
n=0
failed=0
ok() {
    n=$((n + 1))
    if [ "$1" -eq 0 ]; then echo "ok $n - $2"; else
        echo "not ok $n - $2"
        failed=1
    fi
}
cleanup() {
    exec 7>&- 2>/dev/null
    mock_stop
    if [ "$failed" -ne 0 ] && [ -n "${FACET_KEEP_LOGS:-}" ]; then
        echo "# logs kept in $MOCK_DIR"
    else
        rm -rf "$MOCK_DIR"
    fi
}
trap cleanup EXIT

# watch_start MODE: the harness runs scan_watch, which takes commands from
# the FIFO watch.in (held open here so that it never sees end of file).
watch_start() {
    rm -f "$MOCK_DIR/watch.in" "$MOCK_DIR/ctl"
    mkfifo "$MOCK_DIR/watch.in"
    exec 7<>"$MOCK_DIR/watch.in"
    mock_start "$B" -- sh -c "exec '$B/tools/scan_watch' --out '$MOCK_DIR' \
        --scan-timeout 2000 --resend 1000 --result $1 <'$MOCK_DIR/watch.in' \
        >'$WATCH' 2>'$MOCK_DIR/watch.err'"
    wait_line "$WATCH" '^started' 10
}
watch_cmd() { echo "$*" >&7; }
same_as() { cmp -s "$MOCK_DIR/$1.model" "$2"; }
# acked SERIAL N: the device has seen its Nth SCAN_DONE acknowledged (the
# host reports a scan before its ACK reaches the device)
acked() { wait_count "$MOCK_DIR/mock.log" "^event $1 done-acked" "$2" 20; }
job_of() { # the job of the Nth scan line of SERIAL
    grep -E "^scan $1 " "$WATCH" | sed -n "${2}p" | sed 's/.*job=\([^ ]*\).*/\1/'
}

if [ ! -x "$B/fsp-mock" ] || [ ! -x "$B/tools/scan_watch" ]; then
    echo "1..0 # SKIP $B/fsp-mock or $B/tools/scan_watch not built"
    exit 0
fi
echo "1..15"
watch_start auto

mock_cmd plug bulk SN-B1 >/dev/null
wait_line "$WATCH" '^device SN-B1 kind=bulk path=usb:001/' 10
ok $? "a bulk scanner that appears is opened, greeted and registered"

mock_cmd model SN-B1 "$MODEL" >/dev/null && mock_cmd scan SN-B1 >/dev/null &&
    wait_line "$WATCH" '^scan SN-B1 ' 10 && acked SN-B1 1 &&
    wait_line "$MOCK_DIR/mock.log" '^event SN-B1 result \{"job":"job-1"' 10 &&
    same_as job-1 "$MODEL"
ok $? "a 400-contour scan over bulk arrives byte for byte, RESULT goes back"

mock_cmd plug hid SN-H1 >/dev/null
wait_line "$WATCH" '^device SN-H1 kind=hid path=/dev/hidraw' 10 &&
    mock_cmd model SN-H1 "$MODEL" >/dev/null && mock_cmd scan SN-H1 >/dev/null &&
    wait_line "$WATCH" '^scan SN-H1 ' 20 && acked SN-H1 1
job=$(job_of SN-H1 1)
same_as "$job" "$MODEL" &&
    wait_line "$MOCK_DIR/mock.log" "^event SN-H1 result \\{\"job\":\"$job\"" 10
ok $? "the same scan over hidraw (64-byte reports) arrives byte for byte"

mock_cmd corrupt SN-B1 model 3 >/dev/null && mock_cmd scan SN-B1 >/dev/null
wait_count "$WATCH" '^scan SN-B1 ' 2 10 && acked SN-B1 2
job=$(job_of SN-B1 2)
grep -qE '^event SN-B1 nak [0-9]+' "$MOCK_DIR/mock.log" && same_as "$job" "$MODEL"
ok $? "a MODEL frame with a bad CRC is NAKed, sent again, the scan is whole"

mock_cmd corrupt SN-H1 done >/dev/null && mock_cmd scan SN-H1 >/dev/null
wait_line "$MOCK_DIR/mock.log" '^event SN-H1 dropped' 20 &&
    [ "$(count_lines "$MOCK_DIR/mock.log" '^event SN-H1 nak ')" -eq 3 ] &&
    wait_line "$WATCH" '^notice SN-H1 ERROR 3 ' 10 &&
    [ "$(count_lines "$WATCH" '^scan SN-H1 ')" -eq 1 ]
ok $? "a wrong whole-model CRC is NAKed three times, then the scan is dropped"

mock_cmd unplug-after SN-B1 5 >/dev/null && mock_cmd scan SN-B1 >/dev/null
wait_line "$WATCH" '^gone SN-B1' 10 &&
    grep -q '^notice SN-B1 unplugged during a scan' "$WATCH" &&
    [ "$(count_lines "$WATCH" '^scan SN-B1 ')" -eq 2 ]
ok $? "a scanner unplugged mid-scan loses only that partial scan"

mock_cmd plug bulk SN-B1 >/dev/null
wait_count "$WATCH" '^device SN-B1 ' 2 10 &&
    mock_cmd model SN-B1 "$SMALL" >/dev/null && mock_cmd scan SN-B1 >/dev/null &&
    wait_count "$WATCH" '^scan SN-B1 ' 3 10 && acked SN-B1 3 &&
    same_as "$(job_of SN-B1 3)" "$SMALL"
ok $? "a re-plugged scanner is greeted again and scans again"

mock_cmd model SN-B1 "$MODEL" >/dev/null &&
    mock_cmd scan SN-B1 >/dev/null && mock_cmd scan SN-H1 >/dev/null &&
    wait_count "$WATCH" '^scan SN-B1 ' 4 20 && wait_count "$WATCH" '^scan SN-H1 ' 2 20 &&
    acked SN-B1 4 && acked SN-H1 2 && same_as "$(job_of SN-B1 4)" "$MODEL" && same_as "$(job_of SN-H1 2)" "$MODEL"
ok $? "two scanners (bulk and HID) scan at the same time"

mock_cmd stall SN-B1 after 3 >/dev/null && mock_cmd scan SN-B1 >/dev/null
wait_line "$WATCH" '^notice SN-B1 scan dropped: no frame from the device' 10
r=$?
mock_cmd stall SN-B1 off >/dev/null
wait_line "$MOCK_DIR/mock.log" '^event SN-B1 aborted' 10 && [ $r -eq 0 ]
ok $? "a scanner silent mid-scan is given up after the timeout and sent ABORT"

watch_cmd start SN-B1 1
wait_line "$WATCH" '^ok start SN-B1' 10 && wait_count "$WATCH" '^scan SN-B1 ' 5 10 &&
    acked SN-B1 5 && same_as "$(job_of SN-B1 5)" "$MODEL"
ok $? "START_SCAN from the host starts a scan on the device"

FMB=$MOCK_DIR/k400.fmb
"$B/facet" convert "$MODEL" "$FMB" 2>/dev/null &&
    mock_cmd model SN-B1 "$FMB" fmb1 >/dev/null && mock_cmd scan SN-B1 >/dev/null &&
    wait_count "$WATCH" '^scan SN-B1 ' 6 10 && acked SN-B1 6 &&
    same_as "$(job_of SN-B1 6)" "$FMB"
r=$?
json_model=$(grep -E '^scan SN-B1 ' "$WATCH" | sed -n 1p | sed 's/.*model=//')
fmb_model=$(grep -E '^scan SN-B1 ' "$WATCH" | sed -n 6p | sed 's/.*model=//')
[ $r -eq 0 ] && grep -E '^scan SN-B1 ' "$WATCH" | sed -n 6p | grep -q 'format=fmb1' &&
    [ "$fmb_model" = "$json_model" ] && [ "$fmb_model" != invalid ]
ok $? "an FMB1 scan arrives and parses to the same polyhedron ($fmb_model)"

watch_cmd metrics
wait_line "$WATCH" '^metrics ' 10
m=$(grep '^metrics ' "$WATCH" | tail -n 1)
get() { echo "$m" | sed "s/.* $1=\([0-9]*\).*/\1/"; }
[ "$(get crc_errors)" -ge 1 ] && [ "$(get naks_sent)" -ge 4 ] &&
    [ "$(get devices_connected)" -eq 2 ] && [ "$(get scans_completed)" -eq 8 ] &&
    [ "$(get scans_dropped)" -ge 3 ]
ok $? "metrics count frames, CRC errors, NAKs, devices and scans ($m)"

pid=$(pgrep -f "$B/tools/scan_watch" | head -n 1)
ticks() { awk '{print $14 + $15}' "/proc/$pid/stat"; }
t0=$(ticks)
sleep 2
t1=$(ticks)
# clock ticks are 10 ms: an idle intake (bulk sleeping in poll, HID
# waking ten times a second) must stay far below a core
[ -n "$pid" ] && [ $((t1 - t0)) -le 20 ]
ok $? "an idle intake does not spin ($((t1 - t0)) ticks of CPU in 2 s)"

watch_cmd quit
wait_line "$WATCH" '^stopped' 10 && ! grep -qE 'Sanitizer|runtime error' "$MOCK_DIR/watch.err"
ok $? "the intake stops cleanly (no sanitizer report)"
mock_stop

# RESULTs in scan order: the second scan's job ends first
rm -f "$WATCH"
watch_start manual
mock_cmd plug bulk SN-R1 >/dev/null && mock_cmd model SN-R1 "$SMALL" >/dev/null
wait_line "$WATCH" '^device SN-R1 ' 10 && mock_cmd scan SN-R1 >/dev/null &&
    wait_count "$WATCH" '^scan SN-R1 ' 1 10 && acked SN-R1 1 &&
    mock_cmd scan SN-R1 >/dev/null && wait_count "$WATCH" '^scan SN-R1 ' 2 10
j1=$(job_of SN-R1 1)
j2=$(job_of SN-R1 2)
watch_cmd result SN-R1 "$j2"
wait_line "$WATCH" "^ok result SN-R1 $j2" 10
sleep 0.5
early=$(count_lines "$MOCK_DIR/mock.log" '^event SN-R1 result ')
watch_cmd result SN-R1 "$j1"
wait_count "$MOCK_DIR/mock.log" '^event SN-R1 result ' 2 10
# a RESULT is sent again when its ACK is late (FSP1.md: every 5 s, three
# sends at most), so a loaded machine may log one twice: the order is that
# of first arrivals
order=$(grep '^event SN-R1 result ' "$MOCK_DIR/mock.log" |
    sed 's/.*"job":"\([^"]*\)".*/\1/' | awk '!seen[$0]++' | tr '\n' ' ')
[ "$early" -eq 0 ] && [ "$order" = "$j1 $j2 " ]
ok $? "RESULTs reach the scanner in the order of its scans ($order)"

exit $failed
