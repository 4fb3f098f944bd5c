#!/bin/bash
# fill_collection.sh — the hole-filling table over a collection of open
# meshes: generated ones (tests/tools/gen_open: scanned-like blobs with
# holes of every size, CAD boxes with holes across sharp edges, thin slabs
# with holes across the rim, open sheets; COUNT of each kind, seeds 1..)
# and every *.off/*.obj/*.ply/*.stl in the directories given (for example
# the example meshes a geometry library ships). Each open mesh is filled
# by `facet fill --keep-invalid --report`; the table gives holes filled /
# holes, meshes closed as valid solids, the strategy that closed each
# hole and the reason each open hole was refused, and how many results
# gained a self-intersection the input did not have.
# Usage: tests/bench/fill_collection.sh BUILD_DIR [COUNT] [DIR...]
set -u
B=${1:-build}
COUNT=${2:-5}
shift 2 2>/dev/null || shift $#
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
list="$T/list"
: >"$list"
for kind in scan cad thin sheet; do
    for s in $(seq 1 "$COUNT"); do
        "$B/tools/gen_open" "$kind" "$s" "$T/$kind-$s.off" &&
            echo "$T/$kind-$s.off" >>"$list"
    done
done
for d in "$@"; do
    find "$d" -maxdepth 1 -type f \( -name '*.off' -o -name '*.obj' -o \
        -name '*.ply' -o -name '*.stl' \) | sort >>"$list"
done
while read -r m; do
    n=$(basename "$m")
    n=${n%.*}
    "$B/facet" inspect "$m" >"$T/$n.in.json" 2>/dev/null || continue
    grep -q '"holes": 0,' "$T/$n.in.json" && continue
    timeout 300 "$B/facet" fill "$m" -o "$T/$n.out.off" --keep-invalid \
        --report "$T/$n.rep.json" >/dev/null 2>&1
    [ -s "$T/$n.out.off" ] && "$B/facet" inspect "$T/$n.out.off" \
        >"$T/$n.out.json" 2>/dev/null
    echo "$n"
done <"$list" >"$T/done"
python3 - "$T" <<'PY'
import json, os, sys
from collections import Counter
T = sys.argv[1]
names = open(os.path.join(T, "done")).read().split()
holes = filled = closed_valid = added_si = timeouts = 0
strat, refusal = Counter(), Counter()
rows = []
for n in names:
    ip = os.path.join(T, n + ".in.json")
    rp = os.path.join(T, n + ".rep.json")
    op = os.path.join(T, n + ".out.json")
    din = json.load(open(ip))
    if not os.path.exists(rp):
        timeouts += 1
        holes += din["holes"]
        rows.append((n, din["holes"], 0, "timeout"))
        continue
    rep = json.load(open(rp))["fill"]
    holes += rep["loops"]
    filled += rep["filled"]
    for h in rep["holes"]:
        if h["status"].startswith("filled"):
            strat[h.get("attempt", "?")] += 1
        else:
            refusal[h["status"]] += 1
    valid = False
    if os.path.exists(op):
        dout = json.load(open(op))
        valid = dout["valid"]
        if dout["self_intersecting_facets"] > din["self_intersecting_facets"]:
            added_si += 1
    closed_valid += valid
    rows.append((n, rep["loops"], rep["filled"], "valid" if valid else "not valid"))
for r in rows:
    print("%-28s holes %4d filled %4d  %s" % r)
print("meshes: %d open, %d closed as valid solids; holes: %d of %d filled"
      % (len(names), closed_valid, filled, holes))
print("strategy per filled hole: " + ", ".join("%s %d" % kv for kv in strat.most_common()))
print("refusals by reason: " + (", ".join("%s %d" % kv for kv in refusal.most_common()) or "none"))
print("results with a self-intersection the input did not have: %d; timeouts: %d"
      % (added_si, timeouts))
PY
