#!/bin/bash
# viewer.sh — the web viewer's figures in headless Chromium with software
# GL (SwiftShader), in real time (tests/bench/viewer_fps.py drives the
# browser over the DevTools pipe): for the corrected k400 scan and a
# 10^6-triangle sphere, the time from opening /#/jobs/{id} to the first
# frame, and the frame rate while orbiting (coarse copy for the sphere)
# and drawing every frame in full; the size of the served assets.
# Prints "name: value unit" lines. Usage: viewer.sh BUILD_DIR
set -u
B=${1:-build}
SECS=${BENCH_SECONDS:-5}
T=$(mktemp -d /tmp/facetd-bench.XXXXXX)
trap 'kill "$PID" 2>/dev/null; wait "$PID" 2>/dev/null; rm -rf "$T"' EXIT
CHROME=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$CHROME" ] || ! command -v python3 >/dev/null; then
    echo "viewer: skipped (needs chromium and python3: make deps)"
    exit 0
fi
if [ ! -x "$B/facetd" ] || [ ! -x "$B/tools/gen_scanmesh" ]; then
    echo "viewer: build $B/facetd and $B/tools/gen_scanmesh first (make bench)"
    exit 1
fi
"$B/facetd" --listen 127.0.0.1:0 --state-dir "$T/state" --max-body 256M \
    --workers 1 --log-level notice >"$T/log" 2>&1 &
PID=$!
for i in $(seq 100); do
    PORT=$(sed -n 's|.*listening on http://127\.0\.0\.1:\([0-9]*\).*|\1|p' "$T/log")
    [ -n "$PORT" ] && break
    sleep 0.1
done
URL="http://127.0.0.1:$PORT"
echo "# $(nproc) CPUs; load average $(cut -d' ' -f1-3 /proc/loadavg)"

# submit TYPE FILE PIPELINE: prints the finished job's id
submit() {
    local id
    id=$(curl -s -H "Content-Type: $1" --data-binary "@$2" \
        "$URL/v1/jobs?format=$3&pipeline=$4" | sed -n 's/.*"id":"\([0-9A-Z]*\)".*/\1/p')
    curl -s "$URL/v1/jobs/$id?wait=120" >/dev/null
    echo "$id"
}
bytes=0
for f in / $(curl -s "$URL/" | grep -o '/ui/[a-z.]*' | sort -u) \
    $(for m in api jobs job model gl submit scanners boot app; do echo "/ui/$m.js"; done | sort -u); do
    bytes=$((bytes + $(curl -s "$URL$f" | wc -c)))
done
echo "viewer_assets: $bytes bytes"

k400=$(submit application/json tests/data/models/brilliant.scan-k400.json json correct,report)
"$B/tools/gen_scanmesh" --triangles 1000000 --sphere --radius 5 "$T/sphere.obj" >/dev/null
sphere=$(submit application/octet-stream "$T/sphere.obj" obj inspect)
for case in "k400 $k400" "sphere_1m $sphere"; do
    set -- $case
    python3 tests/bench/viewer_fps.py "$CHROME" "$URL/#/jobs/$2?bench=$((SECS * 1000))" 180 >"$T/fig"
    fig() { sed -n "s/^$1: //p" "$T/fig"; }
    echo "viewer_${1}_triangles: $(fig triangles) (orbiting: $(fig coarseTriangles))"
    echo "viewer_${1}_first_frame: $(fig firstFrameMs) ms (page parse and build $(fig loadMs) ms)"
    echo "viewer_${1}_fps_orbit: $(fig fps) fps"
    echo "viewer_${1}_fps_full: $(fig fpsFull) fps"
done
