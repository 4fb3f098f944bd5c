/* bench_inside.c — batch point classification: 1,000,000 random points
 * in the bounding box of the K=400 scanned brilliant, with 1 and 2
 * threads (best of several runs), plus the preparation time and the
 * random-ray and winding-number tests per point for comparison. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "inside.h"
#include "model_io.h"
#include "parallel.h"
#include "testutil.h"

enum { NPOINTS = 1000000, RUNS = 5 };

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

static double classify_best(const geo_inside *ix, const double (*pts)[3],
                            size_t n, par_pool *pool, int8_t *out)
{
    geo_ctx ctx = {.seed = 1, .parallel_for = pool ? par_for : NULL,
                   .pf_user = pool};
    double best = 1e300;
    for (int r = 0; r < RUNS; r++) {
        double t0 = now_ms();
        if (geo_inside_classify(ix, pts, n, GEO_INSIDE_RAY, out, &ctx, NULL)) {
            fprintf(stderr, "bench_inside: classification failed\n");
            exit(1);
        }
        double t = now_ms() - t0;
        if (t < best)
            best = t;
    }
    return best;
}

int main(void)
{
    geo_err err;
    const char *path = tu_model_path("brilliant.scan-k400.json");
    geo_poly *p = proto_model_read_file(path, PROTO_FMT_UNKNOWN, NULL, &err);
    if (!p) {
        fprintf(stderr, "bench_inside: %s\n", err.msg);
        return 1;
    }
    double t0 = now_ms();
    geo_inside *ix = geo_inside_new(p, &err);
    double prep = now_ms() - t0;
    if (!ix) {
        fprintf(stderr, "bench_inside: %s\n", err.msg);
        return 1;
    }
    const geo_bbox *b = geo_inside_bbox(ix);
    double(*pts)[3] = malloc(NPOINTS * sizeof *pts);
    int8_t *one = malloc(NPOINTS), *two = malloc(NPOINTS);
    if (!pts || !one || !two)
        return 1;
    uint64_t rng = 2025;
    for (size_t i = 0; i < NPOINTS; i++)
        for (int k = 0; k < 3; k++)
            pts[i][k] = b->lo[k] + (b->hi[k] - b->lo[k]) * geo_rand_unit(&rng);
    const double(*cpts)[3] = (const double(*)[3])pts;
    double t1 = classify_best(ix, cpts, NPOINTS, NULL, one);
    par_pool *pool = par_pool_new(2);
    double t2 = classify_best(ix, cpts, NPOINTS, pool, two);
    par_pool_free(pool);
    if (memcmp(one, two, NPOINTS) != 0) {
        fprintf(stderr, "bench_inside: results differ between 1 and 2 threads\n");
        return 1;
    }
    size_t in = 0;
    for (size_t i = 0; i < NPOINTS; i++)
        in += one[i] == GEO_LOC_INSIDE;

    /* the per-point alternatives on a sample */
    enum { SAMPLE = 20000, WSAMPLE = 2000 };
    uint64_t r2 = 9;
    t0 = now_ms();
    for (size_t i = 0; i < SAMPLE; i++)
        if (geo_inside_ray(ix, pts[i], NULL, &r2, NULL) != one[i]) {
            fprintf(stderr, "bench_inside: ray test disagrees at %zu\n", i);
            return 1;
        }
    double tray = (now_ms() - t0) / SAMPLE * 1e3;
    t0 = now_ms();
    for (size_t i = 0; i < WSAMPLE; i++)
        if (geo_inside_winding(ix, pts[i]) != one[i]) {
            fprintf(stderr, "bench_inside: winding test disagrees at %zu\n", i);
            return 1;
        }
    double twn = (now_ms() - t0) / WSAMPLE * 1e3;

    printf("inside_model: brilliant.scan-k400 (%u facets, %u vertices)\n",
           p->nfacets, p->nverts);
    printf("inside_prepare_ms: %.2f ms\n", prep);
    printf("inside_1M_points_ms_1thread: %.1f ms\n", t1);
    printf("inside_1M_points_ms_2threads: %.1f ms\n", t2);
    printf("inside_1M_points_ms: %.1f ms\n", t1 < t2 ? t1 : t2);
    printf("inside_fraction_inside: %.4f\n", (double)in / NPOINTS);
    printf("inside_random_ray_us_per_point: %.2f us\n", tray);
    printf("inside_winding_us_per_point: %.2f us\n", twn);
    free(pts);
    free(one);
    free(two);
    geo_inside_free(ix);
    geo_poly_free(p);
    return 0;
}
