#!/bin/bash
# collapse.sh — `facet collapse`, the op `collapse` on a file: a scan's
# vertex clusters become single vertices, the result stays valid and
# matches the op run by `facet run`; exit status 0 / 1 / 2.
# Usage: tests/integration/collapse.sh BUILD_DIR   (TAP output)
set -u
B=${1:-build}
FACET="$B/facet"
MODELS=${FACET_MODELS:-tests/data/models}
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
field() { grep -o "\"$1\":[-0-9.eE+]*" "$2" | head -n 1 | cut -d: -f2; }

src="$MODELS/brilliant.scan-k400.json"
check "collapse exits 0" bash -c "'$FACET' collapse '$src' -o '$T/c.json' --report '$T/rep.json' >'$T/line'"
check "clusters were found and collapsed" test "$(field collapsed "$T/line")" -gt 0
check "the result has fewer vertices" \
    test "$(field vertices_after "$T/line")" -lt "$(field vertices_before "$T/line")"
"$FACET" inspect "$T/c.json" >"$T/st.json"
check "the result is a valid polyhedron" grep -q '"valid": true' "$T/st.json"
check "the report lists every cluster" test "$(jq '.cluster_list | length' "$T/rep.json")" = "$(field clusters "$T/line")"
echo '["collapse"]' >"$T/pl.json"
"$FACET" run "$T/pl.json" "$src" -o "$T/r.json" >/dev/null 2>&1
check "the same model as the op collapse of facet run" cmp -s "$T/c.json" "$T/r.json"
check "--radius=VALUE is read" "$FACET" collapse "$src" --radius=0.001 -o "$T/d.json"
"$FACET" collapse "$T/none.json" -o "$T/x.json" 2>"$T/err"
check "a missing file exits 1" test $? -eq 1
check "naming the file" grep -q "none.json" "$T/err"
"$FACET" collapse "$src" --radius -1 -o "$T/x.json" 2>"$T/err"
check "a bad radius exits 2" test $? -eq 2
check "naming the option" grep -q -- "--radius" "$T/err"
"$FACET" collapse "$src" --bogus -o "$T/x.json" 2>/dev/null
check "an unknown option exits 2" test $? -eq 2
echo "1..$n"
