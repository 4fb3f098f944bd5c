/* bench_cut.c — plane cut times (lib/cut/cut.h). Targets: the K=400 scan cut
 * by 1,000 random planes through its bounding box under 1 ms per cut; a
 * 1,000,000-facet star-shaped model cut once under 0.5 s. Also a
 * 1,000,000-triangle torus cut along its plane, whose section is an
 * annulus split into several facets (lib/cut/region_split.h). Best of several
 * runs where it is cheap to repeat. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cut.h"
#include "cut_shapes.h"
#include "hole_shapes.h"
#include "model_io.h"
#include "testutil.h"
#include "topo.h"
#include "vec.h"

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

static void random_plane(const double lo[3], const double hi[3],
                         uint64_t *seed, double ret[4])
{
    double n[3], x[3];
    do {
        for (int k = 0; k < 3; k++)
            n[k] = 2 * geo_rand_unit(seed) - 1;
    } while (geo_vdot(n, n) > 1 || geo_vdot(n, n) < 1e-4);
    for (int k = 0; k < 3; k++)
        x[k] = lo[k] + (hi[k] - lo[k]) * geo_rand_unit(seed);
    memcpy(ret, n, sizeof n);
    ret[3] = -geo_vdot(n, x);
}

/* Cuts p by `count` random planes; returns the mean ms per cut. */
static double cut_many(const geo_poly *p, const geo_topo *t, int count,
                       double *ret_components)
{
    double lo[3], hi[3];
    geo_poly_bbox(p, lo, hi);
    uint64_t seed = 1234;
    geo_cut_opts opts;
    geo_cut_opts_default(&opts);
    opts.topo = t;
    geo_poly *out = geo_poly_new();
    double comps = 0, t0 = now_ms();
    for (int i = 0; i < count; i++) {
        double pl[4];
        random_plane(lo, hi, &seed, pl);
        geo_cut_report rep;
        geo_err err;
        if (geo_cut(p, pl, &opts, NULL, out, &rep, &err) < 0) {
            fprintf(stderr, "cut %d: %s\n", i, err.msg);
            exit(1);
        }
        comps += rep.components;
    }
    double ms = (now_ms() - t0) / count;
    geo_poly_free(out);
    *ret_components = comps / count;
    return ms;
}

int main(void)
{
    geo_err err;
    geo_poly *p = proto_model_read_file(tu_model_path("brilliant.scan-k400.json"),
                                        PROTO_FMT_UNKNOWN, NULL, &err);
    if (!p) {
        fprintf(stderr, "%s\n", err.msg);
        return 1;
    }
    double best = 1e30, best_pre = 1e30, comps = 0;
    geo_topo *t = geo_topo_build(p, NULL);
    for (int run = 0; run < 3; run++) {
        double ms = cut_many(p, NULL, 1000, &comps);
        best = fmin(best, ms);
        ms = cut_many(p, t, 1000, &comps);
        best_pre = fmin(best_pre, ms);
    }
    printf("cut_k400_facets: %u facets\n", p->nfacets);
    printf("cut_k400_per_cut: %.3f ms\n", best);
    printf("cut_k400_per_cut_prebuilt_topology: %.3f ms\n", best_pre);
    printf("cut_k400_mean_components: %.3f\n", comps);
    geo_topo_free(t);
    geo_poly_free(p);

    /* 1,000,000 triangles: 501 rings × 1000 segments */
    double t0 = now_ms();
    geo_poly *big = cs_sphere(501, 1000, 0.2);
    if (!big) {
        fprintf(stderr, "out of memory\n");
        return 1;
    }
    printf("cut_big_facets: %u facets\n", big->nfacets);
    printf("cut_big_generate: %.1f ms\n", now_ms() - t0);
    double pl[4] = {0.3, 0.2, 1.0, -0.15};
    geo_poly *out = geo_poly_new();
    geo_cut_report rep;
    double bbest = 1e30, tbest = 1e30;
    for (int run = 0; run < 3; run++) {
        t0 = now_ms();
        if (geo_cut(big, pl, NULL, NULL, out, &rep, &err) < 0) {
            fprintf(stderr, "big cut: %s\n", err.msg);
            return 1;
        }
        bbest = fmin(bbest, now_ms() - t0);
        t0 = now_ms();
        geo_topo *bt = geo_topo_build(big, NULL);
        tbest = fmin(tbest, now_ms() - t0);
        geo_topo_free(bt);
    }
    printf("cut_big_one_cut: %.1f ms\n", bbest);
    printf("cut_big_topology_share: %.1f ms\n", tbest);
    printf("cut_big_result: %u facets, %u components, volume %.6f of %.6f\n",
           out->nfacets, rep.components, rep.volume_after, rep.volume_before);
    geo_poly_free(out);
    geo_poly_free(big);

    /* a torus cut along its plane: the section is an annulus */
    geo_poly *torus = hs_torus(1000, 500, 2.0, 1.0);
    if (!torus) {
        fprintf(stderr, "out of memory\n");
        return 1;
    }
    const double zpl[4] = {0, 0, 1, -0.001};
    out = geo_poly_new();
    bbest = 1e30;
    for (int run = 0; run < 3; run++) {
        t0 = now_ms();
        if (geo_cut(torus, zpl, NULL, NULL, out, &rep, &err) < 0) {
            fprintf(stderr, "torus cut: %s\n", err.msg);
            return 1;
        }
        bbest = fmin(bbest, now_ms() - t0);
    }
    printf("cut_torus_facets: %u facets\n", torus->nfacets);
    printf("cut_torus_along_plane: %.1f ms\n", bbest);
    printf("cut_torus_section: %u components, %u new facets, %u new vertices\n",
           rep.components, rep.new_facets, rep.new_vertices);
    geo_poly_free(out);
    geo_poly_free(torus);
    return 0;
}
