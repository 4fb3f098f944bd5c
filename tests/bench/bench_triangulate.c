/* bench_triangulate.c — the F-rep triangulation at Vyatkin's levels
 * (Q_LEV = 9, B_LEV = 10): the 83-perturbation blob of fig. 14 (triangles,
 * vertices, deviations, time per stage, 1 and 2 threads, best of 3), the
 * other test objects, the cut gem at Q_LEV 7, 8 and 9 and gems of random
 * proportions and orientations at Q_LEV 8 (self-intersections, normal
 * deviation away from edges, distance of the true edges from the mesh).
 * Prints "name: value unit" lines. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "frep_json.h"
#include "gen_frep.h"
#include "parallel.h"
#include "triangulate.h"

static geo_frep *load(const char *name)
{
    char path[512];
    snprintf(path, sizeof path, "tests/data/frep/%s.json", name);
    geo_err err = {{0}};
    geo_frep *f = proto_frep_read_file(path, NULL, &err);
    if (!f)
        fprintf(stderr, "%s\n", err.msg);
    return f;
}

/* Best of `runs` runs (by total time) with the given thread count at
 * Q_LEV q, B_LEV q + 1. */
static geo_poly *best_run_at(const geo_frep *f, int threads, int runs,
                             uint32_t q, geo_tri_report *best)
{
    par_pool *pool = par_pool_new(threads);
    geo_ctx ctx = {.parallel_for = par_for, .pf_user = pool};
    geo_tri_opts o;
    geo_tri_opts_default(&o);
    o.quad_levels = q;
    o.binary_levels = q + 1;
    geo_poly *keep = NULL;
    for (int r = 0; r < runs; r++) {
        geo_tri_report rep;
        geo_poly *m = NULL;
        geo_err err = {{0}};
        if (geo_triangulate(f, &o, &ctx, &m, &rep, &err) < 0) {
            fprintf(stderr, "triangulate: %s\n", err.msg);
            break;
        }
        if (!keep || rep.t_total < best->t_total) {
            if (keep)
                geo_tri_report_clear(best);
            geo_poly_free(keep);
            keep = m;
            *best = rep;
        } else {
            geo_tri_report_clear(&rep);
            geo_poly_free(m);
        }
    }
    par_pool_free(pool);
    return keep;
}

/* Best of three at Vyatkin's levels. */
static geo_poly *best_run(const geo_frep *f, int threads, geo_tri_report *best)
{
    return best_run_at(f, threads, 3, 9, best);
}

/* The distances of the gem's true edges from mesh m (see gen_frep.h). */
static void print_edges(const char *p, json_t *j, const geo_poly *m,
                        double v)
{
    double *planes, *segs, d[5];
    int np = gf_halfspaces(j, &planes);
    int ns = gf_polytope_edges((const double(*)[4])planes, np, &segs);
    if (np <= 0 || ns <= 0)
        return;
    gf_edge_distances(m, segs, ns, 0.25 * v, 1.5 * v, d);
    printf("%s_true_edges: %d\n", p, ns);
    printf("%s_edge_distance_max: %.3g units (%.2f voxel)\n", p, d[0],
           d[0] / v);
    printf("%s_edge_distance_away_from_corners_median: %.3g units\n", p,
           d[1]);
    printf("%s_edge_distance_away_from_corners_p90: %.3g units (%.2f voxel)\n",
           p, d[2], d[2] / v);
    printf("%s_edge_distance_away_from_corners_p99: %.3g units (%.2f voxel)\n",
           p, d[3], d[3] / v);
    printf("%s_edge_distance_away_from_corners_max: %.3g units (%.2f voxel)\n",
           p, d[4], d[4] / v);
    free(planes), free(segs);
}

