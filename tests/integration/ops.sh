#!/bin/bash
# ops.sh — the kernels wired into facetd's pipelines, over HTTP: cut,
# move_vertex and inversion_stats run as jobs, report in the job's stats,
# change (or keep) the result model; bad parameters are 422 by place, a
# failing op fails the job naming itself; /v1/version lists the ops; a
# job that only reads the model serves its input, byte for byte, as the
# result.
. "$(dirname "$0")/lib.sh" "$@"

start_facetd || { not_ok "facetd starts"; finish; exit 1; }

req GET /v1/version
for op in cut move inversion_stats; do
    check "/v1/version lists $op" grep -q "\"$op\"" "$BODY"
done

# cut: the notch cube below z = 4 is a 10 x 10 x 4 box
submit notch-cube.json '["inspect", {"op":"cut","plane":[0,0,2,-8]}, "inspect"]'
expect_eq "a cut job is accepted" 202 "$CODE"
wait_job "$ID"
expect_eq "it succeeds" succeeded "$STATE_OF"
check "the summary counts the result" grep -q '"facets_after":6' "$BODY"
req GET "/v1/jobs/$ID/stats"
check "the stats report the cut" grep -q '"op":"cut"' "$BODY"
check "with the volume after it" grep -q '"volume_after":400' "$BODY"
check "and the normalised plane" grep -q '"plane":\[0.0,0.0,1.0,-4.0\]' "$BODY"
check "an inspect after the cut is the 'after' report" grep -q '"after":{' "$BODY"
req GET "/v1/jobs/$ID/model?format=obj"
expect_eq "the result has 6 facets" 6 "$(grep -c '^f ' "$BODY")"

# move_vertex on the clean stone: a small move converges and is logged
submit brilliant.truth.json '[{"op":"move","vertex":100,"by":[1e-6,-1e-6,5e-7],"schedule":"scaled"}]'
wait_job "$ID"
expect_eq "a move job succeeds" succeeded "$STATE_OF"
req GET "/v1/jobs/$ID/stats"
check "its report has the result" grep -q '"result":{[^}]*"converged":true' "$BODY"
check "and the iteration log" grep -q '"log":\[{"step":0' "$BODY"
submit brilliant.scan-k400.json '[{"op":"move","vertex":2000,"by":[3.4e-5,0,0]}]'
wait_job "$ID"
expect_eq "a move without a schedule succeeds on the raw scan" succeeded "$STATE_OF"
req GET "/v1/jobs/$ID/stats"
check "by the least-norm schedule" grep -q '"result":{"schedule":"least-norm","converged":true,"valid":true' "$BODY"
curl -s -o "$T/moved.json" "$URL/v1/jobs/$ID/model?format=json"
"$BUILD/facet" move "$MODELS/brilliant.scan-k400.json" --vertex 2000 --by 3.4e-5,0,0 -o "$T/moved_cli.json" >/dev/null
check "the same model as facet move, byte for byte" cmp -s "$T/moved.json" "$T/moved_cli.json"
submit brilliant.truth.json '[{"op":"move","vertex":9999,"to":[0,0,0]}]'
expect_eq "a vertex out of range is refused at submission" 422 "$CODE"
check "naming the op and the vertex" grep -q '"path":"pipeline\[0\].vertex","message":"9999 out of range (238 vertices)"' "$BODY"
submit brilliant.truth.json '[{"op":"move","vertex":5,"by":[0.01,0,0],"max_steps":2}]'
wait_job "$ID"
expect_eq "a move that cannot converge fails the job" failed "$STATE_OF"
check "saying why" grep -q 'does not give a valid polyhedron (no convergence after 2 steps' "$BODY"

# inversion_stats reads the model: the result is the input, byte for byte
submit brilliant.truth.json '[{"op":"inversion_stats","samples":3,"magnitudes":[1,0.0001],"seed":5,"schedule":"scaled"}]'
wait_job "$ID" 120
expect_eq "an inversion_stats job succeeds" succeeded "$STATE_OF"
req GET "/v1/jobs/$ID/stats"
check "its report has the table" grep -q '"table":\[{"m":1.0,"runs":3' "$BODY"
check "and the seed" grep -q '"seed":5' "$BODY"
req GET "/v1/jobs/$ID/model?format=json"
check "the result model is the input file, byte for byte" cmp -s "$BODY" "$MODELS/brilliant.truth.json"
etag=$(header ETag)
req GET "/v1/jobs/$ID/model?format=json" -H "If-None-Match: $etag"
expect_eq "and revalidates with 304" 304 "$CODE"

# bad parameters are 422, each by place
f=$(body notch-cube.json '[{"op":"cut"}]')
post_json /v1/jobs "$f"
expect_eq "a cut without a plane is 422" 422 "$CODE"
check "naming pipeline[0].plane" grep -q '"path":"pipeline\[0\].plane"' "$BODY"
f=$(body notch-cube.json '[{"op":"move","vertex":1,"to":[0,0,0],"by":[1,0,0]}]')
post_json /v1/jobs "$f"
expect_eq "move with both to and by is 422" 422 "$CODE"
f=$(body notch-cube.json '[{"op":"inversion_stats","samples":0}]')
post_json /v1/jobs "$f"
expect_eq "inversion_stats with 0 samples is 422" 422 "$CODE"
check "naming pipeline[0].samples" grep -q '"path":"pipeline\[0\].samples"' "$BODY"

finish
