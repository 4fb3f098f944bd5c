/* bench_fill.c — hole filling and stitching times (lib/mesh/hole_fill.h,
 * lib/mesh/fill.h, lib/mesh/stitch.h). Targets: Liepa's triangulation of a
 * 200-vertex planar and a 200-vertex curved loop under 50 ms each;
 * refinement + fairing of a 1,000-vertex hole under 1 s. Also: the
 * checked fill of a 500-vertex hole in a sphere, and stitching two
 * halves of a sphere. Best of several runs. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "edgemap.h"
#include "fill.h"
#include "gen_sphere.h"
#include "hole_fill.h"
#include "stitch.h"
#include "vec.h"

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

/* A cone (apex below) whose open ring of n points is flat or waves. */
static geo_poly *open_cone(uint32_t n, double wave)
{
    geo_poly *p = geo_poly_new();
    double apex[3] = {0, 0, -1};
    geo_poly_add_vertex(p, apex);
    for (uint32_t i = 0; i < n; i++) {
        double a = 2 * M_PI * i / n;
        double v[3] = {cos(a), sin(a), wave * cos(3 * a)};
        geo_poly_add_vertex(p, v);
    }
    for (uint32_t i = 0; i < n; i++) {
        uint32_t t[3] = {0, 1 + (i + 1) % n, 1 + i};
        geo_poly_add_facet(p, t, 3);
    }
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    return p;
}

/* A sphere with the facets above z = zcut removed. */
static geo_poly *holed_sphere(uint32_t n, double zcut)
{
    geo_poly *p = gs_sphere(n, 1.0);
    bool *keep = malloc(p->nfacets * sizeof *keep);
    for (uint32_t f = 0; f < p->nfacets; f++) {
        double c[3];
        geo_poly_facet_center(p, f, c);
        keep[f] = c[2] <= zcut;
    }
    geo_poly_compact(p, keep, NULL, NULL);
    free(keep);
    return p;
}

static geo_poly *band_part(const geo_poly *s, double lo, double hi)
{
    geo_poly *p = geo_poly_copy(s);
    bool *keep = malloc(p->nfacets * sizeof *keep);
    for (uint32_t f = 0; f < p->nfacets; f++) {
        double c[3];
        geo_poly_facet_center(p, f, c);
        keep[f] = c[2] > lo && c[2] < hi;
    }
    geo_poly_compact(p, keep, NULL, NULL);
    free(keep);
    return p;
}

/* Quality of the patch of a filled unit sphere (p had nv0 vertices and
 * nf0 facets before): mean patch edge over mean mesh edge at the loop,
 * largest dihedral angle at the loop and inside the patch (degrees),
 * largest and mean distance of the added vertices from the sphere. */
static void sphere_patch_quality(const geo_poly *p, uint32_t nv0, uint32_t nf0,
                                 double ret[5])
{
    geo_edgemap he;
    geo_edgemap_init(&he, 3 * (size_t)p->nfacets);
    for (uint32_t f = 0; f < p->nfacets; f++) {
        const uint32_t *fv = geo_poly_facet(p, f);
        for (int i = 0; i < 3; i++)
            geo_edgemap_put(&he, geo_edge_key(fv[i], fv[(i + 1) % 3]), f);
    }
    uint8_t *on_loop = calloc(nv0 + 1, 1);
    double border = 0, inner = 0, in_sum = 0, out_sum = 0;
    uint64_t in_n = 0, out_n = 0;
    for (uint32_t f = nf0; f < p->nfacets; f++) {
        const uint32_t *fv = geo_poly_facet(p, f);
        double n1[3];
        geo_poly_facet_area_vector(p, f, n1);
        for (int i = 0; i < 3; i++) {
            uint32_t a = fv[i], b = fv[(i + 1) % 3];
            uint32_t g = geo_edgemap_get(&he, geo_edge_key(b, a));
            if (a < nv0)
                on_loop[a] = 1;
            if (g == UINT32_MAX)
                continue;
            double n2[3], x[3];
            geo_poly_facet_area_vector(p, g, n2);
            geo_vcross(n1, n2, x);
            double ang = atan2(geo_vlen(x), geo_vdot(n1, n2)) * 180 / M_PI;
            if (g < nf0) {
                border = fmax(border, ang);
            } else {
                inner = fmax(inner, ang);
                if (a < b) {
                    in_sum += geo_vdist(p->verts[a], p->verts[b]);
                    in_n++;
                }
            }
        }
    }
    for (uint32_t f = 0; f < nf0; f++) {
        const uint32_t *fv = geo_poly_facet(p, f);
        for (int i = 0; i < 3; i++)
            if (on_loop[fv[i]] || on_loop[fv[(i + 1) % 3]]) {
                out_sum += geo_vdist(p->verts[fv[i]], p->verts[fv[(i + 1) % 3]]);
                out_n++;
            }
    }
    double dmax = 0, dsum = 0;
    for (uint32_t v = nv0; v < p->nverts; v++) {
        double d = fabs(geo_vlen(p->verts[v]) - 1);
        dmax = fmax(dmax, d);
        dsum += d;
    }
    ret[0] = (in_sum / (double)in_n) / (out_sum / (double)out_n);
    ret[1] = border;
    ret[2] = inner;
    ret[3] = dmax;
    ret[4] = p->nverts > nv0 ? dsum / (p->nverts - nv0) : 0;
    free(on_loop);
    geo_edgemap_destroy(&he);
}

