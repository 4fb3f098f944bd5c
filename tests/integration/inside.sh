#!/bin/bash
# inside.sh — `facet inside` end to end: answers on the notch cube
# (inside, outside, on facets, edges and vertices), both points forms,
# standard input, errors naming the place, exit codes, and identical
# output for 1 and 2 threads. Usage: inside.sh BUILD_DIR
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

echo '[[5,5,5],[8,5,8],[10,5,5],[0,0,0],[-1,0,0],[6,5,8],[10,3,8]]' >"$tmp/p.json"
out=$("$F" inside "$M/notch-cube.json" "$tmp/p.json")
rc=$?
check "classifies the notch cube points" '[ $rc -eq 0 ]'
check "inside, notch, facet, vertex, outside, notch wall, notch edge" \
    '[ "$out" = "[\"inside\",\"outside\",\"boundary\",\"boundary\",\"outside\",\"boundary\",\"boundary\"]" ]'

out=$(echo '{"points":[[1,1,1],[20,0,0]],"note":"x"}' | "$F" inside "$M/notch-cube.json" -)
check "the object form on standard input" '[ "$out" = "[\"inside\",\"outside\"]" ]'
out=$(echo '[]' | "$F" inside "$M/notch-cube.json" -)
check "no points, an empty array" '[ "$out" = "[]" ]'

echo '{"points":[[1,2,3],[1,2,3],[4,5,"6"]]}' >"$tmp/bad.json"
"$F" inside "$M/notch-cube.json" "$tmp/bad.json" >/dev/null 2>"$tmp/err"
rc=$?
check "a non-number is bad input naming its place (exit 1)" \
    '[ $rc -eq 1 ] && grep -q "bad.json: points\[2\]\[2\]: expected a number" "$tmp/err"'
echo '[[1,2]]' | "$F" inside "$M/notch-cube.json" - >/dev/null 2>"$tmp/err"
check "a short point is named" 'grep -q "points\[0\]: expected 3 numbers, got 2" "$tmp/err"'
echo '[[1,2,3],' | "$F" inside "$M/notch-cube.json" - >/dev/null 2>"$tmp/err"
rc=$?
check "broken JSON gives line and column (exit 1)" '[ $rc -eq 1 ] && grep -q "line 2, column" "$tmp/err"'
"$F" inside "$M/missing.json" "$tmp/p.json" >/dev/null 2>&1
rc=$?
check "a missing model is bad input (exit 1)" '[ $rc -eq 1 ]'
"$F" inside "$M/notch-cube.json" >/dev/null 2>&1
rc=$?
check "a missing argument is a usage error (exit 2)" '[ $rc -eq 2 ]'
"$F" inside "$M/notch-cube.json" "$tmp/p.json" --method best >/dev/null 2>&1
rc=$?
check "an unknown method is a usage error (exit 2)" '[ $rc -eq 2 ]'
"$F" inside --help | grep -q "usage: facet inside"
check "--help prints the usage" '[ $? -eq 0 ]'

# 20000 grid-aligned and random points in the scanned stone's box
awk 'BEGIN { srand(7); printf "["; for (i = 0; i < 20000; i++) {
    if (i) printf ",";
    if (i % 4 == 0) printf "[%d,%d,%d]", i % 7 - 3, int(i / 7) % 7 - 3, int(i / 49) % 5 - 3;
    else printf "[%.17g,%.17g,%.17g]", 6.6 * rand() - 3.3, 6.6 * rand() - 3.3, 4.2 * rand() - 3.0 }
    printf "]\n" }' >"$tmp/many.json"
"$F" inside "$M/brilliant.scan-k400.json" "$tmp/many.json" --threads 1 >"$tmp/one.out"
"$F" inside "$M/brilliant.scan-k400.json" "$tmp/many.json" --threads 2 >"$tmp/two.out"
check "identical answers with 1 and 2 threads" 'cmp -s "$tmp/one.out" "$tmp/two.out"'
check "some points inside the stone" 'grep -q "\"inside\"" "$tmp/one.out"'
head -c 40000 "$tmp/many.json" | sed 's/,\[[^]]*$/]/' >"$tmp/few.json"
"$F" inside "$M/brilliant.scan-k400.json" "$tmp/few.json" --method ray >"$tmp/r.out"
"$F" inside "$M/brilliant.scan-k400.json" "$tmp/few.json" --method winding >"$tmp/w.out"
check "the winding number gives the ray's answers on the closed stone" \
    '[ "$(tr , "\n" <"$tmp/w.out" | wc -l)" -gt 500 ] && cmp -s "$tmp/r.out" "$tmp/w.out"'
out=$("$F" inside "$M/notch-cube.flipped.json" "$tmp/p.json")
check "a flipped facet does not change the answers (ray parity)" \
    '[ "$out" = "[\"inside\",\"outside\",\"boundary\",\"boundary\",\"outside\",\"boundary\",\"boundary\"]" ]'
out=$(echo '[[0,0,-1],[0,0,0.5]]' | "$F" inside "$M/brilliant.holes.json" -)
check "a model with holes is classified by the winding number" \
    '[ "$out" = "[\"inside\",\"inside\"]" ]'
