#!/bin/bash
# fill_collection.sh — the hole-filling table over a collection of open
# meshes: generated ones (tests/tools/gen_open: scanned-like blobs with
# holes of every size, CAD boxes with holes across sharp edges, thin slabs
# with holes across the rim, open sheets; COUNT of each kind, seeds 1..)
# and every *.off/*.obj/*.ply/*.stl in the directories given (for example
# the example meshes a geometry library ships). Each open mesh is filled
# by `facet fill --keep-invalid --report`, then again with --parts-overlap
# (a patch may cross another shell its own shell already crossed), with
# --remove-crossing (crossing facets removed first, the openings filled)
# and with both (an assembly whose parts also have flaps); each
# table gives holes filled / holes, meshes closed as valid solids, the
# strategy that closed each hole and the reason each open hole was
# refused, and the crossings each result has that its input did not:
# none may exist (plain), none but between two parts that crossed in the
# input (--parts-overlap), no more pairs than the input had
# (--remove-crossing, whose removal renumbers the facets; with both, the
# rule of the step that gave the result). Every pair is counted
# (inspect --pairs).
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
for mode in plain parts-overlap remove-crossing both; do
case $mode in
plain) flags= ;;
both) flags="--parts-overlap --remove-crossing" ;;
*) flags=--$mode ;;
esac
echo "== facet fill $flags"
while read -r m; do
    n=$(basename "$m")
    n=${n//./_}
    "$B/facet" convert "$m" "$T/$n.in.off" 2>/dev/null || continue
    "$B/facet" inspect --pairs 100000000 "$T/$n.in.off" >"$T/$n.in.json" \
        2>/dev/null || continue
    grep -q '"holes": 0,' "$T/$n.in.json" && continue
    rm -f "$T/$n.out.off" "$T/$n.rep.json" "$T/$n.out.json"
    timeout 300 "$B/facet" fill "$T/$n.in.off" -o "$T/$n.out.off" $flags \
        --keep-invalid --report "$T/$n.rep.json" >/dev/null 2>&1
    [ -s "$T/$n.out.off" ] && "$B/facet" inspect --pairs 100000000 \
        "$T/$n.out.off" >"$T/$n.out.json" 2>/dev/null
    echo "$n"
done <"$list" >"$T/done"
python3 - "$T" "$mode" <<'PY'
import json, os, sys
from collections import Counter
T, mode = sys.argv[1], sys.argv[2]

def read_off(path):
    tok = []
    for line in open(path):
        tok += line.split("#")[0].split()
    nv, nf = int(tok[1]), int(tok[2])
    i = 4 + 3 * nv
    F = []
    for _ in range(nf):
        k = int(tok[i])
        F.append(tuple(int(x) for x in tok[i + 1:i + 1 + k]))
        i += 1 + k
    return F

def shells(F):
    """Components across edges of exactly two facets."""
    par = list(range(len(F)))
    def find(x):
        while par[x] != x:
            par[x] = par[par[x]]
            x = par[x]
        return x
    edge = {}
    for f, vs in enumerate(F):
        for a, b in zip(vs, vs[1:] + vs[:1]):
            edge.setdefault((min(a, b), max(a, b)), []).append(f)
    for fs in edge.values():
        if len(fs) == 2:
            par[find(fs[0])] = find(fs[1])
    return [find(f) for f in range(len(F))]

def new_crossings(n, din, dout, removed):
    """Pairs of the result that are not the input's: all of them (plain),
    those not between two parts that crossed in the input (overlap); with
    facets removed first (remove-crossing, or both when the removal gave
    the result) the indices move, so: how many more pairs the result has
    than its input."""
    if mode == "remove-crossing" or (mode == "both" and removed > 0):
        return max(0, dout["self_intersections"]["count"]
                   - din["self_intersections"]["count"])
    old = set(map(tuple, din["self_intersections"]["pairs"]))
    pairs = [tuple(q) for q in dout["self_intersections"]["pairs"]]
    fresh = [q for q in pairs if q not in old]
    if mode == "plain" or not fresh:
        return len(fresh)
    sh = shells(read_off(os.path.join(T, n + ".out.off")))
    crossed = {frozenset((sh[a], sh[b])) for a, b in old if sh[a] != sh[b]}
    return sum(1 for a, b in fresh
               if sh[a] == sh[b] or frozenset((sh[a], sh[b])) not in crossed)

names = open(os.path.join(T, "done")).read().split()
holes = filled = closed = closed_valid = added = timeouts = 0
strat, refusal = Counter(), Counter()
rows = []
for n in names:
    din = json.load(open(os.path.join(T, n + ".in.json")))
    rp = os.path.join(T, n + ".rep.json")
    op = os.path.join(T, n + ".out.json")
    if not os.path.exists(rp):
        timeouts += 1
        holes += din["holes"]
        rows.append((n, din["holes"], 0, "timeout"))
        continue
    rep = json.load(open(rp))["fill"]
    holes += rep["loops"]
    filled += rep["filled"]
    closed += rep["filled"] == rep["loops"]
    for h in rep["holes"]:
        if h["status"].startswith("filled"):
            strat[h.get("attempt", "?")] += 1
        else:
            refusal[h["status"]] += 1
    valid = False
    if os.path.exists(op):
        dout = json.load(open(op))
        valid = dout["valid"]
        added += new_crossings(n, din, dout, rep["facets_removed"]) > 0
    closed_valid += valid
    rows.append((n, rep["loops"], rep["filled"], "valid" if valid else "not valid"))
for r in rows:
    print("%-28s holes %4d filled %4d  %s" % r)
print("meshes: %d open, %d with every hole filled, %d closed as valid solids;"
      " holes: %d of %d filled" % (len(names), closed, closed_valid, filled, holes))
print("strategy per filled hole: " + ", ".join("%s %d" % kv for kv in strat.most_common()))
print("refusals by reason: " + (", ".join("%s %d" % kv for kv in refusal.most_common()) or "none"))
rule = {"plain": "none new", "parts-overlap": "only between parts that crossed",
        "remove-crossing": "no more pairs than the input",
        "both": "the rule of the step that gave the result"}[mode]
print("results with a crossing the rule forbids (%s): %d; timeouts: %d"
      % (rule, added, timeouts))
PY
done
