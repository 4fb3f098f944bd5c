#!/bin/bash
# api_job_file.sh — POST /v1/jobs?format=NAME takes the model file itself
# as the body (the viewer's drop zone, curl users): the job runs as the
# JSON form's would, with the same checks and problem+json errors; the
# submitted model comes back from GET /v1/jobs/{id}/model?which=input.
. "$(dirname "$0")/lib.sh" "$@"

start_facetd --workers 1 || { not_ok "facetd starts"; finish; exit 1; }
"$BUILD/facet" convert "$MODELS/notch-cube.json" "$T/cube.stl" >/dev/null 2>&1
"$BUILD/facet" convert "$MODELS/notch-cube.json" "$T/cube.obj" >/dev/null 2>&1
"$BUILD/facet" convert "$MODELS/notch-cube.json" "$T/cube.ply" >/dev/null 2>&1
"$BUILD/facet" convert "$MODELS/notch-cube.json" "$T/cube.off" >/dev/null 2>&1
oct='Content-Type: application/octet-stream'

req POST '/v1/jobs?format=stl&pipeline=inspect&label=drop' -H "$oct" --data-binary "@$T/cube.stl"
expect_eq "an STL body with format=stl is queued" 202 "$CODE"
ID=$(jstr id)
expect_eq "its label came from the query" drop "$(jstr label)"
wait_job "$ID"
expect_eq "the job succeeds" succeeded "$STATE_OF"
expect_eq "it read every facet of the STL (triangles)" 28 "$(jnum facets_before)"

for f in obj ply off; do
    req POST "/v1/jobs?format=$f&pipeline=inspect" -H "$oct" --data-binary "@$T/cube.$f"
    expect_eq "format=$f is queued" 202 "$CODE"
done
req POST '/v1/jobs?format=json&pipeline=inspect' -H 'Content-Type: application/json' --data-binary "@$MODELS/notch-cube.json"
expect_eq "format=json takes a facet-model/1 body with its own media type" 202 "$CODE"
req POST '/v1/jobs?format=stl&pipeline=inspect' -H 'Content-Type: model/stl' --data-binary "@$T/cube.stl"
expect_eq "the format's own media type is accepted" 202 "$CODE"
req POST '/v1/jobs?format=stl&pipeline=inspect,merge' -H "$oct" --data-binary "@$T/cube.stl"
expect_eq "op names separated by commas make a pipeline" 202 "$CODE"
req POST '/v1/jobs?format=stl&pipeline=%5B%22inspect%22%5D' -H "$oct" --data-binary "@$T/cube.stl"
expect_eq "a JSON pipeline in the query works too" 202 "$CODE"

req POST '/v1/jobs?format=stl' -H 'Content-Type: text/plain' --data-binary "@$T/cube.stl"
expect_eq "another media type is 415" 415 "$CODE"
req POST '/v1/jobs?format=ase' -H "$oct" --data-binary "@$T/cube.stl"
expect_eq "a format facetd cannot read is 400" 400 "$CODE"
req POST '/v1/jobs?format=ply&pipeline=inspect' -H "$oct" --data-binary "@$T/cube.stl"
expect_eq "a body that is not the format is 422" 422 "$CODE"
expect_eq "the error names the model and the place" model "$(jstr path)"
check "the detail says why" grep -q 'not a PLY file' "$BODY"
req POST '/v1/jobs?format=stl&pipeline=inspect,nosuchop&colour=red' -H "$oct" --data-binary "@$T/cube.stl"
expect_eq "a bad pipeline and an unknown parameter are 422" 422 "$CODE"
check "both are listed, each with its place" grep -q '"path":"colour".*"path":"pipeline\[1\]"' "$BODY"
check "as problem+json" grep -qi '^Content-Type: application/problem+json' "$HDRS"
req POST '/v1/jobs?format=stl&priority=urgent' -H "$oct" --data-binary "@$T/cube.stl"
expect_eq "a bad priority is 422 as in the JSON form" 422 "$CODE"

req GET "/v1/jobs/$ID/model?which=input&format=stl"
expect_eq "which=input gives the submitted model" 200 "$CODE"
cmp -s "$BODY" "$T/cube.stl" && ok "the input is the model as sent" ||
    { "$BUILD/facet" convert "$BODY" "$T/back.json" >/dev/null 2>&1 &&
      expect_eq "the input has the model's facets" 28 "$(grep -o '"vertices":\[' "$T/back.json" | wc -l)"; }
req GET "/v1/jobs/$ID/model?which=both"
expect_eq "another which is 400" 400 "$CODE"
finish
