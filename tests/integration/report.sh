#!/bin/bash
# report.sh — `facet report` end to end: public GemCad designs read into
# stones whose mains come back at the file's angles, .asc round trips,
# designs in progress refused naming the line, and --scan RAW: a truth
# against itself deviates by nothing, a corrected simulated scan against
# its raw scan by a few µm.
. "$(dirname "$0")/lib.sh" "$@"
F="$BUILD/facet"
SIM="$BUILD/tools/scansim"
PUB=tests/data/designs/public

for d in SRB Compear125 CubeIllusionTri Turkey; do
    "$F" convert "$PUB/$d.asc" "$T/$d.json" 2> "$T/err"
    expect_eq "$d.asc converts" 0 "$?"
    check "$d.asc converts without a warning" test ! -s "$T/err"
    "$F" convert "$T/$d.json" "$T/$d.asc" && "$F" convert "$T/$d.asc" "$T/$d.back.json"
    expect_eq "$d: json -> asc -> json keeps the facets" \
        "$(jq '.facets | length' "$T/$d.json")" \
        "$(jq '.facets | length' "$T/$d.back.json")"
done

"$F" report "$PUB/SRB.asc" > "$T/srb.json"
expect_eq "SRB: 8 bezels at 28 deg" true \
    "$(jq '.crown_mains == 8 and (.crown_angle_deg - 28 | fabs) < 0.02' "$T/srb.json")"
expect_eq "SRB: 8 pavilion mains at 41.5 deg" true \
    "$(jq '.pavilion_mains == 8 and (.pavilion_angle_deg - 41.5 | fabs) < 0.02' "$T/srb.json")"
expect_eq "SRB: 16 upper girdle facets at 34 deg" 16 \
    "$(jq '[.facets[] | select(.tier == "crown" and (.inclination_deg - 34 | fabs) < 0.02)] | length' "$T/srb.json")"

printf 'GemCad 5.0\ng 96 0.0\na -90 1 3 27 51 75\n n G\na -45 0.8 3 27 51 75\n' > "$T/wip.asc"
"$F" convert "$T/wip.asc" "$T/wip.json" 2> "$T/err"
expect_eq "a design without its crown exits 1" 1 "$?"
check "the error names the file, the line and what is missing" grep -q \
    "wip.asc: line 5: the facets do not bound a stone: no crown facets" "$T/err"

# --scan: the truth against itself, then a corrected scan against its raw scan
"$SIM" --design tests/data/designs/round-brilliant.asc --k 400 --seed 5 \
    --noise 0.001 --truth "$T/truth.json" --scan "$T/raw.json" > /dev/null
"$F" report "$T/truth.json" --scan "$T/truth.json" > "$T/self.json"
expect_eq "report --scan succeeds" 0 "$?"
expect_eq "every facet of the truth has a deviation" 0 \
    "$(jq '[.facets[] | select(.scan_deviation_um == null)] | length' "$T/self.json")"
expect_eq "the truth deviates from itself by nothing (max <= 1e-6 um)" true \
    "$(jq '[.facets[].scan_deviation_um.max] | max <= 1e-6' "$T/self.json")"
"$F" correct "$T/raw.json" -o "$T/corr.json" > /dev/null
"$F" report "$T/corr.json" --scan "$T/raw.json" > "$T/dev.json"
expect_eq "the corrected scan's facets lie within 1-10 um of the raw scan" true \
    "$(jq '[.facets[].scan_deviation_um | select(. != null) | .max] | (max > 1 and max < 10)' "$T/dev.json")"
expect_eq "their rms is below their max and below 3 um" true \
    "$(jq '[.facets[].scan_deviation_um | select(. != null) | .rms <= .max and .rms < 3] | all' "$T/dev.json")"
expect_eq "without --scan no facet has the field" false \
    "$("$F" report "$T/corr.json" | jq '[.facets[] | has("scan_deviation_um")] | any')"
"$F" report "$T/corr.json" --scan "$T/missing.json" 2> "$T/err"
expect_eq "a missing scan exits 1" 1 "$?"
check "naming the file" grep -q "missing.json" "$T/err"
"$F" report "$T/corr.json" --scan 2> /dev/null
expect_eq "--scan without a value exits 2" 2 "$?"

# in facetd: {"op": "report", "scan": true} measures against the job's input
start_facetd --workers 1 || { not_ok "facetd starts"; finish; exit 1; }
submit brilliant.scan-k400.json '["correct", {"op":"report","scan":true}]'
expect_eq "a job with report scan is accepted" 202 "$CODE"
wait_job "$ID" 60
expect_eq "it succeeds" succeeded "$STATE_OF"
req GET "/v1/jobs/$ID/stats"
expect_eq "its report gives the facets their deviation from the submitted scan" true \
    "$(jq '[.ops[1].report.facets[].scan_deviation_um | select(. != null) | .max] | (length > 50 and max > 1 and max < 10)' "$BODY")"
submit brilliant.scan-k400.json '[{"op":"report","scan":"yes"}]'
expect_eq "a scan that is not a boolean is 422" 422 "$CODE"
check "naming the place" grep -q 'pipeline\[0\].scan' "$BODY"
stop_facetd
finish
