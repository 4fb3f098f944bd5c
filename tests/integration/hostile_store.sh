#!/bin/bash
# hostile_store.sh — a full disk under the job store: outcomes the store
# refuses are retried (/readyz says not ready meanwhile, naming the
# store), and the jobs finish once there is room again; a start-up on a
# disk that filled up while facetd was stopped succeeds by giving up the
# disk reserve. The store goes on an 8 MB tmpfs this script mounts, so it
# needs root (skipped otherwise).
. "$(dirname "$0")/lib.sh" "$@"

if [ "$(id -u)" != 0 ]; then
    echo "1..0 # SKIP needs root to mount a small tmpfs for the store"
    exit 0
fi
MNT="$T/mnt"
mkdir -p "$MNT"
if ! mount -t tmpfs -o size=8m tmpfs "$MNT" 2>/dev/null; then
    echo "1..0 # SKIP cannot mount a tmpfs here"
    exit 0
fi
trap 'umount "$MNT" 2>/dev/null; cleanup' EXIT
STATE="$MNT/state"
mkdir -p "$STATE"
STATE_KEEP=1 start_facetd --no-scanners --workers 1 || {
    not_ok "facetd starts"; finish; exit 1; }
check "start-up made the disk reserve" test -s "$STATE/facetd.reserve"
f=$(body brilliant.scan-k800.json '"correct"')
ids=()
for i in 1 2 3 4; do post_json /v1/jobs "$f"; ids+=("$(jstr id)"); done
dd if=/dev/zero of="$MNT/fill" bs=64k 2>/dev/null
ready=""
for k in $(seq $((100 * SLOW))); do
    req GET /readyz
    [ "$CODE" = 503 ] && grep -q '"path":"store"' "$BODY" && { ready=503; break; }
    sleep 0.1
done
expect_eq "with the disk full, /readyz is 503 naming the store" 503 "$ready"
req GET "/v1/jobs?status=running"
check "the job whose outcome is refused stays running, not lost" \
    grep -q '"state":"running"' "$BODY"
post_json /v1/jobs "$f"
expect_eq "a submission meanwhile is 503 (store full), not 500" 503 "$CODE"
rm -f "$MNT/fill"
all=yes
for id in "${ids[@]}"; do
    wait_job "$id" 30
    [ "$STATE_OF" = succeeded ] || all="no ($id $STATE_OF)"
done
expect_eq "once there is room, all four jobs succeed" yes "$all"
req GET /readyz
expect_eq "and /readyz is 200 again" 200 "$CODE"
stop_facetd
dd if=/dev/zero of="$MNT/fill" bs=4k 2>/dev/null
STATE_KEEP=1 start_facetd --no-scanners --workers 1
check "a start-up on the full disk succeeds" test -n "${PORT:-}" -a "$(curl -s -o /dev/null -w '%{http_code}' "$URL/livez")" = 200
check "... by giving up the reserve" grep -q 'gave up the 2 MiB disk reserve' "$LOG"
stop_facetd
umount "$MNT"
finish
