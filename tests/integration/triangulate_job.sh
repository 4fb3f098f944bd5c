#!/bin/bash
# triangulate_job.sh — F-rep objects through the job API: a frep-object/1
# input with the triangulate op gives a closed mesh served like any
# job's model, the quality report in the statistics, progress while it
# runs; a frep input alone gets the triangulation by default; a Q_LEV 10
# job stops soon after DELETE; mismatched inputs and pipelines and bad
# objects are 422 with the place named.
. "$(dirname "$0")/lib.sh" "$@"

D=tests/data/frep
# frep_body OBJECT [PIPELINE_JSON]: a request with a frep input; prints
# its path.
frep_body() {
    local f
    f=$(mktemp "$T/body.XXXXXX")
    { printf '{%s"frep":' "${2:+\"pipeline\":$2,}"; cat "$D/$1"; printf '}'; } >"$f"
    echo "$f"
}

start_facetd --workers 1 || { not_ok "facetd starts"; finish; exit 1; }
ok "facetd starts and is ready"

req GET /v1/version
check "/v1/version lists the triangulate op" grep -q '"triangulate"' "$BODY"

# the sphere at low levels, then inspected
f=$(frep_body sphere.json '[{"op":"triangulate","quad_levels":6,"binary_levels":7,"fill":"area","refine":true,"fair":"uniform"},"inspect"]')
post_json /v1/jobs "$f"
expect_eq "a frep job is accepted (202)" 202 "$CODE"
ID=$(jstr id)
check "the stored pipeline is canonical" grep -q '"sharpen":true' "$BODY"
wait_job "$ID"
expect_eq "the frep job succeeds" succeeded "$STATE_OF"
check "the summary says the mesh is valid and closed" \
    grep -q '"valid":true' "$BODY"
check "the summary counts no self-intersections" \
    grep -q '"self_intersections":0' "$BODY"
check "a frep job has no counts before" bash -c "! grep -q facets_before '$BODY'"
req GET "/v1/jobs/$ID/model?format=obj"
expect_eq "the model is served" 200 "$CODE"
ntri=$(grep -c '^f ' "$BODY")
check "the model is a triangle mesh ($ntri triangles)" test "$ntri" -gt 1000
req GET "/v1/jobs/$ID/stats"
expect_eq "the statistics are served" 200 "$CODE"
check "the stats carry the triangulation report" \
    grep -q '"op":"triangulate"' "$BODY"
check "with its deviation metrics" grep -q '"normal_deviation":{' "$BODY"
check "and its topology" grep -q '"boundary_edges":0' "$BODY"
check "and the inspection after it" grep -q '"before":{' "$BODY"

# the gem with its hard edges, default fill/fair
f=$(frep_body gem.json '[{"op":"triangulate","quad_levels":6,"binary_levels":7}]')
post_json /v1/jobs "$f"
GEM=$(jstr id)
wait_job "$GEM"
expect_eq "the gem job succeeds" succeeded "$STATE_OF"
check "the gem mesh has no self-intersections" \
    grep -q '"self_intersections":0' "$BODY"

# a frep alone: triangulate at its defaults (canceled right away here)
f=$(frep_body ellipsoid.json)
post_json /v1/jobs "$f"
expect_eq "a frep without a pipeline is accepted" 202 "$CODE"
check "its pipeline is triangulate at Q_LEV 9" \
    grep -q '"op":"triangulate","quad_levels":9,"binary_levels":10' "$BODY"
DEF=$(jstr id)
req DELETE "/v1/jobs/$DEF"

# cancellation of a long job: the blob at Q_LEV 10
f=$(frep_body blob83.json '[{"op":"triangulate","quad_levels":10,"binary_levels":11}]')
post_json /v1/jobs "$f"
LONG=$(jstr id)
state=""; prog=0
for i in $(seq 1 $((100 * SLOW))); do
    req GET "/v1/jobs/$LONG"
    state=$(jstr state); prog=$(jnum progress)
    [ "$state" = running ] && awk -v p="$prog" 'BEGIN{exit !(p > 0)}' && break
    sleep 0.1
done
expect_eq "the Q_LEV 10 job runs" running "$state"
check "it reports progress ($prog)" awk -v p="$prog" 'BEGIN{exit !(p > 0 && p < 1)}'
t0=$(date +%s%N)
req DELETE "/v1/jobs/$LONG"
check "DELETE is accepted ($CODE)" test "$CODE" -lt 300
wait_job "$LONG" 20
ms=$((($(date +%s%N) - t0) / 1000000))
expect_eq "the job ends canceled" canceled "$STATE_OF"
check "it stopped within $((2000 * SLOW)) ms ($ms ms)" test "$ms" -lt $((2000 * SLOW))

# inputs and pipelines that do not fit
f=$(frep_body sphere.json '["inspect"]')
post_json /v1/jobs "$f"
expect_eq "a frep with a model op first is 422" 422 "$CODE"
check "it says to start with triangulate" grep -q "start with 'triangulate'" "$BODY"
f=$(body brilliant.scan-k400.json '["triangulate"]')
post_json /v1/jobs "$f"
expect_eq "triangulate on a model is 422" 422 "$CODE"
check "it says triangulate needs a frep" grep -q "needs a 'frep' input" "$BODY"
printf '{"frep":{"format":"frep-object/1","bounds":[[-1,-1,-1],[1,1,1]],"shape":{"sphere":{"center":[0,0,0],"radius":-1}}}}' >"$T/bad.json"
post_json /v1/jobs "$T/bad.json"
expect_eq "a bad object is 422" 422 "$CODE"
check "the error names the place" grep -q '"path":"frep.shape.sphere' "$BODY"
printf '{"frep":{"format":"frep-object/1","bounds":[[-1,-1,-1],[1,1,1]],"shape":{"sphere":{"center":[0,0,0],"radius":1}}},"pipeline":[{"op":"triangulate","fair":"smooth"}]}' >"$T/bad2.json"
post_json /v1/jobs "$T/bad2.json"
expect_eq "a bad parameter is 422" 422 "$CODE"
check "the error names the parameter" grep -q 'pipeline\[0\].fair' "$BODY"
# an object too big for its bounds fails as a job, with the reason
printf '{"frep":{"format":"frep-object/1","bounds":[[-0.5,-0.5,-0.5],[0.5,0.5,0.5]],"shape":{"sphere":{"center":[0,0,0],"radius":0.7}}},"pipeline":[{"op":"triangulate","quad_levels":5,"binary_levels":6}]}' >"$T/big.json"
post_json /v1/jobs "$T/big.json"
BIG=$(jstr id)
wait_job "$BIG"
expect_eq "a frep leaving its bounds fails" failed "$STATE_OF"
check "the job says why" grep -q "reaches the boundary" "$BODY"

finish
