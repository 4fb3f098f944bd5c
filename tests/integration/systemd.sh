#!/bin/bash
# systemd.sh — running under systemd: `make install` puts the units,
# tmpfiles, sysusers and example configuration in place and
# `systemd-analyze verify` accepts the units; the notify protocol (READY=1,
# STATUS=, WATCHDOG=1 when a watchdog is set, RELOADING=1 on SIGHUP,
# STOPPING=1 on SIGTERM); socket activation through sd_listen_fds; and
# the configuration: --help, drop-ins, a bad reload keeping the old values.
. "$(dirname "$0")/lib.sh" "$@"

# make install into a private prefix (the build is already up to date).
san=0
case "$BUILD" in *asan*) san=1 ;; esac
root="$T/root"
if make --no-print-directory -s install PREFIX="$root/usr" SANITIZE=$san >"$T/install.log" 2>&1; then
    ok "make install succeeds"
else
    not_ok "make install succeeds" "$(tail -n 5 "$T/install.log")"
fi
for f in bin/facetd bin/facet lib/systemd/system/facetd.service \
         lib/systemd/system/facetd.socket lib/tmpfiles.d/facetd.conf \
         lib/sysusers.d/facetd.conf share/doc/facetd/facetd.conf.example \
         lib/udev/rules.d/70-facetd-scanners.rules share/man/man1/facet.1 \
         share/man/man5/facetd.conf.5 share/man/man8/facetd.8 \
         share/doc/facetd/docs/README.md; do
    check "installed: $f" test -s "$root/usr/$f"
done
check "the unit runs the installed facetd" \
    grep -qx "ExecStart=$root/usr/bin/facetd" "$root/usr/lib/systemd/system/facetd.service"
if command -v systemd-analyze >/dev/null; then
    # its man: links are looked up in the installed pages
    if MANPATH="$root/usr/share/man" systemd-analyze verify "$root/usr/lib/systemd/system/facetd.service" \
        "$root/usr/lib/systemd/system/facetd.socket" >"$T/verify" 2>&1; then
        ok "systemd-analyze verify accepts the units"
    else
        not_ok "systemd-analyze verify accepts the units" "$(head -n 5 "$T/verify")"
    fi
else
    skip "systemd-analyze verify (systemd-analyze is not installed)"
fi
for key in Type=notify WatchdogSec= ProtectSystem=strict ProtectHome=yes \
           PrivateTmp=yes NoNewPrivileges=yes RestrictAddressFamilies= \
           DeviceAllow=char-hidraw DeviceAllow=char-usb_device StateDirectory=facetd; do
    check "the service sets $key" grep -q "^$key" "$root/usr/lib/systemd/system/facetd.service"
done

# The notify protocol.
mkdir "$T/n"
touch "$T/n/out"
"$BUILD/tools/notify_listen" "$T/n/sock" 300000 -- "$FACETD" \
    --listen 127.0.0.1:0 --state-dir "$T/n/state" >"$T/n/out" 2>"$T/n/log" &
nl=$!
for i in $(seq $((50 * SLOW))); do grep -q '^READY=1' "$T/n/out" && break; sleep 0.1; done
fpid=$(sed -n 's/^PID //p' "$T/n/out")
check "READY=1 once serving, with the address in STATUS" \
    grep -q '^READY=1 STATUS=listening on 127.0.0.1:' "$T/n/out"
sleep 0.5
check "WATCHDOG=1 pings while healthy" grep -q '^WATCHDOG=1' "$T/n/out"
check "STATUS= reports the queue" grep -q '^STATUS=[0-9]* queued, [0-9]* running' "$T/n/out"
kill -HUP "$fpid"
for i in $(seq 30); do grep -q '^RELOADING=1' "$T/n/out" && break; sleep 0.1; done
check "SIGHUP sends RELOADING=1" grep -q '^RELOADING=1' "$T/n/out"
kill -TERM "$fpid"
wait $nl
expect_eq "SIGTERM ends facetd with status 0" 0 $?
check "SIGTERM sends STOPPING=1" grep -q '^STOPPING=1' "$T/n/out"

# Socket activation.
if command -v systemd-socket-activate >/dev/null; then
    for try in 1 2 3 4 5; do
        sport=$((20000 + RANDOM % 40000))
        systemd-socket-activate -l "127.0.0.1:$sport" "$FACETD" \
            --state-dir "$T/sa" >"$T/sa.log" 2>&1 &
        sa=$!
        sleep 0.2
        kill -0 $sa 2>/dev/null && break
    done
    code=""
    for i in $(seq $((50 * SLOW))); do
        code=$(curl -s -o /dev/null -w '%{http_code}' "http://127.0.0.1:$sport/readyz")
        [ "$code" = 200 ] && break; sleep 0.1
    done
    expect_eq "facetd serves on the socket systemd passed" 200 "$code"
    check "it says it took the passed socket" grep -q "listening on http://127.0.0.1:$sport" "$T/sa.log"
    kill -TERM $sa; wait $sa
else
    skip "socket activation (systemd-socket-activate is not installed)"
fi

# Configuration.
"$FACETD" --help >"$T/help"
for flag in --listen --state-dir --workers --queue-size --max-body \
            --job-timeout --retention-age --retention-bytes --api-token; do
    check "--help lists $flag" grep -q -- "$flag" "$T/help"
done
"$FACETD" --workers=many >/dev/null 2>"$T/bad"
expect_eq "a bad flag value exits with 2" 2 $?
check "and names the flag" grep -q -- '--workers: Workers: expected a whole number' "$T/bad"
conf="$T/c.conf"
mkdir "$conf.d"
printf '[Jobs]\nQueueSize=7\nWorkers=2\n' >"$conf"
printf '[Jobs]\nQueueSize=9\n' >"$conf.d/50-local.conf"
start_facetd -c "$conf" || { not_ok "facetd starts with -c"; finish; exit 1; }
expect_eq "a drop-in overrides the file" 9 "$(metric facetd_queue_capacity)"
printf '[Jobs]\nQueueSize=eleven\n' >"$conf.d/60-bad.conf"
kill -HUP "$PID"
for i in $(seq 30); do grep -q 'reload failed' "$LOG" && break; sleep 0.1; done
check "a bad reload is refused with the place" grep -q 'reload failed.*60-bad.conf:2: QueueSize' "$LOG"
expect_eq "and the running value stays" 9 "$(metric facetd_queue_capacity)"
printf '[Jobs]\nQueueSize=11\nWorkers=3\n' >"$conf.d/60-bad.conf"
kill -HUP "$PID"
for i in $(seq 30); do [ "$(metric facetd_queue_capacity)" = 11 ] && break; sleep 0.1; done
expect_eq "a good reload applies" 11 "$(metric facetd_queue_capacity)"
check "a restart-only key is reported, not applied" grep -q 'Jobs.Workers changed; a restart is needed' "$LOG"
expect_eq "the running worker count stays" 2 "$(metric facetd_workers)"
finish
