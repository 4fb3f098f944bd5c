#!/bin/bash
# inspect_vs_cgal.sh — the whole `facet inspect --threads 1` process against
# CGAL 5.5's PMP::does_self_intersect in-process (the mesh already built,
# its reading not counted; tests/bench/cgal_selfint.cpp), on the same mesh:
# three scanned-like meshes of 26k, 51k and 91k triangles (gen_scanmesh,
# seeds 1-3), the 1,002,252-triangle cube-sphere and the K=400 gem scan.
# facet reads the facet-model/1 file (the scanned meshes without planes),
# CGAL the OBJ of the same vertices and triangles (the gem's polygons
# triangulated for CGAL). Best of RUNS (default 3) wall times, the two
# programs interleaved, and beside them the best CPU times of the same
# runs, since a shared machine moves wall times. Also facet's peak RSS on the
# sphere against its vertex and index arrays. Prints "name: value"
# lines; skipped (exit 0) where cgal_selfint was not built.
# Usage: inspect_vs_cgal.sh BUILD_DIR
set -u
B=${1:-build}
RUNS=${BENCH_RUNS:-3}
if [ ! -x "$B/bench/cgal_selfint" ]; then
    echo "inspect_vs_cgal: skipped ($B/bench/cgal_selfint not built: make bench-deps)"
    exit 0
fi
T=$(mktemp -d /tmp/facet-vs-cgal.XXXXXX)
trap 'rm -rf "$T"' EXIT
echo "# $(nproc) CPUs; load average $(cut -d' ' -f1-3 /proc/loadavg)"

for s in 1:26000 2:50000 3:90000; do
    "$B/tools/gen_scanmesh" --triangles "${s#*:}" --seed "${s%%:*}" \
        "$T/scan${s%%:*}.json" "$T/scan${s%%:*}.obj" >/dev/null || exit 1
done
"$B/tools/gen_scanmesh" --triangles 1000000 --sphere --radius 1 \
    "$T/sphere.json" "$T/sphere.obj" >/dev/null || exit 1
cp tests/data/models/brilliant.scan-k400.json "$T/k400.json"
"$B/facet" convert "$T/k400.json" "$T/k400.obj" >/dev/null || exit 1

# "wall cpu" seconds of one facet run (bash's time: real, user + sys).
facet_run() {
    local TIMEFORMAT='%R %U %S'
    { time "$B/facet" inspect --threads 1 "$1" >/dev/null; } 2>&1 |
        awk '{printf "%.4f %.4f\n", $1, $2 + $3}'
}
# "wall cpu" seconds of CGAL's does_self_intersect.
cgal_run() {
    "$B/bench/cgal_selfint" "$1" 1 |
        awk '{printf "%.4f %.4f\n", $2 / 1000, $4 / 1000}'
}

compare() { # name json obj target
    local fw=1e9 fc=1e9 cw=1e9 cc=1e9 r w c
    lt() { awk -v a="$1" -v b="$2" 'BEGIN {exit !(a < b)}'; }
    for r in $(seq "$RUNS"); do
        read -r w c < <(facet_run "$2")
        lt "$w" "$fw" && fw=$w
        lt "$c" "$fc" && fc=$c
        read -r w c < <(cgal_run "$3")
        lt "$w" "$cw" && cw=$w
        lt "$c" "$cc" && cc=$c
    done
    awk -v n="$1" -v fw="$fw" -v fc="$fc" -v cw="$cw" -v cc="$cc" -v t="$4" '
        BEGIN {
            printf "inspect_vs_cgal_%s: facet %.1f ms, cgal %.1f ms, ", n,
                   fw * 1e3, cw * 1e3
            printf "ratio %.2f (target <= %s); ", fw / cw, t
            printf "cpu facet %.1f ms, cgal %.1f ms, ratio %.2f\n", fc * 1e3,
                   cc * 1e3, (cc > 0 ? fc / cc : 0)
        }'
}

compare scan26k "$T/scan1.json" "$T/scan1.obj" 0.5
compare scan51k "$T/scan2.json" "$T/scan2.obj" 0.5
compare scan91k "$T/scan3.json" "$T/scan3.obj" 0.5
compare sphere1m "$T/sphere.json" "$T/sphere.obj" 0.5
compare k400 "$T/k400.json" "$T/k400.obj" 0.2

# Peak RSS on the sphere against its vertex (24 B) and index (12 B per
# triangle) arrays.
if [ -x /usr/bin/time ]; then
    kb=$(/usr/bin/time -f %M "$B/facet" inspect --threads 1 "$T/sphere.json" \
         2>&1 >/dev/null | tail -n 1)
    nv=$(grep -c '^\[' "$T/sphere.json")
    nt=$(grep -c '^{"vertices"' "$T/sphere.json")
    awk -v kb="$kb" -v nv="$nv" -v nt="$nt" '
        BEGIN {
            a = (24 * nv + 12 * nt) / 1048576
            printf "inspect_sphere1m_peak_rss: %.1f MB, %.2f x the ", kb / 1024,
                   kb / 1024 / a
            printf "vertex+index arrays (%.1f MB; target <= 3)\n", a
        }'
else
    echo "inspect_sphere1m_peak_rss: /usr/bin/time is not installed"
fi
