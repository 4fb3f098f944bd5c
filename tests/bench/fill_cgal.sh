#!/bin/bash
# fill_cgal.sh — hole filling with refinement and fairing, facet beside
# CGAL 5.5's triangulate_refine_and_fair_hole on the same holes: a bowl
# whose rim is one hole of 200, 500 and 1,000 vertices (tests/tools/
# gen_open cup N), filled by `facet fill` (every patch checked, the
# result inspected) and by build/bench/cgal_fill (built where libcgal-dev
# is installed: make bench-deps). facet's figure is its kernel time (the
# "ms" of its summary: the fill and the check, without reading, writing
# and the final inspection); the whole command's wall time is shown too.
# CGAL's is the call alone. Each side is the best of RUNS runs (default
# 3). Usage: [RUNS=N] tests/bench/fill_cgal.sh BUILD_DIR
set -u
B=${1:-build}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
cgal="$B/bench/cgal_fill"
[ -x "$cgal" ] || echo "(no $cgal: CGAL's side skipped; make bench-deps)"
printf '%-8s %10s %10s %10s %8s %10s %10s %8s\n' boundary facet_ms \
    facet_wall cgal_ms ratio facet_tris cgal_tris tri_ratio
status=0
for n in 200 500 1000; do
    m="$T/cup$n.off"
    "$B/tools/gen_open" cup "$n" "$m" || { status=1; continue; }
    # best of RUNS: the machine may be shared
    fms="" wall=""
    for r in $(seq "${RUNS:-3}"); do
        t0=$(date +%s%N)
        line=$("$B/facet" fill "$m" -o "$T/out$n.off") || status=1
        t1=$(date +%s%N)
        x=$(sed -n 's/.*"ms":\([0-9.]*\).*/\1/p' <<<"$line")
        w=$(( (t1 - t0) / 1000000 ))
        fms=$(awk -v a="$fms" -v b="$x" 'BEGIN { print (a == "" || b < a) ? b : a }')
        wall=$(awk -v a="$wall" -v b="$w" 'BEGIN { print (a == "" || b < a) ? b : a }')
    done
    ftri=$(sed -n 's/.*"facets_added":\([0-9]*\).*/\1/p' <<<"$line")
    valid=$(sed -n 's/.*"valid":\([a-z]*\).*/\1/p' <<<"$line")
    cms=- ctri=- ratio=- tratio=-
    if [ -x "$cgal" ]; then
        cms=""
        for r in $(seq "${RUNS:-3}"); do
            c=$("$cgal" "$m") || status=1
            x=$(sed -n 's/.*"ms":\([0-9.]*\).*/\1/p' <<<"$c")
            cms=$(awk -v a="$cms" -v b="$x" 'BEGIN { print (a == "" || b < a) ? b : a }')
        done
        ctri=$(sed -n 's/.*"faces_added":\([0-9]*\).*/\1/p' <<<"$c")
        ratio=$(awk -v a="$fms" -v b="$cms" 'BEGIN { printf "%.2f", a / b }')
        tratio=$(awk -v a="$ftri" -v b="$ctri" 'BEGIN { printf "%.2f", a / b }')
        grep -q '"self_intersecting":true' <<<"$c" && ctri="$ctri(SI)"
    fi
    [ "$valid" = true ] || fms="$fms(INVALID)"
    printf '%-8s %10s %10s %10s %8s %10s %10s %8s\n' "$n" "$fms" "$wall" \
        "$cms" "$ratio" "$ftri" "$ctri" "$tratio"
done
exit $status
