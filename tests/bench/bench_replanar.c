/* bench_replanar.c — vertex move (least-norm and local-exp) on the
 * 400-contour scan: its time, and how local an edit of δ = 0.034 µm stays
 * (the largest move of another vertex, in δ); the inversion statistics
 * (100 samples × 10 magnitudes) on 1 and 2 threads. Prints "name: value unit" lines; each figure is the best of
 * several runs (the machine may be shared). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "inversion.h"
#include "parallel.h"
#include "replanar.h"
#include "testutil.h"
#include "tu_load.h"
#include "vec.h"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Moves vertex v to t with schedule s and returns the best wall time (ms)
 * of reps runs of geo_move, preparation included; *ret_other is the
 * largest move of another vertex. */
static double bench_move_to(const geo_poly *orig, uint32_t v,
                            const double t[3], enum geo_replanar_schedule s,
                            int reps, geo_replanar_result *ret,
                            double *ret_other)
{
    double best = 1e300;
    for (int r = 0; r < reps; r++) {
        geo_poly *p = geo_poly_copy(orig);
        double t0 = now();
        if (geo_move(p, v, t, s, NULL, NULL, NULL, ret, NULL) < 0) {
            fprintf(stderr, "move failed\n");
            exit(1);
        }
        double dt = now() - t0;
        if (dt < best)
            best = dt;
        double m = 0;
        for (uint32_t i = 0; i < p->nverts; i++)
            if (i != v && geo_vdist(p->verts[i], orig->verts[i]) > m)
                m = geo_vdist(p->verts[i], orig->verts[i]);
        *ret_other = m;
        geo_poly_free(p);
    }
    return best * 1e3;
}

/* Moves vertex v by m × (its nearest-vertex distance). */
static double bench_move(const geo_poly *orig, uint32_t v, double m,
                         enum geo_replanar_schedule s, int reps,
                         geo_replanar_result *ret)
{
    double d = 1e300, other;
    for (uint32_t i = 0; i < orig->nverts; i++)
        if (i != v && geo_vdist(orig->verts[i], orig->verts[v]) < d)
            d = geo_vdist(orig->verts[i], orig->verts[v]);
    double dir[3] = {0.36, -0.48, 0.8}, t[3];
    geo_vmadd(orig->verts[v], m * d, dir, t);
    return bench_move_to(orig, v, t, s, reps, ret, &other);
}

static double bench_stats(const geo_poly *p, int threads, int reps,
                          geo_inversion_stats *ret)
{
    par_pool *pool = par_pool_new(threads);
    geo_ctx ctx = {.seed = 1, .parallel_for = par_for, .pf_user = pool};
    double best = 1e300;
    for (int r = 0; r < reps; r++) {
        geo_inversion_stats_clear(ret);
        double t0 = now();
        if (geo_inversion_stats_run(p, NULL, &ctx, ret, NULL) < 0) {
            fprintf(stderr, "inversion statistics failed\n");
            exit(1);
        }
        double dt = now() - t0;
        if (dt < best)
            best = dt;
    }
    par_pool_free(pool);
    return best;
}

int main(void)
{
    geo_poly *p = tu_load_model("brilliant.scan-k400.json");
    if (!p)
        return 1;
    static const uint32_t verts[] = {5, 500, 2000};
    static const enum geo_replanar_schedule scheds[] = {
        GEO_REPLANAR_LEAST_NORM, GEO_REPLANAR_LOCAL_EXP};
    for (size_t k = 0; k < 2; k++) {
        const char *name = geo_replanar_schedule_name(scheds[k]);
        double total = 0;
        for (size_t i = 0; i < sizeof verts / sizeof verts[0]; i++) {
            geo_replanar_result res;
            double ms = bench_move(p, verts[i], 0.01, scheds[k], 5, &res);
            printf("move_%s_k400_v%u: %.2f ms (%u steps, %u of %u "
                   "vertices active, %s)\n",
                   name, verts[i], ms, res.steps, res.active_vertices,
                   p->nverts,
                   geo_replanar_result_valid(&res) ? "valid" : "NOT valid");
            total += ms;
        }
        printf("move_%s_k400_mean: %.2f ms\n", name, total / 3);
    }
    /* a local edit: δ along x, as the correction issue checks it */
    static const uint32_t edits[] = {1000, 2000, 3000};
    const double delta = 3.4e-5;
    for (size_t k = 0; k < 2; k++) {
        const char *name = geo_replanar_schedule_name(scheds[k]);
        for (size_t i = 0; i < sizeof edits / sizeof edits[0]; i++) {
            geo_replanar_result res;
            double t[3], other;
            memcpy(t, p->verts[edits[i]], sizeof t);
            t[0] += delta;
            double ms = bench_move_to(p, edits[i], t, scheds[k], 3, &res,
                                      &other);
            printf("local_edit_%s_k400_v%u: %.2f delta (largest other "
                   "move; %.2f ms, %s)\n",
                   name, edits[i], other / delta, ms,
                   geo_replanar_result_valid(&res) ? "valid" : "NOT valid");
        }
    }

    geo_inversion_stats st = {0};
    double t1 = bench_stats(p, 1, 2, &st);
    printf("inversion_stats_k400_100x10_1thread: %.2f s\n", t1);
    double t2 = bench_stats(p, 2, 2, &st);
    printf("inversion_stats_k400_100x10_2threads: %.2f s\n", t2);
    for (uint32_t k = 0; k < st.nrows; k++)
        printf("inversion_k400_p_m%g: %.2f\n", st.rows[k].m, st.rows[k].p);
    geo_inversion_stats_clear(&st);
    geo_poly_free(p);
    return 0;
}
