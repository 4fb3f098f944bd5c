/* least_norm.c — one Gauss–Newton step of the least-norm re-planarisation
 * (see least_norm.h for the system).
 *
 * Rows are the corners of the facets of four or more vertices, numbered in
 * corner order; row r couples with every row of its facet (the plane
 * unknowns they share) and with every row at its vertex when that vertex
 * is free (the offset they share). */
#include "least_norm.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "spchol.h"
#include "vec.h"

/* Plane unknowns cost this fraction of a vertex's displacement. */
#define PLANE_WEIGHT 1e-6
/* Tikhonov term, relative to the largest diagonal entry. */
#define RIDGE 1e-14

typedef struct sys {
    uint32_t nrows;
    int32_t *crow;     /* corner → row, −1 for a triangle's corner */
    uint32_t *rcorner; /* row → corner */
    uint32_t *rfacet;  /* row → facet */
    uint32_t *vstart;  /* vertex → its rows, CSR (nverts + 1) */
    uint32_t *vrows;
    double (*g)[3];    /* per row: t1·(x−m), t2·(x−m), 1 */
    double (*n)[3];    /* per row: its facet's normal */
    uint32_t *rp, *ci; /* M, compressed rows */
    double *mv;
    double (*b)[3];    /* right-hand side, then y (column 0) */
} sys;

static void sys_free(sys *s)
{
    free(s->crow);
    free(s->rcorner);
    free(s->rfacet);
    free(s->vstart);
    free(s->vrows);
    free(s->g);
    free(s->n);
    free(s->rp);
    free(s->ci);
    free(s->mv);
    free(s->b);
}

/* Rows, their vertex lists and the per-row coefficients at x. */
static int build_rows(sys *s, const geo_poly *p, const uint8_t *in,
                      const double (*planes)[4], const double (*x)[3])
{
    uint32_t nc = geo_poly_ncorners(p);
    s->crow = malloc(((size_t)nc + 1) * sizeof *s->crow);
    s->vstart = calloc((size_t)p->nverts + 1, sizeof *s->vstart);
    if (!s->crow || !s->vstart)
        return -ENOMEM;
    uint32_t nr = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        bool big = geo_poly_facet_size(p, f) > 3 && (!in || in[f]);
        for (uint32_t c = p->fstart[f]; c < p->fstart[f + 1]; c++)
            s->crow[c] = big ? (int32_t)nr++ : -1;
    }
    s->nrows = nr;
    size_t n1 = (size_t)nr + 1;
    s->rcorner = malloc(n1 * sizeof *s->rcorner);
    s->rfacet = malloc(n1 * sizeof *s->rfacet);
    s->vrows = malloc(n1 * sizeof *s->vrows);
    s->g = malloc(n1 * sizeof *s->g);
    s->n = malloc(n1 * sizeof *s->n);
    s->b = calloc(n1, sizeof *s->b);
    if (!s->rcorner || !s->rfacet || !s->vrows || !s->g || !s->n || !s->b)
        return -ENOMEM;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t c0 = p->fstart[f], c1 = p->fstart[f + 1];
        if (c1 - c0 <= 3 || (in && !in[f]))
            continue;
        double m[3] = {0, 0, 0}, t1[3], t2[3];
        for (uint32_t c = c0; c < c1; c++)
            geo_vadd(m, x[p->fidx[c]], m);
        geo_vscale(m, 1.0 / (c1 - c0), m);
        geo_vbasis(planes[f], t1, t2);
        for (uint32_t c = c0; c < c1; c++) {
            uint32_t r = (uint32_t)s->crow[c];
            double d[3];
            geo_vsub(x[p->fidx[c]], m, d);
            s->rcorner[r] = c;
            s->rfacet[r] = f;
            s->g[r][0] = geo_vdot(t1, d);
            s->g[r][1] = geo_vdot(t2, d);
            s->g[r][2] = 1;
            memcpy(s->n[r], planes[f], sizeof s->n[r]);
            s->vstart[p->fidx[c] + 1]++;
        }
    }
    for (uint32_t v = 0; v < p->nverts; v++)
        s->vstart[v + 1] += s->vstart[v];
    uint32_t *fill = malloc(((size_t)p->nverts + 1) * sizeof *fill);
    if (!fill)
        return -ENOMEM;
    memcpy(fill, s->vstart, (size_t)p->nverts * sizeof *fill);
    for (uint32_t r = 0; r < nr; r++)
        s->vrows[fill[p->fidx[s->rcorner[r]]]++] = r;
    free(fill);
    return 0;
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

/* v[0..k) ascending: a row's columns are a facet's corners and a
 * vertex's, mostly a dozen, where qsort's calls cost more than the sort;
 * qsort beyond SMALL_SORT. */
#define SMALL_SORT 32

static void sort_u32(uint32_t *v, uint32_t k)
{
    if (k > SMALL_SORT) {
        qsort(v, k, sizeof *v, cmp_u32);
        return;
    }
    for (uint32_t i = 1; i < k; i++) {
        uint32_t x = v[i], j = i;
        for (; j > 0 && v[j - 1] > x; j--)
            v[j] = v[j - 1];
        v[j] = x;
    }
}

