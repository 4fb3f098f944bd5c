#!/bin/bash
# convert.sh — `facet convert` end to end: the JSON → PLY → JSON round trip
# gives back the same file, every writable format converts, and the exit
# status is 0 / 1 (bad input, message naming file and place) / 2 (usage).
# Usage: tests/integration/convert.sh BUILD_DIR   (TAP output)
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

src="$MODELS/brilliant.scan-k400.json"
check "json to ply exits 0" "$FACET" convert "$src" "$T/x.ply"
check "ply to json exits 0" "$FACET" convert "$T/x.ply" "$T/y.json"
check "json -> ply -> json gives back the same file" cmp -s "$src" "$T/y.json"

for f in json poly obj stl stl-ascii ply ply-ascii ase fmb1 off; do
    check "converts to $f" "$FACET" convert "$MODELS/notch-cube.json" \
        "$T/n.out" --to "$f"
done
check "fmb1 back to json is the same file" bash -c \
    "'$FACET' convert '$MODELS/notch-cube.json' '$T/n.fmb' &&
     '$FACET' convert '$T/n.fmb' '$T/n.json' &&
     cmp -s '$MODELS/notch-cube.json' '$T/n.json'"

printf '{"format":"facet-model/1","vertices":[[0,0,0],[1,0,0],[0,1,0]],\n'\
'"facets":[{"vertices":[0,1,7]}]}\n' > "$T/bad.json"
"$FACET" convert "$T/bad.json" "$T/out.json" 2> "$T/err"
rc=$?
check "bad input exits 1" test $rc -eq 1
check "the error names the file and the place" grep -q \
    "bad.json: facets\[0\].vertices\[2\]: index 7 out of range (3 vertices)" \
    "$T/err"
check "no output is left after a failed read" test ! -e "$T/out.json"

"$FACET" convert "$src" 2> /dev/null
check "a missing argument exits 2" test $? -eq 2
"$FACET" convert "$src" "$T/x.unknown" 2> /dev/null
check "an unknown output extension exits 2" test $? -eq 2
"$FACET" convert "$src" "$T/x.json" --to nope 2> /dev/null
check "an unknown format name exits 2" test $? -eq 2
"$FACET" convert "$T/n.out" "$T/x.json" --from ase 2> /dev/null
check "reading ase exits 2" test $? -eq 2
check "--help exits 0 and shows the usage" bash -c \
    "'$FACET' convert --help | grep -q 'usage: facet convert IN OUT'"
"$FACET" convert "$MODELS/brilliant.selfint.json" "$T/s.json" 2> "$T/warn"
check "mismatching planes warn but succeed" test $? -eq 0
check "the warning names the facet" grep -q \
    "warning: 3 of 121 given planes disagree.*facets\[99\].plane" "$T/warn"
echo "1..$n"
