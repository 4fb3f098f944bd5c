/* correct_table.c — the acceptance table of the automatic correction
 * (docs/kernels/correct.md): simulated stones of several cuts and
 * seeds scanned with K views (tests/support/stone_sim.h; silhouette noise
 * --sim-noise, 1 µm by default), each scan
 * corrected by geo_correct, and the result compared with the stone.
 *
 *   correct_table [--cuts brilliant,princess,emerald,jubilee,jubilee96]
 *                 [--seeds 1,2,3]
 *                 [--ks 100,400,800] [--angle DEG] [--rel-dev R]
 *                 [--sim-noise MM] [--group-noise MM|0|-1] [--views K]
 *                 [--plane contour|weighted|area] [--order event|paper]
 *                 [--no-collapse] [--no-bevels] [--models DIR]
 *
 * One Markdown table row per scan: cut, seed, K, facets (truth / scan /
 * corrected), Hausdorff distance to the stone of the scan and of the
 * corrected model (µm, sim_hausdorff), volume error of the corrected model
 * (%), groups merged / not merged, the scanner's views and the surface
 * noise the automatic groups used (--views and --group-noise set them:
 * 0 means read off the scan, a negative noise no noise test), whether
 * geo_inspect calls the result valid, whether the row meets the
 * acceptance, and the correction's time. With --models, the sample scans
 * DIR/brilliant.scan-k{100,400,800}.json are added, compared with
 * DIR/brilliant.truth.json. The last line sums up: rows, rows meeting
 * "facets within 10 % and Hausdorff not above the scan's", invalid rows. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "correct.h"
#include "model_io.h"
#include "stone_sim.h"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

typedef struct totals {
    int rows, good, invalid;
} totals;

static void row(const char *cut, const char *seed, unsigned k,
                const geo_poly *truth, const geo_poly *scan,
                const geo_correct_opts *o, totals *t)
{
    geo_poly *p = geo_poly_copy(scan);
    geo_correct_report rep;
    geo_err err;
    double t0 = now();
    int r = p ? geo_correct(p, o, NULL, &rep, &err) : -1;
    double ms = (now() - t0) * 1e3;
    t->rows++;
    if (r < 0) {
        printf("| %s | %s | %u | error: %s |\n", cut, seed, k, p ? err.msg : "oom");
        t->invalid++;
        geo_poly_free(p);
        return;
    }
    double hs = sim_hausdorff(scan, truth, 2000) * 1e3;
    double hc = sim_hausdorff(p, truth, 2000) * 1e3;
    double vt = geo_poly_volume(truth);
    double verr = 100 * (geo_poly_volume(p) - vt) / vt;
    double ferr = (double)p->nfacets / truth->nfacets - 1;
    bool good = ferr <= 0.1 && ferr >= -0.1 && hc <= hs && rep.after.valid;
    t->good += good;
    t->invalid += !rep.after.valid;
    printf("| %s | %s | %u | %u / %u / %u | %.2f | %.2f | %+.3f | %u / %u | %u / %.2f "
           "| %s | %s | %.0f |\n",
           cut, seed, k, truth->nfacets, scan->nfacets, p->nfacets, hs, hc,
           verr, rep.merge.merged, rep.merge.failed, rep.views, rep.noise * 1e3,
           rep.after.valid ? "yes" : "NO", good ? "yes" : "**no**", ms);
    geo_correct_report_clear(&rep);
    geo_poly_free(p);
}

static int split(char *s, char **out, int max)
{
    int n = 0;
    for (char *tok = strtok(s, ","); tok && n < max; tok = strtok(NULL, ","))
        out[n++] = tok;
    return n;
}

int main(int argc, char **argv)
{
    char cuts_s[256] = "brilliant,princess,emerald,jubilee,jubilee96";
    double sim_noise = 0.001;
    char seeds_s[256] = "1,2,3", ks_s[256] = "100,400,800";
    const char *models = NULL;
    geo_correct_opts o;
    geo_correct_opts_default(&o);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--no-collapse") == 0) {
            o.collapse_clusters = false;
            continue;
        }
        if (strcmp(a, "--no-bevels") == 0) {
            o.merge.bevels = false;
            continue;
        }
        if (!v) {
            fprintf(stderr, "correct_table: %s needs a value\n", a);
            return 2;
        }
        i++;
        if (strcmp(a, "--cuts") == 0)
            snprintf(cuts_s, sizeof cuts_s, "%s", v);
        else if (strcmp(a, "--seeds") == 0)
            snprintf(seeds_s, sizeof seeds_s, "%s", v);
        else if (strcmp(a, "--ks") == 0)
            snprintf(ks_s, sizeof ks_s, "%s", v);
        else if (strcmp(a, "--angle") == 0)
            o.merge.max_angle_deg = atof(v);
        else if (strcmp(a, "--sim-noise") == 0)
            sim_noise = atof(v);
        else if (strcmp(a, "--group-noise") == 0)
            o.merge.noise = atof(v);
        else if (strcmp(a, "--views") == 0)
            o.merge.views = (uint32_t)strtoul(v, NULL, 10);
        else if (strcmp(a, "--rel-dev") == 0)
            o.merge.rel_deviation = atof(v);
        else if (strcmp(a, "--plane") == 0)
            o.merge.plane = strcmp(v, "contour") == 0    ? GEO_MERGE_PLANE_CONTOUR
                            : strcmp(v, "weighted") == 0 ? GEO_MERGE_PLANE_CONTOUR_WEIGHTED
                                                         : GEO_MERGE_PLANE_AREA;
        else if (strcmp(a, "--order") == 0)
            o.merge.lift_order = strcmp(v, "paper") == 0 ? GEO_LIFT_PAPER
                                                         : GEO_LIFT_EVENT_HEIGHT;
        else if (strcmp(a, "--models") == 0)
            models = v;
        else {
            fprintf(stderr, "correct_table: unknown option %s\n", a);
            return 2;
        }
    }
    char *cuts[8], *seeds[32], *ks[16];
    int nc = split(cuts_s, cuts, 8), ns = split(seeds_s, seeds, 32),
        nk = split(ks_s, ks, 16);
    printf("| cut | seed | K | facets truth / scan / corrected | Hausdorff scan µm "
           "| Hausdorff corrected µm | volume error %% | groups merged / not "
           "| views / noise µm | valid | meets | ms |\n"
           "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    totals t = {0, 0, 0};
    for (int c = 0; c < nc; c++) {
        enum sim_cut cut = strcmp(cuts[c], "princess") == 0  ? SIM_PRINCESS
                           : strcmp(cuts[c], "emerald") == 0 ? SIM_EMERALD
                           : strcmp(cuts[c], "jubilee") == 0 ? SIM_JUBILEE
                           : strcmp(cuts[c], "jubilee96") == 0 ? SIM_JUBILEE96
                                                             : SIM_BRILLIANT;
        for (int s = 0; s < ns; s++) {
            uint64_t seed = strtoull(seeds[s], NULL, 10);
            geo_poly *stone = sim_stone(cut, seed);
            for (int k = 0; stone && k < nk; k++) {
                unsigned kv = (unsigned)strtoul(ks[k], NULL, 10);
                geo_poly *scan = sim_scan(stone, kv, sim_noise, seed);
                if (scan)
                    row(cuts[c], seeds[s], kv, stone, scan, &o, &t);
                geo_poly_free(scan);
            }
            geo_poly_free(stone);
        }
    }
    if (models) {
        char path[4096];
        geo_err err;
        snprintf(path, sizeof path, "%s/brilliant.truth.json", models);
        geo_poly *truth = proto_model_read_file(path, PROTO_FMT_UNKNOWN, NULL, &err);
        unsigned kk[3] = {100, 400, 800};
        for (int k = 0; truth && k < 3; k++) {
            snprintf(path, sizeof path, "%s/brilliant.scan-k%u.json", models, kk[k]);
            geo_poly *scan = proto_model_read_file(path, PROTO_FMT_UNKNOWN, NULL, &err);
            if (scan)
                row("sample brilliant", "—", kk[k], truth, scan, &o, &t);
            geo_poly_free(scan);
        }
        geo_poly_free(truth);
    }
    printf("\nrows: %d, meeting the acceptance (facets within 10%%, Hausdorff "
           "not above the scan's, valid): %d, invalid: %d\n", t.rows, t.good,
           t.invalid);
    return t.invalid ? 1 : 0;
}
