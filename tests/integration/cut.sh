#!/bin/bash
# cut.sh — `facet cut` end to end: the one-line JSON summary, the result
# file, unchanged/empty results and the exit codes. Usage: cut.sh BUILD_DIR
B=${1:-build}
F="$B/facet"
M=tests/data/models
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
n=0
check() { # $1 description, $2 condition (evaluated)
    n=$((n + 1))
    if eval "$2"; then echo "ok $n - $1"; else echo "not ok $n - $1"; fi
}

out=$("$F" cut "$M/notch-cube.json" --plane 0,0,1,-8 -o "$tmp/a.json")
rc=$?
check "cut across the notch succeeds" '[ $rc -eq 0 ]'
check "summary is one line of JSON" '[ "$(printf "%s\n" "$out" | wc -l)" -eq 1 ] && [[ $out == "{"*"}" ]]'
check "summary counts one component" '[[ $out == *"\"components\":1,"* ]]'
check "summary has both volumes" '[[ $out == *"\"volume_before\":936,"* && $out == *"\"volume_after\":768,"* ]]'
check "result file is a readable model" '"$F" convert "$tmp/a.json" "$tmp/a.obj"'

out=$("$F" cut "$M/notch-cube.json" --plane 0,0,1,-80 -o "$tmp/b.json")
check "a plane above the model leaves it unchanged" '[[ $out == *"\"unchanged\":true"* && $out == *"\"empty\":false"* ]]'
out=$("$F" cut "$M/notch-cube.json" --plane 0,0,-1,80 -o "$tmp/c.json")
rc=$?
check "the opposite side is empty, not an error" '[ $rc -eq 0 ] && [[ $out == *"\"empty\":true"* ]]'

out=$("$F" cut "$M/brilliant.scan-k400.json" --plane 0.2,0.1,1,0.3 -o "$tmp/d.ply")
rc=$?
check "a scan cut to PLY" '[ $rc -eq 0 ] && [ -s "$tmp/d.ply" ] && [[ $out == *"\"components\":1,"* ]]'

out=$("$F" cut "$M/notch-cube.json" --plane 1,1,1,-16 -o "$tmp/e.json")
rc=$?
check "a section with a hole takes two facets" '[ $rc -eq 0 ] && [[ $out == *"\"components\":1,\"new_facets\":2,"* ]]'
check "the holed cut is a valid model" '"$F" inspect "$tmp/e.json" | grep -q "\"valid\": true"'
"$F" cut "$M/notch-cube.json" --plane -48,0,-32,480 -o "$tmp/h.json" 2>"$tmp/err"
rc=$?
check "a pinch along a reflex edge is refused with the way out (exit 1)" '[ $rc -eq 1 ] && grep -q "reflex edge" "$tmp/err" && grep -q "plane\[3\]" "$tmp/err"'
"$F" cut "$M/notch-cube.json" --plane 1,2 -o "$tmp/f.json" 2>/dev/null
rc=$?
check "a malformed plane is a usage error (exit 2)" '[ $rc -eq 2 ]'
"$F" cut "$M/notch-cube.json" -o "$tmp/f.json" 2>/dev/null
rc=$?
check "a missing plane is a usage error (exit 2)" '[ $rc -eq 2 ]'
"$F" cut "$M/brilliant.holes.json" --plane 0,0,1,0 -o "$tmp/g.json" 2>"$tmp/err"
rc=$?
check "an open model is bad input (exit 1)" '[ $rc -eq 1 ] && grep -q "closed" "$tmp/err"'
check "--help exits 0" '"$F" cut --help >/dev/null'
echo "1..$n"
