#!/bin/bash
# idle.sh — an idle facetd (scanner intake on, the default; workers, the
# waiter hub's timer, the job monitor, the RESULT sender all waiting) uses
# no CPU: every thread sleeps until it has something to do. A thread
# whose timed wait ends at once (a deadline on the wrong clock) would
# burn a core, and every benchmark with it.
. "$(dirname "$0")/lib.sh" "$@"

start_facetd || { not_ok "facetd starts"; finish; exit 1; }
sleep 1
ticks() { awk '{print $14 + $15}' "/proc/$PID/stat"; }
t0=$(ticks)
sleep 3
t1=$(ticks)
# a spinning thread takes ~300 ticks in 3 s; waking every 100 ms a few
check "an idle facetd takes at most 5 ticks of CPU in 3 s ($((t1 - t0)))" \
    test $((t1 - t0)) -le 5
submit notch-cube.json
wait_job "$ID"
expect_eq "a job still runs" succeeded "$STATE_OF"
t0=$(ticks)
sleep 3
t1=$(ticks)
check "and afterwards it is idle again ($((t1 - t0)) ticks)" \
    test $((t1 - t0)) -le 5

finish
