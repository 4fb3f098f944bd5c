#!/bin/bash
# viewer.sh — the web viewer (docs/viewer.md): GET / and its files are
# served by facetd with no external URL; in headless Chromium (WebGL
# through SwiftShader) the page of a corrected k400 scan shows the job's
# numbers, draws the model (a screenshot of its canvas is not blank), and
# records no JavaScript error; with an API token the page asks for it and
# shows no job data. Without chromium the browser checks are skipped.
. "$(dirname "$0")/lib.sh" "$@"

CHROME=$(command -v chromium || command -v chromium-browser || true)
# browse OUT ARGS... URL: one headless run; virtual time lets the page
# finish its requests and first frame without a fixed sleep.
browse() {
    local out=$1; shift
    timeout $((40 * SLOW)) "$CHROME" --headless --no-sandbox --no-first-run \
        --user-data-dir="$T/chrome" --disable-extensions --mute-audio \
        --use-angle=swiftshader --enable-unsafe-swiftshader \
        --window-size=1200,800 --virtual-time-budget=8000 "$@" >"$out" 2>"$T/chrome.log"
}

start_facetd --workers 1 || { not_ok "facetd starts"; finish; exit 1; }
req GET /
expect_eq "GET / is the page" "200 text/html; charset=utf-8" "$CODE $(header Content-Type)"
check "it allows nothing but this origin" grep -qi "^Content-Security-Policy: default-src 'self'" "$HDRS"
cp "$BODY" "$T/index.html"
etag=$(header ETag)
req GET / -H "If-None-Match: $etag"
expect_eq "it revalidates with 304" 304 "$CODE"
files=$(grep -o '/ui/[a-z.]*' "$T/index.html" | sort -u)
check "the page loads its files from /ui/" test -n "$files"
: >"$T/all"
for f in $files boot.js api.js jobs.js job.js model.js gl.js submit.js scanners.js; do
    f=/ui/${f#/ui/}
    req GET "$f"
    case $f in *.css) want="text/css; charset=utf-8" ;; *) want="text/javascript; charset=utf-8" ;; esac
    expect_eq "$f is served as ${want%%;*}" "200 $want" "$CODE $(header Content-Type)"
    cat "$BODY" >>"$T/all"
done
# every import of every module is a file facetd serves
for m in $(grep -o "from '\./[a-z]*\.js'" "$T/all" | grep -o '[a-z]*\.js' | sort -u); do
    req GET "/ui/$m"
    expect_eq "imported module $m is served" 200 "$CODE"
done
cat "$T/index.html" >>"$T/all"
# absolute and protocol-relative URLs: the page must need nothing else
if grep -nE "https?://|(src|href)=[\"']?//|url\(['\"]?//|import\(['\"]?//" "$T/all" >"$T/urls"; then
    not_ok "no external URL in the page or its files" "$(head -n 3 "$T/urls")"
else
    ok "no external URL in the page or its files"
fi
req GET /ui/nosuch.js
expect_eq "an unknown file is 404" 404 "$CODE"
req GET /ui/app.js -X POST
expect_eq "the files are read-only" 405 "$CODE"

# the corrected sample scan, submitted as a file
req POST '/v1/jobs?format=json&pipeline=correct,report&label=k400' -H 'Content-Type: application/json' \
    --data-binary "@$MODELS/brilliant.scan-k400.json"
