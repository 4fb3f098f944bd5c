#!/bin/bash
# fill_stitch.sh — open meshes end to end: `facet fill` puts the
# brilliant's two missing facets back (121 facets, valid, the true
# volume), `facet stitch` joins the stone's crown and pavilion (a band of
# facets removed between them) into one valid solid by the band, the
# halves of the stone cut by two planes back into the stone by the
# facet planes, and overlapping halves trimmed and welded; facetd runs
# fill_holes on a model and stitch on a job with "meshes": [m1, m2],
# refusing meshes it cannot stitch with 422.
. "$(dirname "$0")/lib.sh" "$@"
F="$BUILD/facet"

out=$("$F" fill "$MODELS/brilliant.holes.json" -o "$T/filled.json" --report "$T/fill.rep")
check "facet fill succeeds" test $? -eq 0
check "both holes come back as one planar facet each" grep -q '"loops":2,"filled":2,"planar":2,"left_open":0' <<<"$out"
check "the result has 121 facets and is valid" grep -q '"valid":true,"vertices":238,"facets":121' <<<"$out"
check "the report names each hole's outcome" grep -q '"status": "filled_planar"' "$T/fill.rep"
check "the report has the time" grep -q '"ms":' "$T/fill.rep"
python3 - "$T/filled.json" "$MODELS/brilliant.truth.json" <<'PY' && ok "the filled stone has the true stone's volume" || not_ok "the filled stone has the true stone's volume"
import json, sys
def vol(path):
    m = json.load(open(path)); v = m["vertices"]; s = 0.0
    for f in m["facets"]:
        idx = f["vertices"] if isinstance(f, dict) else f
        p0 = v[idx[0]]
        for a, b in zip(idx[1:-1], idx[2:]):
            p1, p2 = v[a], v[b]
            s += (p0[0] * (p1[1] * p2[2] - p1[2] * p2[1]) - p0[1] * (p1[0] * p2[2] - p1[2] * p2[0]) + p0[2] * (p1[0] * p2[1] - p1[1] * p2[0])) / 6
    return s
a, b = vol(sys.argv[1]), vol(sys.argv[2])
sys.exit(0 if abs(a - b) <= 1e-9 * abs(b) else 1)
PY

# an open box with a column through its opening and its floor: every
# lid crosses the column, so fill fails (exit 1), says why, writes nothing
python3 - "$T/linked.off" <<'PY'
import sys
def box(lo, hi, off):
    v = [(x, y, z) for z in (lo[2], hi[2]) for y in (lo[1], hi[1]) for x in (lo[0], hi[0])]
    f = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (1, 3, 7, 5), (3, 2, 6, 7), (2, 0, 4, 6)]
    return v, [tuple(i + off for i in q) for q in f]
v1, f1 = box((0, 0, 0), (1, 1, 1), 0)
f1 = [q for q in f1 if q != (4, 5, 7, 6)]  # no top
v2, f2 = box((0.4, 0.4, -1), (0.6, 0.6, 50), 8)
with open(sys.argv[1], "w") as o:
    o.write("OFF\n%d %d 0\n" % (16, len(f1) + len(f2)))
    for p in v1 + v2: o.write("%g %g %g\n" % p)
    for q in f1 + f2: o.write("4 %d %d %d %d\n" % q)
PY
"$F" fill "$T/linked.off" -o "$T/linked.out.off" >"$T/linked.line" 2>"$T/err"
expect_eq "an unfillable hole fails the fill (exit 1)" 1 "$?"
check "the error says the result is not valid" grep -q "not a valid closed solid, not written" "$T/err"
check "the summary still says what was tried" grep -q '"left_open":1' "$T/linked.line"
check "no invalid result is written" test ! -e "$T/linked.out.off"
"$F" fill "$T/linked.off" -o "$T/linked.out.off" --keep-invalid >/dev/null 2>&1
expect_eq "--keep-invalid still exits 1" 1 "$?"
check "--keep-invalid writes the result for inspection" test -s "$T/linked.out.off"
# the box and the column are two parts that already cross (the column
# goes through the floor): --parts-overlap lets the lid cross the column
"$F" fill "$T/linked.off" -o "$T/po.off" --parts-overlap --keep-invalid \
    >"$T/po.line" 2>/dev/null
expect_eq "--parts-overlap: still exit 1 (the parts cross: not a valid solid)" 1 "$?"
check "--parts-overlap fills the hole the column goes through" grep -q '"filled":1,.*"left_open":0' "$T/po.line"
# a box of 4 × 4 quads a side without its top, a flap on the rim folded
# across the opening and out through the far wall: --remove-crossing
# takes it away first, and the box comes back closed and valid
python3 - "$T/flap.off" <<'PY'
import sys
n, V, F, idx = 4, [], [], {}
def vid(p):
    if p not in idx:
        idx[p] = len(V); V.append(p)
    return idx[p]
