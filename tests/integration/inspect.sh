#!/bin/bash
# `facet inspect` and `facet orient` on the sample models: the JSON says
# what the models are, defects still exit 0, unreadable input exits 1,
# usage errors 2, and orient repairs the flipped and the inverted model.
# Usage: tests/integration/inspect.sh BUILD_DIR   (TAP output)
set -u
B=${1:-build}
F="$B/facet"
M=tests/data/models
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
n=0
ok() { n=$((n + 1)); echo "ok $n - $1"; }
no() { n=$((n + 1)); echo "not ok $n - $1"; }
check() { if eval "$2"; then ok "$1"; else no "$1"; fi; }

echo "1..12"
"$F" inspect "$M/brilliant.scan-k400.json" --threads 2 >"$T/k400" 2>"$T/err"
check "scan K=400 inspects as valid" \
    '[ $? -eq 0 ] && grep -q "\"valid\": true" "$T/k400"'
check "scan K=400 has the documented keys" \
    'for k in vertices edges facets closed boundary_edges holes nonmanifold_edges nonmanifold_vertices orientation inconsistent_facets volume area max_nonplanarity nonconvex_facets degenerate_facets self_intersections self_intersecting_facets near_coplanar_pairs vertex_degrees short_edge_clusters valid; do grep -q "\"$k\":" "$T/k400" || exit 1; done'

"$F" inspect "$M/notch-cube.flipped.json" >"$T/flip"
check "flipped facet: exit 0, inconsistent, one facet" \
    '[ $? -eq 0 ] && grep -q "\"orientation\": \"inconsistent\"" "$T/flip" && grep -q "\"inconsistent_facets\": 1," "$T/flip"'

"$F" inspect "$M/brilliant.holes.json" >"$T/holes"
check "two holes" 'grep -q "\"holes\": 2," "$T/holes" && grep -q "\"closed\": false" "$T/holes"'

"$F" inspect "$M/brilliant.selfint.json" --pairs 1 >"$T/si"
check "self-intersecting: one pair listed, count complete" \
    '[ $? -eq 0 ] && [ "$(grep -c "^        [0-9]" "$T/si")" -eq 2 ] && grep -q "\"count\": [3-9]" "$T/si" && grep -q "\"valid\": false" "$T/si"'

"$F" inspect "$T/missing.json" >/dev/null 2>"$T/err"
check "unreadable model exits 1 naming the file" \
    '[ $? -eq 1 ] && grep -q "missing.json" "$T/err"'

"$F" inspect >/dev/null 2>&1
check "no model is a usage error (2)" '[ $? -eq 2 ]'
"$F" inspect "$M/l-prism.json" --pairs -3 >/dev/null 2>&1
check "bad --pairs is a usage error (2)" '[ $? -eq 2 ]'

"$F" orient "$M/notch-cube.flipped.json" -o "$T/fixed.json" 2>"$T/err"
check "orient repairs the flipped facet" \
    '[ $? -eq 0 ] && grep -q "1 facet reversed" "$T/err" && "$F" inspect "$T/fixed.json" | grep -q "\"valid\": true"'

# an inverted model: every facet reversed (through OBJ, which keeps order)
"$F" convert "$M/brilliant.truth.json" "$T/t.obj" &&
    awk '/^f /{printf "f"; for (i = NF; i > 1; i--) printf " %s", $i; print ""; next} {print}' "$T/t.obj" >"$T/inv.obj"
"$F" inspect "$T/inv.obj" >"$T/inv"
check "inverted model is inward" 'grep -q "\"orientation\": \"inward\"" "$T/inv"'
"$F" orient "$T/inv.obj" -o "$T/inv-fixed.json" 2>/dev/null
check "orient turns the inverted model outward" \
    '[ $? -eq 0 ] && "$F" inspect "$T/inv-fixed.json" | grep -q "\"orientation\": \"outward\""'
"$F" orient "$M/l-prism.json" >/dev/null 2>&1
check "orient without -o is a usage error (2)" '[ $? -eq 2 ]'
