/* stitch_halves.c — the stitching experiment on real pairs: a closed
 * model (a gem) is cut by a random plane (tilted up to 15°, within the
 * middle 40% of its height), a band of random width (0.05–0.5 mm, or
 * as given) is removed around that plane, the two halves are opened
 * (their cap facets dropped) and stitched back (lib/mesh/stitch.h); the
 * result's validity and its Hausdorff distance to the original are
 * printed, one JSON line per case, with the facets of the model wholly
 * inside the band (lost: no piece of them is left on either half), the
 * stitch's method and its time.
 *
 *   stitch_halves MODEL CASES [MAX_BAND_MM | seam | overlap]
 *
 * seam: no band, the halves meet on the cut plane, the lower half's rim
 * edges each split at their midpoint, their facets cut in two there
 * (one polyline, sampled differently); overlap: the halves overlap by 0.05–0.5 mm instead of a
 * band removed (no valid solid is expected: each must be reported
 * invalid, which the exit status then counts as a failure).
 *
 * With STITCH_HALVES_DUMP=DIR set, each case's two halves are written
 * there (caseN-top.json, caseN-bot.json) to replay with `facet stitch`.
 * Exit 0 when every case gives a valid solid, 1 otherwise, 2 on usage. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "ctx.h"
#include "cut.h"
#include "hausdorff.h"
#include "model_io.h"
#include "stats.h"
#include "rim_split.h"
#include "stitch.h"
#include "vec.h"

/* The part of m on the side plane ≤ 0, without the facets the cut put on
 * the plane: an open half. NULL when the cut fails. */
static geo_poly *open_half(const geo_poly *m, const double plane[4])
{
    geo_poly *out = geo_poly_new();
    geo_cut_report rep;
    geo_err err = {{0}};
    if (geo_cut(m, plane, NULL, NULL, out, &rep, &err) < 0 || rep.empty ||
        rep.first_new_facet == GEO_NONE) {
        fprintf(stderr, "stitch_halves: cut: %s\n", err.msg);
        return geo_poly_free(out);
    }
    bool *keep = malloc(out->nfacets * sizeof *keep);
    for (uint32_t f = 0; f < out->nfacets; f++)
        keep[f] = f < rep.first_new_facet;
    geo_poly_compact(out, keep, NULL, NULL);
    free(keep);
    return out;
}

