/* gen_convex.c — random convex polyhedra as intersections of half-spaces:
 * every triple of planes is intersected, points inside all half-spaces are
 * the vertices, and each plane's vertices sorted by angle are its facet. */
#include "gen_convex.h"

#include <math.h>
#include <stdlib.h>

#include "plane.h"
#include "vec.h"

typedef struct gvert {
    double x[3];
    unsigned pl[3];
} gvert;

typedef struct angled {
    double angle;
    uint32_t v;
} angled;

static int by_angle(const void *a, const void *b)
{
    double x = ((const angled *)a)->angle, y = ((const angled *)b)->angle;
    return (x > y) - (x < y);
}

static void random_unit(uint64_t *rng, double n[3])
{
    for (;;) {
        for (int k = 0; k < 3; k++)
            n[k] = 2.0 * geo_rand_unit(rng) - 1.0;
        double l = geo_vlen(n);
        if (l > 0.1 && l <= 1.0) {
            geo_vscale(n, 1.0 / l, n);
            return;
        }
    }
}

/* One draw; NULL when the sample is degenerate (*ret_oom tells OOM). */
static geo_poly *draw(uint64_t *rng, unsigned nplanes, const double c[3],
                      double r, int *ret_oom)
{
    unsigned m = 6 + nplanes;
    double(*pl)[4] = malloc(m * sizeof *pl);
    size_t cap = 64, nv = 0;
    gvert *gv = malloc(cap * sizeof *gv);
    geo_poly *out = NULL;
    uint32_t *fstart = NULL, *fidx = NULL;
    double *planes = NULL, *xyz = NULL;
    angled *ring = NULL;
    if (!pl || !gv)
        goto oom;
    for (unsigned i = 0; i < m; i++) {
        double n[3] = {0, 0, 0}, dist;
        if (i < 6) {
            n[i / 2] = (i % 2) ? 1.0 : -1.0;
            dist = 1.5 * r;
        } else {
            random_unit(rng, n);
            dist = r * (0.8 + 0.4 * geo_rand_unit(rng));
        }
        for (int k = 0; k < 3; k++)
            pl[i][k] = n[k];
        pl[i][3] = -(geo_vdot(n, c) + dist);
    }
    const double tol = 1e-9 * r;
    for (unsigned i = 0; i < m; i++)
        for (unsigned j = i + 1; j < m; j++)
            for (unsigned k = j + 1; k < m; k++) {
                double x[3];
                if (!geo_plane_intersect3(pl[i], pl[j], pl[k], x))
                    continue;
                bool inside = true;
                for (unsigned l = 0; l < m && inside; l++) {
                    if (l == i || l == j || l == k)
                        continue;
                    double s = geo_plane_eval(pl[l], x);
                    if (fabs(s) <= tol) /* a fourth plane through x */
                        goto degenerate;
                    inside = s < 0;
                }
                if (!inside)
                    continue;
                for (size_t t = 0; t < nv; t++)
                    if (geo_vdist(gv[t].x, x) < 1e-6 * r)
                        goto degenerate;
                if (nv == cap) {
                    gvert *g = realloc(gv, 2 * cap * sizeof *gv);
                    if (!g)
                        goto oom;
                    gv = g, cap *= 2;
                }
                gv[nv] = (gvert){{x[0], x[1], x[2]}, {i, j, k}};
                nv++;
            }
    fstart = malloc((m + 1) * sizeof *fstart);
    fidx = malloc((3 * nv + 1) * sizeof *fidx);
    planes = malloc(4 * (m + 1) * sizeof *planes);
    xyz = malloc((3 * nv + 1) * sizeof *xyz);
    ring = malloc((nv + 1) * sizeof *ring);
    if (!fstart || !fidx || !planes || !xyz || !ring)
        goto oom;
    for (size_t t = 0; t < nv; t++)
        for (int k = 0; k < 3; k++)
            xyz[3 * t + k] = gv[t].x[k];
    uint32_t nf = 0, nidx = 0;
    fstart[0] = 0;
    for (unsigned i = 0; i < m; i++) {
        size_t cnt = 0;
        double cen[3] = {0, 0, 0};
        for (size_t t = 0; t < nv; t++)
            if (gv[t].pl[0] == i || gv[t].pl[1] == i || gv[t].pl[2] == i) {
                ring[cnt++].v = (uint32_t)t;
                geo_vadd(cen, gv[t].x, cen);
            }
        if (cnt == 0)
            continue; /* a redundant half-space */
        if (cnt < 3)
            goto degenerate;
        geo_vscale(cen, 1.0 / (double)cnt, cen);
        /* basis u, w of the plane with u × w = n: angles grow
         * counter-clockwise seen from outside */
        double u[3], w[3], any[3] = {1, 0, 0};
        if (fabs(pl[i][0]) > 0.9)
            any[0] = 0, any[1] = 1;
        geo_vcross(pl[i], any, u);
        geo_vnormalize(u);
        geo_vcross(pl[i], u, w);
        for (size_t t = 0; t < cnt; t++) {
            double d[3];
            geo_vsub(gv[ring[t].v].x, cen, d);
            ring[t].angle = atan2(geo_vdot(d, w), geo_vdot(d, u));
        }
        qsort(ring, cnt, sizeof *ring, by_angle);
        for (size_t t = 0; t < cnt; t++)
            fidx[nidx++] = ring[t].v;
        for (int k = 0; k < 4; k++)
            planes[4 * nf + k] = pl[i][k];
        fstart[++nf] = nidx;
    }
    out = geo_poly_from_arrays((uint32_t)nv, xyz, nf, fstart, fidx, planes,
                               NULL);
    if (!out)
        goto oom;
    goto done;
degenerate:
    *ret_oom = 0;
    goto done;
oom:
    *ret_oom = 1;
done:
    free(pl);
    free(gv);
    free(fstart);
    free(fidx);
    free(planes);
    free(xyz);
    free(ring);
    return out;
}

geo_poly *gen_convex_polyhedron(uint64_t seed, unsigned nplanes,
                                const double center[3], double radius)
{
    uint64_t rng = seed;
    for (int attempt = 0; attempt < 100; attempt++) {
        int oom = 0;
        geo_poly *p = draw(&rng, nplanes, center, radius, &oom);
        if (p || oom)
            return p;
    }
    return NULL;
}
