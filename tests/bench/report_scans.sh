#!/bin/bash
# report_scans.sh — the report's figures on corrected scans against their
# truths: for each design (random round brilliants, seeds 1..N, and every
# fancy shape of tests/support/design.c with random proportions), a
# simulated scan (scansim --design, K views, 1 µm silhouette noise), its
# correction (facet correct) and the report of both; prints one row per
# scan with the errors of the crown angle, the pavilion angle (degrees)
# and the table % (corrected minus truth), then the worst of each.
# Usage: report_scans.sh BUILD_DIR [N [K]]
set -u
B=${1:-build}
N=${2:-50}
K=${3:-400}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
for t in gen_designs scansim; do
    [ -x "$B/tools/$t" ] || { echo "report_scans: build $B/tools/$t first (make bench)"; exit 1; }
done
echo "# $(nproc) CPUs; load average $(cut -d' ' -f1-3 /proc/loadavg); K=$K, noise 1 um"
printf '%-22s %10s %10s %10s %8s\n' design crown_err pav_err table_err mains
rows="$T/rows"
: >"$rows"
one() { # name, design file, seed
    "$B/tools/scansim" --design "$2" --k "$K" --seed "$3" --noise 0.001 \
        --truth "$T/t.json" --scan "$T/s.json" >/dev/null 2>&1 || { echo "$1: scansim failed"; return; }
    "$B/facet" correct "$T/s.json" -o "$T/c.json" >/dev/null 2>&1 || { echo "$1: correct failed"; return; }
    "$B/facet" report "$T/t.json" >"$T/rt.json" 2>/dev/null || { echo "$1: no report of the truth"; return; }
    "$B/facet" report "$T/c.json" >"$T/rc.json" 2>"$T/err" || { echo "$1: report: $(cat "$T/err")"; return; }
    jq -r -n --arg name "$1" --slurpfile t "$T/rt.json" --slurpfile c "$T/rc.json" '
        def d(f): if ($t[0] | f) == null or ($c[0] | f) == null then "n/a"
                  else (($c[0] | f) - ($t[0] | f)) end;
        # a step cut has no mains: no angle to compare
        def a(f; m): if ($t[0] | m) == 0 or ($c[0] | m) == 0 then "n/a" else d(f) end;
        [$name, a(.crown_angle_deg; .crown_mains),
         a(.pavilion_angle_deg; .pavilion_mains), d(.table_percent),
         "\($c[0].crown_mains // "?")/\($c[0].pavilion_mains // "?")"] | @tsv' |
        tee -a "$rows" | awk -F'\t' '{
            printf "%-22s", $1
            for (i = 2; i <= 4; i++) printf($i == "n/a" ? " %10s" : " %+10.4f", $i)
            printf " %8s\n", $5 }'
}
for s in $(seq 1 "$N"); do
    "$B/tools/gen_designs" --brilliant "$s" >"$T/d.asc" && one "brilliant-$s" "$T/d.asc" "$s"
done
for shape in oval pear marquise heart trilliant princess cushion emerald radiant asymmetric; do
    for s in 1 2 3; do
        "$B/tools/gen_designs" --shape "$shape" "$s" >"$T/d.asc" 2>/dev/null &&
            one "$shape-$s" "$T/d.asc" "$s"
    done
done
awk -F'\t' '
    function upd(i, v) { if (v == "n/a") { na[i]++; return } v += 0
        if (!(i in lo) || v < lo[i]) lo[i] = v; if (!(i in hi) || v > hi[i]) hi[i] = v }
    { n++; upd(2, $2); upd(3, $3); upd(4, $4) }
    END { printf "scans: %d; crown error %+.4f..%+.4f deg, pavilion %+.4f..%+.4f deg, table %+.4f..%+.4f %%", n, lo[2], hi[2], lo[3], hi[3], lo[4], hi[4]
          if (na[2] + na[3]) printf " (no mains on %d crown / %d pavilion reports)", na[2], na[3]
          printf "\n" }' "$rows"
