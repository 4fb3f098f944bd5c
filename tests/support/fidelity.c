/* fidelity.c — facet-by-facet recovery of a true stone (fidelity.h). */
#include "fidelity.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stone_sim.h"
#include "vec.h"

typedef struct pair {
    double angle;
    uint32_t t, c;
} pair;

static int cmp_pair(const void *a, const void *b)
{
    const pair *x = a, *y = b;
    if (x->angle != y->angle)
        return x->angle < y->angle ? -1 : 1;
    if (x->t != y->t)
        return x->t < y->t ? -1 : 1;
    return (x->c > y->c) - (x->c < y->c);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Area centroid of facet f (fan triangles). */
static void area_centroid(const geo_poly *p, uint32_t f, double ret[3])
{
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *v = geo_poly_facet(p, f);
    double a = 0, s[3] = {0, 0, 0};
    for (uint32_t i = 1; i + 1 < n; i++) {
        double u[3], w[3], c[3];
        geo_vsub(p->verts[v[i]], p->verts[v[0]], u);
        geo_vsub(p->verts[v[i + 1]], p->verts[v[0]], w);
        geo_vcross(u, w, c);
        double ar = 0.5 * geo_vlen(c);
        for (int k = 0; k < 3; k++)
            s[k] += ar * (p->verts[v[0]][k] + p->verts[v[i]][k] +
                          p->verts[v[i + 1]][k]) / 3;
        a += ar;
    }
    if (a > 0)
        geo_vscale(s, 1 / a, ret);
    else
        geo_poly_facet_center(p, f, ret);
}

static double angle_deg(const double a[3], const double b[3])
{
    double c[3];
    geo_vcross(a, b, c);
    return atan2(geo_vlen(c), geo_vdot(a, b)) * 180 / M_PI;
}

int sim_fidelity_measure(const geo_poly *truth, const geo_poly *corrected,
                         double tol_deg, double tol_mm, sim_fidelity *ret)
{
    memset(ret, 0, sizeof *ret);
    uint32_t nt = truth->nfacets, nc = corrected->nfacets;
    size_t cap = 64;
    pair *pr = malloc(cap * sizeof *pr);
    double *err = malloc(((size_t)nt + 1) * sizeof *err);
    uint8_t *tused = calloc((size_t)nt + 1, 1), *cused = calloc((size_t)nc + 1, 1);
    if (!pr || !err || !tused || !cused) {
        free(pr), free(err), free(tused), free(cused);
        return -ENOMEM;
    }
    size_t np = 0;
    ret->truth = nt;
    for (uint32_t t = 0; t < nt; t++) {
        double x[3];
        area_centroid(truth, t, x);
        double best = INFINITY;
        err[t] = 180;
        for (uint32_t c = 0; c < nc; c++) {
            double d = sqrt(sim_facet_dist2(corrected, c, x));
            double a = angle_deg(truth->planes[t], corrected->planes[c]);
            if (d < best) {
                best = d;
                err[t] = a;
            }
            if (a > tol_deg || d > tol_mm)
                continue;
            if (np == cap) {
                cap *= 2;
                pair *q = realloc(pr, cap * sizeof *pr);
                if (!q) {
                    free(pr), free(err), free(tused), free(cused);
                    return -ENOMEM;
                }
                pr = q;
            }
            pr[np++] = (pair){a, t, c};
        }
        if (err[t] > ret->angle_max) {
            ret->angle_max = err[t];
            ret->worst_facet = t;
        }
    }
    qsort(pr, np, sizeof *pr, cmp_pair);
    for (size_t i = 0; i < np; i++) {
        if (tused[pr[i].t] || cused[pr[i].c])
            continue;
        tused[pr[i].t] = cused[pr[i].c] = 1;
        ret->recovered++;
    }
    double area = geo_poly_area(corrected);
    for (uint32_t c = 0; c < nc; c++)
        ret->spurious += !cused[c] && geo_poly_facet_area(corrected, c) > 0.01 * area;
    qsort(err, nt, sizeof *err, cmp_double);
    if (nt) {
        ret->angle_median = err[nt / 2];
        ret->angle_p95 = err[(size_t)(0.95 * (nt - 1))];
    }
    free(pr), free(err), free(tused), free(cused);
    return 0;
}
