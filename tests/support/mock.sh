# mock.sh — bash helpers that drive fsp-mock, the mocked USB scanner
# harness, from the integration tests (source it). The harness reads
# commands from the FIFO $MOCK_DIR/ctl and logs replies and events to
# $MOCK_DIR/mock.log (see tests/mock/mock_main.c for the commands).

# wait_line FILE REGEX [SECONDS]: waits until a line of FILE matches the
# extended REGEX; fails after SECONDS (default 10).
wait_line() {
    # deadlines are generous (×MOCK_TIME_SCALE, default 4): a wait ends as
    # soon as its line appears, and a loaded CI machine must not fail it
    local file=$1 re=$2 secs=$(( ${3:-10} * ${MOCK_TIME_SCALE:-4} )) i=0
    while [ "$i" -lt $((secs * 20)) ]; do
        if [ -f "$file" ] && grep -qE -- "$re" "$file"; then
            return 0
        fi
        sleep 0.05
        i=$((i + 1))
    done
    return 1
}

# count_lines FILE REGEX: prints how many lines of FILE match REGEX.
count_lines() {
    if [ -f "$1" ]; then grep -cE -- "$2" "$1"; else echo 0; fi
}

# wait_count FILE REGEX N [SECONDS]: waits until at least N lines match.
wait_count() {
    local file=$1 re=$2 n=$3 secs=$(( ${4:-10} * ${MOCK_TIME_SCALE:-4} )) i=0
    while [ "$i" -lt $((secs * 20)) ]; do
        [ "$(count_lines "$file" "$re")" -ge "$n" ] && return 0
        sleep 0.05
        i=$((i + 1))
    done
    return 1
}

# mock_start BUILD_DIR [-- PROGRAM ARGS...]: starts the harness in the
# background with its files in $MOCK_DIR (which must exist); sets
# MOCK_PID. Returns once the testbed is ready.
mock_start() {
    local b=$1
    shift
    "$b/fsp-mock" --control "$MOCK_DIR/ctl" --log "$MOCK_DIR/mock.log" "$@" &
    MOCK_PID=$!
    wait_line "$MOCK_DIR/mock.log" '^ready ' 10
}

# mock_cmd COMMAND...: sends one command and waits for its reply, which
# it prints; succeeds when the reply is "ok ...".
mock_cmd() {
    local log=$MOCK_DIR/mock.log n
    n=$(count_lines "$log" '^(ok|err) ')
    echo "$*" >"$MOCK_DIR/ctl"
    wait_count "$log" '^(ok|err) ' $((n + 1)) 10 || return 1
    local reply
    reply=$(grep -E '^(ok|err) ' "$log" | sed -n "$((n + 1))p")
    echo "$reply"
    case "$reply" in ok*) return 0 ;; *) return 1 ;; esac
}

# mock_stop: asks the harness to quit (it stops its program) and waits.
mock_stop() {
    [ -n "${MOCK_PID:-}" ] || return 0
    echo quit >"$MOCK_DIR/ctl" 2>/dev/null
    local i=0
    while kill -0 "$MOCK_PID" 2>/dev/null && [ "$i" -lt 200 ]; do
        sleep 0.05
        i=$((i + 1))
    done
    kill "$MOCK_PID" 2>/dev/null
    wait "$MOCK_PID" 2>/dev/null
    MOCK_PID=
}