def face(origin, du, dv):  # quads of the face origin + i/n du + j/n dv
    for i in range(n):
        for j in range(n):
            q = [tuple(o + a * du[k] / n + b * dv[k] / n for k, o in enumerate(origin))
                 for a, b in ((i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1))]
            F.append([vid(p) for p in q])
face((0, 0, 0), (0, 1, 0), (1, 0, 0))  # bottom, outward -z
face((0, 0, 0), (1, 0, 0), (0, 0, 1))  # y = 0
face((1, 0, 0), (0, 1, 0), (0, 0, 1))  # x = 1
face((1, 1, 0), (-1, 0, 0), (0, 0, 1))  # y = 1
face((0, 1, 0), (0, -1, 0), (0, 0, 1))  # x = 0
# the rim edge (0.5, 0, 1)-(0.75, 0, 1) runs 0.75 -> 0.5 in the y = 0
# wall's quad: the flap runs it the other way
a, b = idx[(0.5, 0, 1)], idx[(0.75, 0, 1)]
F.append([a, b, vid((0.6, 1.5, 0.5))])
with open(sys.argv[1], "w") as o:
    o.write("OFF\n%d %d 0\n" % (len(V), len(F)))
    for p in V: o.write("%r %r %r\n" % p)
    for q in F: o.write("%d %s\n" % (len(q), " ".join(map(str, q))))
PY
"$F" fill "$T/flap.off" -o "$T/flap.out.off" >/dev/null 2>&1
expect_eq "a flap across the opening: the plain fill fails (exit 1)" 1 "$?"
out=$("$F" fill "$T/flap.off" -o "$T/flap.out.off" --remove-crossing --report "$T/flap.rep")
expect_eq "--remove-crossing closes it validly (exit 0)" 0 "$?"
check "the result is valid, every hole closed" grep -q '"left_open":0,.*"valid":true' <<<"$out"
check "the report counts the one facet removed" grep -q '"facets_removed": 1' "$T/flap.rep"

# the crown and the pavilion of the true stone, the facets between
# -0.3 < z < 0.3 (the girdle band) removed
python3 - "$MODELS/brilliant.truth.json" "$T/top.json" "$T/bot.json" <<'PY'
import json, sys
m = json.load(open(sys.argv[1])); v = m["vertices"]
def centre(f):
    idx = f["vertices"] if isinstance(f, dict) else f
    return sum(v[i][2] for i in idx) / len(idx)
for path, keep in ((sys.argv[2], lambda z: z > 0.3), (sys.argv[3], lambda z: z < -0.3)):
    fs = [f for f in m["facets"] if keep(centre(f))]
    used = sorted({i for f in fs for i in (f["vertices"] if isinstance(f, dict) else f)})
    ren = {o: n for n, o in enumerate(used)}
    out = dict(m)
    out["vertices"] = [v[i] for i in used]
    out["facets"] = [dict(f, vertices=[ren[i] for i in f["vertices"]]) if isinstance(f, dict) else [ren[i] for i in f] for f in fs]
    json.dump(out, open(path, "w"))
PY
out=$("$F" stitch "$T/top.json" "$T/bot.json" -o "$T/stitched.json" --report "$T/stitch.rep")
check "facet stitch succeeds" test $? -eq 0
check "the halves are joined whole as a band" grep -q '"band":true' <<<"$out"
check "the stitched stone is valid" grep -q '"left_open":0,"valid":true' <<<"$out"
check "the stitch report lists the meridians" grep -q '"meridians":' "$T/stitch.rep"
check "whole facets removed leave loops off any plane: the band joins them" grep -q '"method":"band"' <<<"$out"

# the stone cut by two parallel planes 0.4 mm apart (tilted 3.4°, across
# the crown), the cuts' caps dropped: the facet planes extended across
# the gap give the stone back
open_half() { # $1 plane $2 out
    "$F" cut "$MODELS/brilliant.truth.json" --plane "$1" -o "$T/cut.json" >/dev/null || return 1
    python3 - "$T/cut.json" "$1" "$2" <<'PY'
import json, math, sys
m = json.load(open(sys.argv[1])); p = [float(x) for x in sys.argv[2].split(",")]
l = math.sqrt(sum(x * x for x in p[:3])); p = [x / l for x in p]
fs = [f for f in m["facets"] if max(abs(a - b) for a, b in zip(f["plane"], p)) > 1e-9]
used = sorted({i for f in fs for i in f["vertices"]}); ren = {o: n for n, o in enumerate(used)}
m["vertices"] = [m["vertices"][i] for i in used]
m["facets"] = [dict(f, vertices=[ren[i] for i in f["vertices"]]) for f in fs]
json.dump(m, open(sys.argv[3], "w"))
PY
}
s=$(python3 -c 'import math; print(math.sin(math.radians(3.4)))')
c=$(python3 -c 'import math; print(math.cos(math.radians(3.4)))')
open_half "-$s,0,-$c,0.565" "$T/crown.json" && open_half "$s,0,$c,-0.165" "$T/pav.json"
check "the two halves are cut and opened" test -s "$T/crown.json" -a -s "$T/pav.json"
out=$("$F" stitch "$T/crown.json" "$T/pav.json" -o "$T/planes.json" --report "$T/planes.rep")
check "facet stitch joins the halves of the cut stone" test $? -eq 0
check "by the facet planes, validly" grep -q '"method":"planes".*"left_open":0,"valid":true' <<<"$out"
check "the report says the method and the planes extended" grep -q '"method": "planes"' "$T/planes.rep"
"$F" compare "$MODELS/brilliant.truth.json" "$T/planes.json" >"$T/cmp.json"
python3 - "$T/cmp.json" <<'PY' && ok "the stitched stone is the stone (Hausdorff < 1 um)" || not_ok "the stitched stone is the stone (Hausdorff < 1 um)"
import json, sys
sys.exit(0 if json.load(open(sys.argv[1]))["hausdorff_mm"] < 1e-3 else 1)
PY
# halves that overlap by 0.4 mm: both are cut back to the plane midway
# between their rims, then welded there
open_half "0,0,-1,-0.2" "$T/over-top.json" && open_half "0,0,1,-0.2" "$T/over-bot.json"
out=$("$F" stitch "$T/over-top.json" "$T/over-bot.json" -o "$T/over.json" \
    --report "$T/over.rep" 2>"$T/err")