static void print_report(const char *p, int threads, const geo_tri_report *r)
{
    const geo_frep_metrics *q = &r->quality;
    printf("%s_threads: %d\n", p, threads);
    printf("%s_triangles: %u\n", p, q->nfacets);
    printf("%s_vertices: %u\n", p, q->nverts);
    printf("%s_holes_filled: %u of %u\n", p, r->fill.nfilled, r->fill.nholes);
    printf("%s_vertex_deviation_max: %.3g units\n", p, q->dev_max);
    printf("%s_vertex_deviation_mean: %.3g units\n", p, q->dev_mean);
    printf("%s_vertex_deviation_rms: %.3g units\n", p, q->dev_rms);
    printf("%s_voxel: %.4g x %.4g x %.4g units\n", p, r->voxel[0], r->voxel[1],
           r->voxel[2]);
    printf("%s_normal_deviation_max: %.3f deg\n", p, q->ndev_max);
    printf("%s_normal_deviation_mean: %.3f deg\n", p, q->ndev_mean);
    printf("%s_normal_deviation_p95: %.3f deg\n", p, q->ndev_p95);
    printf("%s_normal_deviation_away_from_creases_max: %.3f deg\n", p,
           q->sdev_max);
    printf("%s_normal_deviation_away_from_creases_p95: %.3f deg\n", p,
           q->sdev_p95);
    printf("%s_edge_length_cv: %.3f\n", p, q->edge_cv);
    printf("%s_triangle_area_cv: %.3f\n", p, q->area_cv);
    printf("%s_nonmanifold_edges: %u\n", p, q->nonmanifold_edges);
    printf("%s_boundary_edges: %u\n", p, q->boundary_edges);
    printf("%s_self_intersections: %lld\n", p,
           (long long)r->self_intersections);
    printf("%s_time_sample: %.3f s\n", p, r->t_sample);
    printf("%s_time_connect: %.3f s\n", p, r->t_connect);
    printf("%s_time_fill: %.3f s\n", p, r->t_fill);
    printf("%s_time_sharpen: %.3f s\n", p, r->t_sharpen);
    printf("%s_time_metrics: %.3f s\n", p, r->t_metrics);
    printf("%s_time_total: %.3f s\n", p, r->t_total);
}

int main(void)
{
    geo_frep *blob = load("blob83");
    geo_frep *gem = load("gem");
    if (!blob || !gem)
        return 1;
    printf("paper_fig14_triangles: 136306\n");
    printf("paper_fig14_vertices: 68418\n");
    for (int threads = 1; threads <= 2; threads++) {
        geo_tri_report rep;
        geo_poly *m = best_run(blob, threads, &rep);
        if (!m)
            return 1;
        print_report("blob83_q9_b10", threads, &rep);
        geo_tri_report_clear(&rep);
        geo_poly_free(m);
    }
    /* every test object at Vyatkin's levels, 2 threads */
    static const char *const others[] = {"sphere", "ellipsoid", "torus",
                                         "two-spheres"};
    for (size_t i = 0; i < sizeof others / sizeof others[0]; i++) {
        geo_frep *f = load(others[i]);
        geo_tri_report rep;
        geo_poly *m = f ? best_run_at(f, 2, 1, 9, &rep) : NULL;
        if (!m)
            return 1;
        char name[64];
        snprintf(name, sizeof name, "%s_q9_b10", others[i]);
        print_report(name, 2, &rep);
        geo_tri_report_clear(&rep);
        geo_poly_free(m);
        geo_frep_free(f);
    }
    json_t *j = gf_gem();
    for (uint32_t q = 7; q <= 9; q++) {
        geo_tri_report rep;
        geo_poly *m = best_run_at(gem, 2, q == 9 ? 3 : 1, q, &rep);
        if (!m)
            return 1;
        char name[64];
        snprintf(name, sizeof name, "gem_q%u_b%u", q, q + 1);
        print_report(name, 2, &rep);
        print_edges(name, j, m, rep.voxel[0]);
        geo_tri_report_clear(&rep);
        geo_poly_free(m);
    }
    json_decref(j);
    /* gems of random proportions and orientations at Q_LEV 8 */
    for (uint64_t seed = 1; seed <= 4; seed++) {
        json_t *rj = gf_gem_random(seed);
        geo_err err = {{0}};
        geo_frep *f = proto_frep_from_json(rj, NULL, NULL, &err);
        geo_tri_report rep;
        geo_poly *m = f ? best_run_at(f, 2, 1, 8, &rep) : NULL;
        if (!m)
            return 1;
        char name[64];
        snprintf(name, sizeof name, "gem_random%llu_q8_b9",
                 (unsigned long long)seed);
        printf("%s_triangles: %u\n", name, rep.quality.nfacets);
        printf("%s_self_intersections: %lld\n", name,
               (long long)rep.self_intersections);
        printf("%s_normal_deviation_away_from_creases_max: %.3f deg\n", name,
               rep.quality.sdev_max);
        print_edges(name, rj, m, rep.voxel[0]);
        geo_tri_report_clear(&rep);
        geo_poly_free(m);
        geo_frep_free(f);
        json_decref(rj);
    }
    geo_frep_free(blob);
    geo_frep_free(gem);
    return 0;
}
