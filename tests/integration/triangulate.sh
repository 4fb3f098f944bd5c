#!/bin/bash
# triangulate.sh — `facet triangulate` end to end: an F-rep object becomes
# a mesh file in every writable format, the mesh read back is closed and
# free of self-intersections (`facet inspect`), the report is valid JSON
# with the figures, and the exit status is 0 / 1 (bad input, message
# naming the place) / 2 (usage).
# Usage: tests/integration/triangulate.sh BUILD_DIR   (TAP output)
set -u
B=${1:-build}
FACET="$B/facet"
D=tests/data/frep
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
n=0
ok() { n=$((n + 1)); echo "ok $n - $1"; }
not_ok() { n=$((n + 1)); echo "not ok $n - $1"; }
check() { # description, command...
    local d=$1
    shift
    if "$@"; then ok "$d"; else not_ok "$d"; fi
}

check "ellipsoid to json exits 0" "$FACET" triangulate "$D/ellipsoid.json" \
    -o "$T/e.json" --quad-levels 6 --binary-levels 7 --metrics "$T/m.json"
check "the report holds the figures" python3 -c '
import json, sys
m = json.load(open(sys.argv[1]))
assert m["triangles"] > 1000 and m["holes"]["left_open"] == 0
assert m["topology"]["self_intersections"] == 0
assert m["deviation"]["max"] < 1e-9
assert set(m["time"]) >= {"sample", "connect", "fill", "sharpen", "total"}
' "$T/m.json"
"$FACET" inspect "$T/e.json" >"$T/i.json"
check "the mesh read back is closed, outward, without self-intersections" \
    python3 -c '
import json, sys
s = json.load(open(sys.argv[1]))
assert s["closed"] and s["orientation"] == "outward"
assert s["nonmanifold_edges"] == 0 and s["nonmanifold_vertices"] == 0
assert s["self_intersections"]["count"] == 0
' "$T/i.json"
for f in obj stl ply ase; do
    check "writes $f" "$FACET" triangulate "$D/torus.json" -o "$T/t.$f" \
        --quad-levels 5 --binary-levels 6 --fair length --fill edges
done
check "gem with --no-refine --fair none exits 0" "$FACET" triangulate \
    "$D/gem.json" -o "$T/g.obj" --quad-levels 5 --binary-levels 6 \
    --no-refine --fair none
printf '{"format":"frep-object/1","bounds":[[-1,-1,-1],[1,1,1]],"shape":{"sphere":{"center":[0,0,0],"radius":"x"}}}' >"$T/bad.json"
out=$("$FACET" triangulate "$T/bad.json" -o "$T/b.obj" 2>&1)
check "bad input exits 1" test $? -eq 1
check "the message names the place" grep -q 'shape.sphere.radius: expected a number' <<<"$out"
"$FACET" triangulate "$D/sphere.json" >/dev/null 2>&1
check "missing -o is a usage error" test $? -eq 2
"$FACET" triangulate "$D/sphere.json" -o "$T/s.obj" --quad-levels 30 >/dev/null 2>&1
check "levels out of range are a usage error" test $? -eq 2
echo "1..$n"
