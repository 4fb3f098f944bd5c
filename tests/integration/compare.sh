#!/bin/bash
# compare.sh — facet compare and the pipeline op compare: the CLI aligns
# a scan onto its design and names its bad inputs (exit 1); through
# facetd a job with the op succeeds, leaves the model as it was, puts the
# comparison in the job's stats and its figures in the summary, and a bad
# reference is a 422 naming the place.
. "$(dirname "$0")/lib.sh" "$@"

FACET="$BUILD/facet"
TRUTH="$MODELS/brilliant.truth.json"
SCAN="$MODELS/brilliant.scan-k400.json"
TETRA='{"format":"facet-model/1","vertices":[[1,0,0],[-0.5,0.8660254037844386,0],[-0.5,-0.8660254037844386,0],[0,0,1.4142135623730951]],"facets":[{"vertices":[0,2,1]},{"vertices":[0,1,3]},{"vertices":[1,2,3]},{"vertices":[2,0,3]}]}'
printf '%s' "$TETRA" >"$T/tetra.json"
printf '{"format":"facet-model/1","vertices":[],"facets":[]}' >"$T/empty.json"

"$FACET" compare "$TRUTH" "$SCAN" >"$T/cmp.json" 2>"$T/err"
expect_eq "facet compare of the truth and its k400 scan succeeds" 0 $?
check "it aligned them" grep -q '"aligned": true' "$T/cmp.json"
check "every design facet is matched" grep -q '"matched_facets": 121' "$T/cmp.json"
h=$(sed -n 's/.*"hausdorff_mm": \([-0-9.e]*\).*/\1/p' "$T/cmp.json")
check "the Hausdorff distance is a few µm ($h mm)" awk -v h="$h" 'BEGIN { exit !(h > 0 && h < 0.01) }'

"$FACET" compare "$TRUTH" "$T/missing.json" 2>"$T/err"
expect_eq "an unreadable file is exit 1" 1 $?
check "naming the file" grep -q 'missing.json' "$T/err"
"$FACET" compare "$T/tetra.json" "$TRUTH" 2>"$T/err"
expect_eq "a model without a table and no axis is exit 1" 1 $?
check "saying so and naming it" grep -q 'tetra.json: no table: .*give an axis' "$T/err"
"$FACET" compare "$TRUTH" "$T/empty.json" 2>"$T/err"
expect_eq "an empty model is exit 1" 1 $?
check "naming it" grep -q 'empty.json: an empty model' "$T/err"
"$FACET" compare "$T/tetra.json" "$T/tetra.json" --axis 0,0,1 >/dev/null 2>&1
expect_eq "with --axis a model without a table is compared" 0 $?

start_facetd || { not_ok "facetd starts"; finish; exit 1; }
req GET /v1/version
check "/v1/version lists compare" grep -q '"compare"' "$BODY"

submit brilliant.scan-k400.json "[{\"op\":\"compare\",\"reference\":$(cat "$TRUTH")}]"
expect_eq "a compare job is accepted" 202 "$CODE"
wait_job "$ID" 60
expect_eq "it succeeds" succeeded "$STATE_OF"
check "the summary says it aligned" grep -q '"compare_aligned":true' "$BODY"
check "with its Hausdorff distance" grep -q '"compare_hausdorff_mm":[0-9]' "$BODY"
check "and the rotation" grep -q '"compare_rotation_deg":[0-9]' "$BODY"
req GET "/v1/jobs/$ID/stats"
check "the stats have the comparison" grep -q '"op":"compare"' "$BODY"
check "with the matched facets" grep -q '"matched_facets":121' "$BODY"
check "and the per-facet pairs" grep -q '"facets":\[{"a":0,"b":' "$BODY"
req GET "/v1/jobs/$ID/model?format=json"
check "the model is left as it was, byte for byte" cmp -s "$BODY" "$SCAN"

f=$(body brilliant.scan-k400.json '[{"op":"compare"}]')
post_json /v1/jobs "$f"
expect_eq "compare without a reference is 422" 422 "$CODE"
check "naming pipeline[0].reference" grep -q '"path":"pipeline\[0\].reference"' "$BODY"
f=$(body brilliant.scan-k400.json "[{\"op\":\"compare\",\"reference\":{\"format\":\"facet-model/1\",\"vertices\":[[0,0,0],[1,0,0],[0,1,0]],\"facets\":[{\"vertices\":[0,1,7]}]}}]")
post_json /v1/jobs "$f"
expect_eq "a reference with a bad index is 422" 422 "$CODE"
check "naming the place inside the reference" grep -q '"path":"pipeline\[0\].reference.facets\[0\].vertices\[2\]"' "$BODY"
f=$(body brilliant.scan-k400.json "[{\"op\":\"compare\",\"reference\":$TETRA}]")
post_json /v1/jobs "$f"
expect_eq "a reference without a table is 422" 422 "$CODE"
check "saying to give an axis" grep -q '"path":"pipeline\[0\].reference","message":"no table: .*give an axis' "$BODY"
f=$(body brilliant.scan-k400.json "[{\"op\":\"compare\",\"axis\":[0,0,0],\"reference\":$TETRA}]")
post_json /v1/jobs "$f"
expect_eq "a zero axis is 422" 422 "$CODE"
check "naming pipeline[0].axis" grep -q '"path":"pipeline\[0\].axis"' "$BODY"

finish