/* Best time of geo_fill_loops on copies of p; *nv gets the vertices
 * added; quality, when not NULL, sphere_patch_quality of the last run. */
static double time_fill(const geo_poly *p, const geo_fill_opts *o, int runs,
                        uint32_t *nv, uint32_t *loop, double *quality)
{
    double best = INFINITY;
    for (int r = 0; r < runs; r++) {
        geo_poly *q = geo_poly_copy(p);
        geo_fill_stats st;
        geo_err err;
        double t0 = now_ms();
        if (geo_fill_loops(q, o, NULL, &st, &err) < 0 || st.nfilled != 1) {
            fprintf(stderr, "fill failed: %s\n", err.msg);
            exit(1);
        }
        double t = now_ms() - t0;
        best = t < best ? t : best;
        *nv = st.nverts_added;
        *loop = st.holes[0].nverts;
        if (quality && r == runs - 1)
            sphere_patch_quality(q, p->nverts, p->nfacets, quality);
        geo_fill_stats_clear(&st);
        geo_poly_free(q);
    }
    return best;
}

int main(void)
{
    geo_fill_opts bare;
    geo_fill_opts_default(&bare);
    bare.refine = false;
    bare.fair = GEO_FAIR_NONE;
    bare.max_dp_vertices = 256; /* the whole O(n³) search, no bridge */
    uint32_t nv, loop;
    for (int curved = 0; curved < 2; curved++) {
        geo_poly *c = open_cone(200, curved ? 0.3 : 0.0);
        for (int w = 0; w < 3; w++) {
            static const char *const names[3] = {"area", "edges", "angle"};
            bare.weight = (enum geo_fill_weight)w;
            double t = time_fill(c, &bare, 5, &nv, &loop, NULL);
            printf("liepa_%s_200_%s: %.2f ms\n", curved ? "curved" : "planar",
                   names[w], t);
        }
        geo_poly_free(c);
    }

    /* a 1,000-vertex hole: the bare triangulation, then with refinement
     * and fairing; the difference is what refinement + fairing cost */
    geo_poly *s = holed_sphere(192, 0.5);
    geo_fill_opts full;
    geo_fill_opts_default(&full);
    double t_bare = time_fill(s, (geo_fill_opts_default(&bare), bare.refine =
                                  false, bare.fair = GEO_FAIR_NONE, &bare),
                              3, &nv, &loop, NULL);
    double qual[5];
    double t_full = time_fill(s, &full, 3, &nv, &loop, qual);
    printf("hole_loop_vertices: %u\n", loop);
    printf("hole_liepa_only: %.1f ms\n", t_bare);
    printf("hole_refine_fair_vertices_added: %u\n", nv);
    printf("hole_refine_and_fair: %.1f ms\n", t_full - t_bare);
    printf("hole_total: %.1f ms\n", t_full);
    printf("hole_edge_ratio: %.2f\n", qual[0]);
    printf("hole_max_dihedral_at_loop: %.1f deg\n", qual[1]);
    printf("hole_max_dihedral_inside: %.1f deg\n", qual[2]);
    printf("hole_sphere_distance_max: %.3f\n", qual[3]);
    printf("hole_sphere_distance_mean: %.3f\n", qual[4]);
    geo_poly_free(s);

    /* the checked fill of a 500-vertex hole (geo_fill) */
    s = holed_sphere(88, 0.5);
    double best = INFINITY;
    geo_mesh_fill_report rep = {0};
    for (int r = 0; r < 3; r++) {
        geo_poly *q = geo_poly_copy(s);
        geo_mesh_fill_report_clear(&rep);
        double t0 = now_ms();
        if (geo_fill(q, NULL, NULL, &rep, NULL) < 0)
            exit(1);
        double t = now_ms() - t0;
        best = t < best ? t : best;
        geo_poly_free(q);
    }
    printf("checked_fill_500_loop_vertices: %u\n", rep.holes[0].nverts);
    printf("checked_fill_500_status: %s\n",
           geo_hole_status_name(rep.holes[0].status));
    printf("checked_fill_500_edge_ratio: %.2f\n", rep.holes[0].edge_ratio);
    printf("checked_fill_500: %.1f ms\n", best);
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(s);

    /* stitching two halves of a sphere across a band */
    s = gs_sphere(64, 1.0);
    geo_poly *top = band_part(s, 0.2, 9), *bot = band_part(s, -9, -0.2);
    best = INFINITY;
    geo_stitch_report sr = {0};
    for (int r = 0; r < 3; r++) {
        geo_poly *out = geo_poly_new();
        geo_stitch_report_clear(&sr);
        double t0 = now_ms();
        if (geo_stitch(top, bot, NULL, NULL, out, &sr, NULL) < 0)
            exit(1);
        double t = now_ms() - t0;
        best = t < best ? t : best;
        geo_poly_free(out);
    }
    printf("stitch_sphere_halves_loop_vertices: %u\n", sr.nloop1);
    printf("stitch_sphere_halves_band_facets: %u\n", sr.band_facets);
    printf("stitch_sphere_halves: %.1f ms\n", best);
    geo_stitch_report_clear(&sr);
    geo_poly_free(top), geo_poly_free(bot), geo_poly_free(s);
    return 0;
}