expect_eq "overlapping halves are stitched (exit 0)" 0 "$?"
check "trimmed, then welded, validly" grep -q '"method":"weld".*"left_open":0,"valid":true' <<<"$out"
check "the report says the halves were trimmed" grep -q '"trimmed": true' "$T/over.rep"
"$F" compare "$MODELS/brilliant.truth.json" "$T/over.json" >"$T/cmp.json"
python3 - "$T/cmp.json" <<'PY' && ok "the trimmed stitch is the stone (Hausdorff < 1 um)" || not_ok "the trimmed stitch is the stone (Hausdorff < 1 um)"
import json, sys
sys.exit(0 if json.load(open(sys.argv[1]))["hausdorff_mm"] < 1e-3 else 1)
PY
"$F" stitch "$MODELS/brilliant.truth.json" "$T/bot.json" -o "$T/x.json" 2>"$T/err"
expect_eq "a closed mesh cannot be stitched (exit 1)" 1 "$?"
check "the error says why" grep -q "no free-edge loop" "$T/err"

start_facetd --workers 1 || { not_ok "facetd starts"; finish; exit 1; }
submit brilliant.holes.json '["fill_holes", "inspect"]'
expect_eq "a fill_holes job is accepted" 202 "$CODE"
wait_job "$ID"
expect_eq "the fill_holes job succeeds" succeeded "$STATE_OF"
check "its summary says valid, 121 facets" grep -q '"facets_after":121' "$BODY"
check "no hole is left open" grep -q '"holes_left_open":0' "$BODY"

"$F" convert "$T/linked.off" "$T/linked.json"
printf '{"pipeline":["fill"],"model":%s}' "$(cat "$T/linked.json")" >"$T/linked.body"
post_json /v1/jobs "$T/linked.body"
expect_eq "a fill job on an unfillable hole is accepted" 202 "$CODE"
ID=$(jstr id)
wait_job "$ID"
expect_eq "the fill job fails instead of passing an open model on" failed "$STATE_OF"
check "the job says why" grep -q "not a valid closed solid.*holes left open.*intersects_mesh" "$BODY"
printf '{"pipeline":[{"op":"fill","parts_overlap":1}],"model":%s}' "$(cat "$T/linked.json")" >"$T/po.body"
post_json /v1/jobs "$T/po.body"
expect_eq "parts_overlap must be a boolean (422)" 422 "$CODE"
check "the 422 names parts_overlap" grep -q "parts_overlap" "$BODY"

mk_meshes() { # $1 pipeline member (may be empty) $2.. mesh files
    local f; f=$(mktemp "$T/body.XXXXXX"); local pl=$1; shift
    { printf '{%s"meshes":[' "${pl:+$pl,}"; local sep=""
      for m in "$@"; do printf '%s' "$sep"; cat "$m"; sep=","; done; printf ']}'; } >"$f"
    echo "$f"
}
post_json /v1/jobs "$(mk_meshes "" "$T/top.json" "$T/bot.json")"
expect_eq "a job with two meshes is accepted" 202 "$CODE"
ID=$(jstr id)
wait_job "$ID"
expect_eq "the stitch job succeeds" succeeded "$STATE_OF"
check "the stitched model is valid" grep -q '"valid":true' "$BODY"
req GET "/v1/jobs/$ID/stats"
check "its stats carry the stitch report" grep -q '"op":"stitch"' "$BODY"
post_json /v1/jobs "$(mk_meshes "" "$T/top.json")"
expect_eq "one mesh is refused" 422 "$CODE"
post_json /v1/jobs "$(mk_meshes '"pipeline":["inspect"]' "$T/top.json" "$T/bot.json")"
expect_eq "meshes without a stitch first are refused" 422 "$CODE"
check "the refusal says why" grep -q "must start with stitch" "$BODY"
finish
