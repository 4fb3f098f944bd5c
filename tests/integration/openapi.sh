#!/bin/bash
# openapi.sh — GET /v1/openapi.json serves the OpenAPI document, and every
# operation it documents is served (no 404 "no resource", no 405) — the
# route table and the document agree (test_openapi checks the converse).
# A path's own 404 (no such scanner) still shows the route is served.
. "$(dirname "$0")/lib.sh" "$@"

start_facetd || { not_ok "facetd starts"; finish; exit 1; }
req GET /v1/openapi.json
expect_eq "the document is served as JSON" "200 application/json" "$CODE $(header Content-Type)"
check "it is OpenAPI 3.1" grep -q '"openapi": "3.1' "$BODY"
cp "$BODY" "$T/doc"
etag=$(header ETag)
req GET /v1/openapi.json -H "If-None-Match: $etag"
expect_eq "it revalidates with 304" 304 "$CODE"

submit notch-cube.json
wait_job "$ID"
# Paths are the keys inside "paths" (indented by one space); methods are
# the keys one level below them.
paths=$(sed -n 's/^  "\(\/[^"]*\)": {$/\1/p' "$T/doc")
check "the document has paths" test -n "$paths"
for p in / "/ui/{file}" /livez /readyz /metrics /v1/version /v1/openapi.json /v1/scanners \
         "/v1/scanners/{serial}/scan" \
         /v1/inspect /v1/jobs "/v1/jobs/{id}" "/v1/jobs/{id}/model" \
         "/v1/jobs/{id}/stats" "/v1/jobs/{id}/events"; do
    echo "$paths" | grep -qxF "$p" && ok "documented: $p" || not_ok "documented: $p"
done
# DELETE goes last: it removes the job the other operations read.
for pass in read delete; do
for p in $paths; do
    methods=$(awk -v p="  \"$p\": {" '
        $0 == p {inside = 1; next}
        inside && /^  [^ ]/ {exit}
        inside && /^   "(get|post|delete|put|patch)": \{/ {gsub(/[" :{]/, ""); print}' "$T/doc")
    url=${p//\{id\}/$ID}
    url=${url//\{serial\}/NO-SUCH-SCANNER}
    for m in $methods; do
        M=$(echo "$m" | tr a-z A-Z)
        [ "$pass" = delete ] && [ "$M" != DELETE ] && continue
        [ "$pass" = read ] && [ "$M" = DELETE ] && continue
        case $M in
            POST) req POST "$url" -H 'Content-Type: application/json' --data-binary "@$MODELS/notch-cube.json" --max-time 5 ;;
            GET) req GET "$url" --max-time 5 ;;
            *) req "$M" "$url" ;;
        esac
        if { [ "$CODE" = 404 ] && grep -q '"urn:facetd:problem:not-found"' "$BODY"; } ||
           [ "$CODE" = 405 ] || [ "$CODE" = 000 ]; then
            not_ok "$M $p is served" "status $CODE"
        else
            ok "$M $p is served ($CODE)"
        fi
    done
done
done
finish
