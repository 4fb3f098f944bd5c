/* bench_replanar.c — vertex move (local-exp) on the 400-contour scan and
 * the inversion statistics (100 samples × 10 magnitudes) on 1 and 2
 * threads. Prints "name: value unit" lines; each figure is the best of
 * several runs (the machine may be shared). */
#include <stdio.h>
#include <stdlib.h>
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

/* Moves vertex v by m × (its nearest-vertex distance) and returns the best
 * wall time (ms) of reps runs of geo_move, preparation included. */
static double bench_move(const geo_poly *orig, uint32_t v, double m, int reps,
                         geo_replanar_result *ret)
{
    double best = 1e300, d = 1e300;
    for (uint32_t i = 0; i < orig->nverts; i++)
        if (i != v && geo_vdist(orig->verts[i], orig->verts[v]) < d)
            d = geo_vdist(orig->verts[i], orig->verts[v]);
    double dir[3] = {0.36, -0.48, 0.8}, t[3];
    geo_vmadd(orig->verts[v], m * d, dir, t);
    for (int r = 0; r < reps; r++) {
        geo_poly *p = geo_poly_copy(orig);
        double t0 = now();
        if (geo_move(p, v, t, GEO_REPLANAR_LOCAL_EXP, NULL, NULL, NULL,
                            ret, NULL) < 0) {
            fprintf(stderr, "move failed\n");
            exit(1);
        }
        double dt = now() - t0;
        if (dt < best)
            best = dt;
        geo_poly_free(p);
    }
    return best * 1e3;
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
    double total = 0;
    for (size_t i = 0; i < sizeof verts / sizeof verts[0]; i++) {
        geo_replanar_result res;
        double ms = bench_move(p, verts[i], 0.01, 5, &res);
        printf("move_local_exp_k400_v%u: %.2f ms (%u steps, %u of %u "
               "vertices active, %s)\n",
               verts[i], ms, res.steps, res.active_vertices, p->nverts,
               geo_replanar_result_valid(&res) ? "valid" : "NOT valid");
        total += ms;
    }
    printf("move_local_exp_k400_mean: %.2f ms\n", total / 3);

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