expect_eq "a ?format= POST becomes a job" 202 "$CODE"
ID=$(jstr id)
wait_job "$ID" 60
expect_eq "the correction succeeds" succeeded "$STATE_OF"
fb=$(jnum facets_before); fa=$(jnum facets_after); va=$(jnum vertices_after)
# the report op's tiers as the legend must count them
req GET "/v1/jobs/$ID/stats"
tiers=$(jq -r '[.ops[] | select(.op == "report") | .report.facets[].tier] as $t
    | ["table","crown","girdle","pavilion","culet"]
    | map(. as $n | "\($n) \([$t[] | select(. == $n)] | length)") | join(", ")' "$BODY" 2>/dev/null)

if [ -z "$CHROME" ]; then
    skip "the browser checks: chromium is not installed (make deps installs it)"
    finish; exit
fi
start=$(date +%s%N)
browse "$T/job.html" --dump-dom "$URL/#/jobs/$ID"
check "the job page ends ready" grep -q '<body data-state="ready"' "$T/job.html"
check "no JavaScript error" grep -q 'data-errors="0"' "$T/job.html"
grep -q 'data-errors="0"' "$T/job.html" || grep -A3 'id="js-errors"' "$T/job.html" | sed 's/^/#   /'
dd() { sed -n "s/.*<dd data-k=\"$1\">\([^<]*\)<.*/\1/p" "$T/job.html" | head -n 1; }
expect_eq "the page shows the facets before" "$fb" "$(dd facets_before)"
expect_eq "the page shows the facets after" "$fa" "$(dd facets_after)"
expect_eq "the page shows the vertices after" "$va" "$(dd vertices_after)"
expect_eq "the page shows it valid" yes "$(dd valid)"
expect_eq "the page shows the orientation" outward "$(dd orientation)"
hd=$(dd hausdorff)
check "the page shows the Hausdorff distance ($hd mm)" test -n "$hd" -a "$hd" != "—"
check "the page lists a download in every format" \
    grep -q 'data-format="stl-ascii".*data-format="fmb1"' "$T/job.html"
rect=$(sed -n 's/.*data-canvas="\([0-9 ]*\)".*/\1/p' "$T/job.html")
first=$(sed -n 's/.*data-first-frame-ms="\([0-9]*\)".*/\1/p' "$T/job.html")
echo "# first frame ${first:-?} ms after navigation (virtual time)"

browse "$T/tiers.html" --dump-dom "$URL/#/jobs/$ID?colour=tiers"
check "the report's tiers are a colour layer ($tiers)" \
    grep -q "data-tiers=\"$tiers\"" "$T/tiers.html"
check "chosen by the link" grep -q 'value="tiers" checked' "$T/tiers.html"
check "the tiers view has no JavaScript error" grep -q 'data-errors="0"' "$T/tiers.html"

browse "$T/shot.out" --screenshot="$T/shot.png" "$URL/#/jobs/$ID"
set -- $rect
if [ $# -eq 4 ] && probe=$("$BUILD/tools/png_probe" "$T/shot.png" $(($1 + 2)) $(($2 + 2)) $(($3 - 2)) $(($4 - 2))); then
    set -- $probe
    echo "# canvas: $3 per mille covered, $4 shades"
    check "the screenshot shows the model (covered $3‰ of the canvas)" test "$3" -ge 30
    check "shaded, with drawn edges ($4 shades)" test "$4" -ge 8
else
    not_ok "the screenshot can be read" "canvas rect '$rect'"
fi

# a large mesh orbits as a coarse copy: 10^5+ triangles, drawn while the
# camera spins (virtual time: the frame rate itself is tests/bench's)
"$BUILD/tools/gen_scanmesh" --triangles 200000 --sphere --radius 3 "$T/big.obj" >/dev/null
req POST '/v1/jobs?format=obj&pipeline=inspect&label=big' -H 'Content-Type: application/octet-stream' \
    --data-binary "@$T/big.obj"
BIG=$(jstr id)
wait_job "$BIG" 60
# in real time (tests/bench/viewer_fps.py drives the browser over the
# DevTools pipe): the spin draws coarse frames, then full ones
if command -v python3 >/dev/null; then
    python3 tests/bench/viewer_fps.py "$CHROME" "$URL/#/jobs/$BIG?bench=1000" $((60 * SLOW)) \
        >"$T/big.txt" 2>&1
    fig() { sed -n "s/^$1: //p" "$T/big.txt"; }
    big_t=$(fig triangles); big_c=$(fig coarseTriangles)
    check "a $big_t-triangle mesh orbits as a coarse copy of $big_c triangles" \
        test -n "$big_c" -a "${big_c:-0}" -gt 1000 -a "${big_c:-0}" -lt $((${big_t:-0} / 4))
    check "it draws frames coarse ($(fig fps) fps) and in full ($(fig fpsFull) fps)" \
        awk -v a="$(fig fps)" -v b="$(fig fpsFull)" 'BEGIN { exit !(a > 0 && b > 0) }'
    expect_eq "the large mesh has no JavaScript error" 0 "$(fig errors)"
else
    skip "the real-time spin of a large mesh: python3 is not installed"
fi

browse "$T/list.html" --dump-dom "$URL/#/jobs"
check "the job list shows the job" grep -q "<tr data-id=\"$ID\" data-state=\"succeeded\">" "$T/list.html"
check "with its facets before → after" grep -q "$fb → $fa" "$T/list.html"
check "the list has no JavaScript error" grep -q 'data-errors="0"' "$T/list.html"
browse "$T/scan.html" --dump-dom "$URL/#/scanners"
check "the scanners panel loads" grep -q 'id="scanners"' "$T/scan.html"

stop_facetd
STATE_KEEP=1 start_facetd --workers 1 --api-token s3cret || { not_ok "facetd starts with a token"; finish; exit 1; }
browse "$T/tok.html" --dump-dom "$URL/#/jobs/$ID"
check "with a token the page asks for it" grep -q '<form id="token-form">' "$T/tok.html"
check "in a password field" grep -q 'id="token" type="password"' "$T/tok.html"
check "and shows no job data" bash -c "! grep -qE '$ID|data-k=|<tr data-id' '$T/tok.html'"
check "a refused request is no JavaScript error" grep -q 'data-errors="0"' "$T/tok.html"
echo "# browser checks: $((($(date +%s%N) - start) / 1000000)) ms"
finish
