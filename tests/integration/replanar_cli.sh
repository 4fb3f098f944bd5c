#!/bin/bash
# replanar_cli.sh — `facet move` and `facet inversion-stats` end to end:
# outputs, logs, exit codes, and the same table for any thread count.
# Usage: tests/integration/replanar_cli.sh BUILD_DIR (TAP output)
set -u
B=${1:-build}
FACET="$B/facet"
M=tests/data/models
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
n=0
ok() { n=$((n + 1)); echo "ok $n - $1"; }
notok() { n=$((n + 1)); echo "not ok $n - $1"; }
check() { if eval "$2"; then ok "$1"; else notok "$1"; fi; }

"$FACET" move "$M/brilliant.scan-k100.json" --vertex 5 --by 1e-5,-2e-5,3e-5 \
    --log "$tmp/log.tsv" -o "$tmp/out.json" >"$tmp/res.json"
rc=$?
check "move of 3.7e-5 mm converges, exit 0" "[ $rc -eq 0 ]"
check "move writes the model" "[ -s '$tmp/out.json' ]"
check "move prints converged and valid" \
    "grep -q '\"converged\": true' '$tmp/res.json' && grep -q '\"valid\": true' '$tmp/res.json'"
check "log has a header and one row per step" \
    "[ \$(head -1 '$tmp/log.tsv' | cut -f1) = step ] && [ \$((\$(wc -l <'$tmp/log.tsv') - 1)) -eq \$(sed -n 's/.*\"steps\": \\([0-9]*\\).*/\\1/p' '$tmp/res.json') ]"

"$FACET" move "$M/brilliant.scan-k100.json" --vertex 5 --by 1e-5,0,0 \
    --schedule global-exp --log "$tmp/log.json" -o "$tmp/out2.json" >/dev/null
check "JSON log for a .json path" "head -c 1 '$tmp/log.json' | grep -q '\\['"

"$FACET" move "$M/brilliant.truth.json" --vertex 0 --to 0,0,0 \
    -o "$tmp/bad.json" >/dev/null 2>"$tmp/err.txt"
rc=$?
check "a move through the stone exits 1 and writes nothing" \
    "[ $rc -eq 1 ] && [ ! -e '$tmp/bad.json' ] && grep -q 'not give a valid' '$tmp/err.txt'"

"$FACET" move "$M/brilliant.truth.json" --vertex 0 -o "$tmp/x.json" 2>/dev/null
check "move without --to/--by is a usage error" "[ $? -eq 2 ]"
"$FACET" move "$M/brilliant.truth.json" --vertex 99999 --to 0,0,0 \
    -o "$tmp/x.json" 2>/dev/null
check "vertex out of range is bad input" "[ $? -eq 1 ]"
"$FACET" move "$M/brilliant.truth.json" --vertex 1 --to 0,0 -o "$tmp/x.json" \
    2>/dev/null
check "malformed --to is a usage error" "[ $? -eq 2 ]"

"$FACET" move "$M/brilliant.truth.json" --vertex 100 --by 7e-4,-9e-4,1.5e-3 \
    --schedule local-exp --fit all --force -o "$tmp/all.json" >"$tmp/all-res.json"
check "--fit all reports the moved vertex's distance from its planes" \
    "sed -n 's/.*\"fixed_residual\": \\([^,}]*\\).*/\\1/p' '$tmp/all-res.json' | awk '{v = \$1} END {exit !(v > 1e-9 && v < 1e-6)}'"
"$FACET" move "$M/brilliant.truth.json" --vertex 100 --by 7e-4,-9e-4,1.5e-3 \
    --fit all -o "$tmp/x.json" 2>"$tmp/fit.err"
check "--fit all with the default least-norm schedule is refused, saying why" \
    "[ $? -eq 1 ] && grep -q 'fit all: the least-norm schedule' '$tmp/fit.err' && [ ! -e '$tmp/x.json' ]"
"$FACET" move "$M/brilliant.truth.json" --vertex 100 --by 1e-4,0,0 \
    --fit loose -o "$tmp/x.json" 2>/dev/null
check "an unknown --fit is a usage error" "[ $? -eq 2 ]"
"$FACET" move "$M/brilliant.truth.json" --vertex 100 --by 1e-4,0,0 \
    --schedule scaled --scaled-k s2 --log "$tmp/s2.json" -o "$tmp/y.json" \
    >/dev/null
check "--scaled-k s2 runs the paper's rule" "[ $? -eq 0 ] && [ -s '$tmp/s2.json' ]"

"$FACET" inversion-stats "$M/brilliant.scan-k100.json" --samples 6 --seed 9 \
    --threads 1 --runs >"$tmp/s1.json"
rc1=$?
"$FACET" inversion-stats "$M/brilliant.scan-k100.json" --samples 6 --seed 9 \
    --threads 2 --runs >"$tmp/s2.json"
rc2=$?
check "inversion-stats exits 0" "[ $rc1 -eq 0 ] && [ $rc2 -eq 0 ]"
check "inversion-stats output identical for 1 and 2 threads" \
    "cmp -s '$tmp/s1.json' '$tmp/s2.json'"
check "table has 10 magnitudes and 60 runs" \
    "[ \$(grep -c '\"ci95\"' '$tmp/s1.json') -eq 10 ] && [ \$(grep -c '\"sample\"' '$tmp/s1.json') -eq 60 ]"
"$FACET" inversion-stats "$M/brilliant.truth.json" --magnitudes 1,0 \
    2>/dev/null >/dev/null
check "a zero magnitude is a usage error" "[ $? -eq 2 ]"
"$FACET" inversion-stats "$tmp/missing.json" 2>/dev/null >/dev/null
check "a missing model is bad input" "[ $? -eq 1 ]"
echo "1..$n"
