#!/bin/bash
# correct.sh — the automatic post-scan correction end to end: `facet
# correct` and `facet merge` offline (summaries, reports, exit codes), and
# facetd's "correct" pipeline serving byte for byte the model `facet correct`
# writes (the convex path by default; with the op's convex: false, the one
# `facet correct --no-convex` writes), with statistics that call it valid.
. "$(dirname "$0")/lib.sh" "$@"
F="$BUILD/facet"
K400=$MODELS/brilliant.scan-k400.json

# within_10pct TEXT: its "facets_after" is within 10 % of the stone's 121
within_10pct() {
    local n
    n=$(grep -o '"facets_after":[0-9]*' <<<"$1" | head -n 1 | cut -d: -f2)
    [ -n "$n" ] && [ "$n" -ge 109 ] && [ "$n" -le 133 ]
}

out=$("$F" correct "$K400" -o "$T/offline.json" --report "$T/report.json")
rc=$?
expect_eq "facet correct succeeds" 0 "$rc"
check "its summary says valid" grep -q '"valid":true' <<<"$out"
check "the scan's 1808 facets become the stone's 121 within 10 %" \
    within_10pct "$out"
check "the summary names the scanner's 400 views" grep -q '"views":400,' <<<"$out"
check "the report lists groups, moved vertices and both statistics" \
    grep -q '"group_list"' "$T/report.json"
check "the corrected model passes facet inspect as valid" \
    bash -c "'$F' inspect '$T/offline.json' | grep -q '\"valid\": *true'"

out=$("$F" merge "$K400" --groups "0,99999" -o "$T/m.json" 2>"$T/err")
rc=$?
expect_eq "merge with a facet out of range is bad input" 1 "$rc"
check "it names the facet" grep -q "facet 99999 out of range" "$T/err"
"$F" merge "$K400" -o "$T/m.json" >/dev/null 2>&1
expect_eq "merge without --groups or --auto is a usage error" 2 "$?"
out=$("$F" merge "$K400" --auto -o "$T/m.json")
check "merge --auto merges every group it finds" grep -q '"failed":0' <<<"$out"

start_facetd --workers 1 || { not_ok "facetd starts"; finish; exit 1; }
submit brilliant.scan-k400.json '"correct"'
expect_eq "a job with pipeline \"auto\" is accepted" 202 "$CODE"
wait_job "$ID" 60
expect_eq "the job succeeds" succeeded "$STATE_OF"
check "its summary says the result is valid" grep -q '"valid":true' "$BODY"
check "its summary counts the stone's 121 facets within 10 %" \
    within_10pct "$(cat "$BODY")"
req GET "/v1/jobs/$ID/model?format=json"
cp "$BODY" "$T/served.json"
check "the served model equals facet correct's, byte for byte" \
    cmp -s "$T/served.json" "$T/offline.json"
req GET "/v1/jobs/$ID/stats"
# "after" is the last member of the statistics, so its "valid" comes last
expect_eq "the statistics after the correction say valid" '"valid":true' \
    "$(grep -o '"valid":[a-z]*' "$BODY" | tail -n 1)"
check "the statistics report the correct op" grep -q '"op":"correct"' "$BODY"
check "by default the convex path gave the result" \
    grep -q '"convex":{"used":true,"reason":null' "$BODY"

# the merge alone, asked for by the op's argument as by facet correct
# --no-convex
"$F" correct --no-convex "$K400" -o "$T/merged.json" >/dev/null
check "the merge alone gives another model than the convex path" \
    bash -c "! cmp -s '$T/merged.json' '$T/offline.json'"
submit brilliant.scan-k400.json '[{"op":"correct","convex":false}]'
expect_eq "a correct job with convex: false is accepted" 202 "$CODE"
wait_job "$ID" 60
expect_eq "it succeeds" succeeded "$STATE_OF"
req GET "/v1/jobs/$ID/model?format=json"
cp "$BODY" "$T/served-merged.json"
check "the served model equals facet correct --no-convex's, byte for byte" \
    cmp -s "$T/served-merged.json" "$T/merged.json"
req GET "/v1/jobs/$ID/stats"
check "a correction asked for the merge alone says so (convex: null)" \
    grep -q '"convex":null' "$BODY"
finish