/* M's pattern and values; wt and ws are the inverse weights of a turn and
 * a shift. Each row's columns are sorted and unique (a vertex twice in one
 * facet would otherwise repeat one). */
static int build_matrix(sys *s, const geo_poly *p, const uint8_t *fixed,
                        double wt, double ws)
{
    uint32_t nr = s->nrows;
    size_t ub = 0, longest = 0;
    for (uint32_t r = 0; r < nr; r++) {
        uint32_t f = s->rfacet[r], v = p->fidx[s->rcorner[r]];
        size_t k = geo_poly_facet_size(p, f) +
                   (fixed[v] ? 0 : s->vstart[v + 1] - s->vstart[v]);
        ub += k;
        if (k > longest)
            longest = k;
    }
    if (ub > UINT32_MAX)
        return -ERANGE;
    s->rp = malloc(((size_t)nr + 1) * sizeof *s->rp);
    s->ci = malloc((ub + 1) * sizeof *s->ci);
    s->mv = malloc((ub + 1) * sizeof *s->mv);
    uint32_t *col = malloc((longest + 1) * sizeof *col);
    if (!s->rp || !s->ci || !s->mv || !col) {
        free(col);
        return -ENOMEM;
    }
    double dmax = 0;
    uint32_t at = 0;
    s->rp[0] = 0;
    for (uint32_t r = 0; r < nr; r++) {
        uint32_t f = s->rfacet[r], v = p->fidx[s->rcorner[r]];
        uint32_t k = 0;
        for (uint32_t c = p->fstart[f]; c < p->fstart[f + 1]; c++)
            col[k++] = (uint32_t)s->crow[c];
        if (!fixed[v])
            for (uint32_t j = s->vstart[v]; j < s->vstart[v + 1]; j++)
                col[k++] = s->vrows[j];
        sort_u32(col, k);
        for (uint32_t i = 0; i < k; i++) {
            uint32_t q = col[i];
            if (i > 0 && q == col[i - 1])
                continue;
            double e = 0;
            if (s->rfacet[q] == f)
                e += (s->g[r][0] * s->g[q][0] + s->g[r][1] * s->g[q][1]) * wt +
                     s->g[r][2] * s->g[q][2] * ws;
            if (!fixed[v] && p->fidx[s->rcorner[q]] == v)
                e += geo_vdot(s->n[r], s->n[q]);
            s->ci[at] = q;
            s->mv[at++] = e;
            if (q == r && e > dmax)
                dmax = e;
        }
        s->rp[r + 1] = at;
    }
    free(col);
    double ridge = RIDGE * (dmax > 0 ? dmax : 1);
    for (uint32_t r = 0; r < nr; r++)
        for (uint32_t i = s->rp[r]; i < s->rp[r + 1]; i++)
            if (s->ci[i] == r) {
                s->mv[i] += ridge;
                break;
            }
    return 0;
}

int geo_least_norm_step(const geo_poly *p, const uint8_t *fixed,
                        const uint8_t *in, const double (*planes)[4],
                        double (*x)[3],
                        bool from_start, uint64_t max_nnz, const geo_ctx *ctx)
{
    sys s;
    memset(&s, 0, sizeof s);
    double size = geo_poly_size(p);
    if (!(size > 0))
        size = 1;
    double wt = 1.0 / (PLANE_WEIGHT * size * size), ws = 1.0 / PLANE_WEIGHT;
    int rc = build_rows(&s, p, in, planes, (const double(*)[3])x);
    if (rc == 0)
        rc = build_matrix(&s, p, fixed, wt, ws);
    if (rc < 0 || s.nrows == 0) {
        sys_free(&s);
        return rc;
    }
    for (uint32_t r = 0; r < s.nrows; r++) {
        uint32_t f = s.rfacet[r], v = p->fidx[s.rcorner[r]];
        double rhs = -geo_plane_eval(planes[f], x[v]);
        if (!fixed[v] && from_start) {
            double e[3];
            geo_vsub(x[v], p->verts[v], e);
            rhs += geo_vdot(s.n[r], e);
        }
        s.b[r][0] = rhs;
    }
    geo_spchol *fac = NULL;
    rc = geo_spchol_factor(s.nrows, s.rp, s.ci, s.mv, GEO_SPCHOL_MIN_DEGREE,
                           max_nnz, ctx, &fac);
    if (rc == 0)
        rc = geo_spchol_solve3(fac, s.b);
    geo_spchol_free(fac);
    if (rc == 0) {
        for (uint32_t v = 0; v < p->nverts; v++) {
            if (fixed[v] || s.vstart[v] == s.vstart[v + 1])
                continue;
            double u[3] = {0, 0, 0};
            for (uint32_t j = s.vstart[v]; j < s.vstart[v + 1]; j++)
                geo_vmadd(u, s.b[s.vrows[j]][0], s.n[s.vrows[j]], u);
            geo_vadd(from_start ? p->verts[v] : x[v], u, x[v]);
        }
    }
    sys_free(&s);
    return rc;
}
