# mock_facetd.sh — bash helpers that run facetd inside the fsp-mock
# testbed (source after mock.sh, with MOCK_DIR set and the harness
# started by mock_start): facetd then sees the mocked scanners through
# unmodified libusb, hidapi and libudev.

# mock_facetd_start BUILD_DIR STATE_DIR ARGS...: starts facetd on a free
# loopback port with its store in STATE_DIR and its log in a new file;
# sets URL, FACETD_LOG and FACETD_PID. Fails if it does not get ready.
mock_facetd_start() {
    local b=$1 state=$2 a i port
    shift 2
    FACETD_LOG=$(mktemp "$MOCK_DIR/facetd.XXXXXX.log")
    local w=$FACETD_LOG.sh
    # the harness splits its commands on blanks: the arguments go through
    # a script
    {
        echo '#!/bin/sh'
        printf 'exec'
        for a in "$b/facetd" --listen 127.0.0.1:0 --state-dir "$state" "$@"; do
            printf " '%s'" "$a"
        done
        printf " >>'%s' 2>&1\n" "$FACETD_LOG"
    } >"$w"
    chmod +x "$w"
    local reply
    reply=$(mock_cmd run "$w") || return 1
    FACETD_PID=${reply##* }
    for i in $(seq 1 200); do
        port=$(sed -n 's|.*listening on http://127\.0\.0\.1:\([0-9]*\).*|\1|p' "$FACETD_LOG" | head -n 1)
        [ -n "$port" ] && break
        kill -0 "$FACETD_PID" 2>/dev/null || return 1
        sleep 0.05
    done
    [ -n "$port" ] || return 1
    URL="http://127.0.0.1:$port"
    for i in $(seq 1 200); do
        [ "$(curl -s -o /dev/null -w '%{http_code}' "$URL/readyz")" = 200 ] && return 0
        sleep 0.05
    done
    return 1
}

# mock_facetd_stop: SIGTERM to facetd, waits until it has exited; sets
# FACETD_STATUS to its exit status.
mock_facetd_stop() {
    local n
    n=$(count_lines "$MOCK_DIR/mock.log" '^child-exit ')
    mock_cmd kill >/dev/null || return 1
    wait_count "$MOCK_DIR/mock.log" '^child-exit ' $((n + 1)) 30 || return 1
    FACETD_STATUS=$(grep '^child-exit ' "$MOCK_DIR/mock.log" | tail -n 1 | cut -d' ' -f2)
}