int main(int argc, char **argv)
{
    if (argc < 3 || argc > 4) {
        fprintf(stderr, "usage: stitch_halves MODEL CASES "
                        "[MAX_BAND_MM | seam | overlap]\n");
        return 2;
    }
    geo_err err = {{0}};
    geo_poly *m = proto_model_read_file(argv[1], PROTO_FMT_UNKNOWN, NULL,
                                        &err);
    if (!m) {
        fprintf(stderr, "stitch_halves: %s\n", err.msg);
        return 2;
    }
    int cases = atoi(argv[2]);
    bool seam = argc == 4 && !strcmp(argv[3], "seam"),
         overlap = argc == 4 && !strcmp(argv[3], "overlap");
    double max_band = argc == 4 && !seam && !overlap ? atof(argv[3]) : 0.5;
    double lo = INFINITY, hi = -INFINITY, c[3] = {0, 0, 0};
    for (uint32_t v = 0; v < m->nverts; v++) {
        lo = fmin(lo, m->verts[v][2]);
        hi = fmax(hi, m->verts[v][2]);
        for (int k = 0; k < 3; k++)
            c[k] += m->verts[v][k] / m->nverts;
    }
    uint64_t seed = 20261201;
    int status = 0, nvalid = 0;
    double worst = 0;
    for (int i = 0; i < cases; i++) {
        double tilt = geo_rand_unit(&seed) * 15 * M_PI / 180,
               az = geo_rand_unit(&seed) * 2 * M_PI;
        double n[3] = {sin(tilt) * cos(az), sin(tilt) * sin(az), cos(tilt)};
        double z = c[2] + (geo_rand_unit(&seed) - 0.5) * 0.4 * (hi - lo);
        double band = 0.05 + geo_rand_unit(&seed) * (max_band - 0.05);
        double at[3] = {c[0], c[1], z};
        double d = -geo_vdot(n, at);
        /* seam: the halves meet; overlap: each reaches band/2 past the plane */
        if (seam)
            band = 0;
        else if (overlap)
            band = -band;
        /* top: n·x + d ≥ band/2, written as −n·x − d + band/2 ≤ 0 */
        double ptop[4] = {-n[0], -n[1], -n[2], -d + band / 2};
        double pbot[4] = {n[0], n[1], n[2], d + band / 2};
        geo_poly *top = open_half(m, ptop), *bot = open_half(m, pbot);
        if (seam && bot) {
            geo_poly *b2 = rim_split(bot);
            geo_poly_free(bot);
            bot = b2;
        }
        /* STITCH_HALVES_DUMP=DIR keeps each case's halves to replay */
        const char *dump = getenv("STITCH_HALVES_DUMP");
        if (dump && top && bot) {
            char path[512];
            snprintf(path, sizeof path, "%s/case%d-top.json", dump, i);
            proto_model_write_file(top, path, PROTO_FMT_JSON, &err);
            snprintf(path, sizeof path, "%s/case%d-bot.json", dump, i);
            proto_model_write_file(bot, path, PROTO_FMT_JSON, &err);
        }
        /* facets wholly inside the band: nothing of them is left to extend */
        unsigned lost = 0;
        for (uint32_t f = 0; f < m->nfacets; f++) {
            bool inside = true;
            for (uint32_t k = 0; k < geo_poly_facet_size(m, f) && inside; k++) {
                const double *x = m->verts[geo_poly_facet(m, f)[k]];
                inside = geo_plane_eval(ptop, x) > 0 && geo_plane_eval(pbot, x) > 0;
            }
            lost += inside;
        }
        geo_poly *out = geo_poly_new();
        geo_stitch_report rep;
        memset(&rep, 0, sizeof rep);
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        int r = top && bot ? geo_stitch(top, bot, NULL, NULL, out, &rep, &err)
                           : -1;
        clock_gettime(CLOCK_MONOTONIC, &t1);
        double ms = (t1.tv_sec - t0.tv_sec) * 1e3 + (t1.tv_nsec - t0.tv_nsec) / 1e6;
        bool valid = false;
        double hd = INFINITY;
        if (r == 0) {
            geo_stats st;
            if (geo_inspect(out, NULL, NULL, &st, &err) == 0) {
                valid = st.valid;
                geo_stats_clear(&st);
            }
            geo_hausdorff(out, m, &hd, &err);
        }
        nvalid += valid;
        if (!valid)
            status = 1;
        else if (hd > worst)
            worst = hd;
        printf("{\"case\":%d,\"tilt_deg\":%.1f,\"z\":%.3f,\"band_mm\":%.3f,"
               "\"lost_facets\":%u,\"stitched\":%s,\"valid\":%s,\"hausdorff_um\":%.1f,"
               "\"method\":\"%s\",\"planes\":%u,\"band\":%s,\"welded\":%u,"
               "\"inserted\":%u,\"trimmed\":%s,"
               "\"left_open\":%u,\"ms\":%.2f}\n",
               i, tilt * 180 / M_PI, z, band, lost, r == 0 ? "true" : "false",
               valid ? "true" : "false", hd * 1000,
               geo_stitch_method_name(rep.method), rep.planes, rep.band ? "true" : "false", rep.welded, rep.inserted,
               rep.trimmed ? "true" : "false", rep.fill.nopen, ms);
        geo_stitch_report_clear(&rep);
        geo_poly_free(top);
        geo_poly_free(bot);
        geo_poly_free(out);
    }
    printf("{\"cases\":%d,\"valid\":%d,\"worst_hausdorff_um\":%.1f}\n", cases,
           nvalid, worst * 1000);
    geo_poly_free(m);
    return status;
}
