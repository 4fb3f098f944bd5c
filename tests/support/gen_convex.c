/* gen_convex.c — convex clipping (Sutherland–Hodgman per facet, one new
 * vertex per crossed edge shared by both facets on it, the cap ordered by
 * angle around its centroid). Sides are decided exactly, so a vertex on
 * the plane is kept and reused by the cap. */
#include "gen_convex.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "predicates.h"
#include "vec.h"

typedef struct cut_edge {
    uint32_t a, b, v; /* a < b: the edge; v: its new vertex */
} cut_edge;

typedef struct cap_pt {
    double ang;
    uint32_t v;
} cap_pt;

static int cmp_cap(const void *x, const void *y)
{
    const cap_pt *a = x, *b = y;
    return (a->ang > b->ang) - (a->ang < b->ang);
}

static int64_t edge_vertex(geo_poly *p, cut_edge **edges, uint32_t *ne,
                           uint32_t *cap, uint32_t a, uint32_t b,
                           const double plane[4])
{
    uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
    for (uint32_t i = 0; i < *ne; i++)
        if ((*edges)[i].a == lo && (*edges)[i].b == hi)
            return (*edges)[i].v;
    double dl = geo_plane_eval(plane, p->verts[lo]);
    double dh = geo_plane_eval(plane, p->verts[hi]);
    double t = dl / (dl - dh), x[3], d[3];
    geo_vsub(p->verts[hi], p->verts[lo], d);
    geo_vmadd(p->verts[lo], t, d, x);
    int64_t v = geo_poly_add_vertex(p, x);
    if (v < 0)
        return v;
    if (*ne == *cap) {
        uint32_t c = *cap ? 2 * *cap : 64;
        cut_edge *n = realloc(*edges, c * sizeof *n);
        if (!n)
            return -ENOMEM;
        *edges = n;
        *cap = c;
    }
    (*edges)[(*ne)++] = (cut_edge){lo, hi, (uint32_t)v};
    return v;
}

int gc_clip(geo_poly *p, const double plane[4])
{
    int rc = -ENOMEM;
    geo_poly *q = geo_poly_new();
    int8_t *side = malloc(p->nverts + 1);
    cut_edge *edges = NULL;
    uint32_t ne = 0, ecap = 0;
    uint32_t *buf = malloc((geo_poly_ncorners(p) + 1) * 2 * sizeof *buf);
    uint8_t *oncap = NULL;
    cap_pt *pts = NULL;
    if (!q || !side || !buf)
        goto out;
    bool any_out = false;
    for (uint32_t v = 0; v < p->nverts; v++) {
        side[v] = (int8_t)geo_plane_sign(plane, p->verts[v]);
        any_out |= side[v] > 0;
    }
    if (!any_out) {
        rc = 0;
        goto out;
    }
    /* q starts as p's vertices; new ones are appended */
    if (geo_poly_reserve(q, p->nverts, p->nfacets + 1,
                         geo_poly_ncorners(p)) < 0)
        goto out;
    for (uint32_t v = 0; v < p->nverts; v++)
        geo_poly_add_vertex(q, p->verts[v]);
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f), m = 0;
        const uint32_t *fv = geo_poly_facet(p, f);
        for (uint32_t i = 0; i < n; i++) {
            uint32_t a = fv[i], b = fv[(i + 1) % n];
            if (side[a] <= 0)
                buf[m++] = a;
            if ((side[a] < 0 && side[b] > 0) || (side[a] > 0 && side[b] < 0)) {
                int64_t v = edge_vertex(q, &edges, &ne, &ecap, a, b, plane);
                if (v < 0)
                    goto out;
                buf[m++] = (uint32_t)v;
            }
        }
        if (m < 3)
            continue;
        int64_t nf = geo_poly_add_facet(q, buf, m);
        if (nf < 0)
            goto out;
        memcpy(q->planes[nf], p->planes[f], sizeof q->planes[0]);
    }
    /* the cap: every kept vertex on the plane */
    oncap = calloc(q->nverts + 1, 1);
    pts = malloc((q->nverts + 1) * sizeof *pts);
    if (!oncap || !pts)
        goto out;
    for (uint32_t c = 0; c < geo_poly_ncorners(q); c++) {
        uint32_t v = q->fidx[c];
        if (v >= p->nverts || side[v] == 0)
            oncap[v] = 1;
    }
    uint32_t m = 0;
    double cen[3] = {0, 0, 0};
    for (uint32_t v = 0; v < q->nverts; v++)
        if (oncap[v]) {
            pts[m++].v = v;
            geo_vadd(cen, q->verts[v], cen);
        }
    if (m >= 3) {
        geo_vscale(cen, 1.0 / m, cen);
        double u[3], w[3], nrm[3] = {plane[0], plane[1], plane[2]};
        double ax[3] = {0, 0, 0};
        ax[fabs(nrm[0]) < 0.5 ? 0 : 1] = 1;
        geo_vcross(nrm, ax, u);
        geo_vnormalize(u);
        geo_vcross(nrm, u, w);
        for (uint32_t i = 0; i < m; i++) {
            double d[3];
            geo_vsub(q->verts[pts[i].v], cen, d);
            pts[i].ang = atan2(geo_vdot(d, w), geo_vdot(d, u));
        }
        qsort(pts, m, sizeof *pts, cmp_cap);
        for (uint32_t i = 0; i < m; i++)
            buf[i] = pts[i].v;
        int64_t nf = geo_poly_add_facet(q, buf, m);
        if (nf < 0)
            goto out;
        memcpy(q->planes[nf], plane, sizeof q->planes[0]);
    }
    if (geo_poly_compact(q, NULL, NULL, NULL) < 0 || geo_poly_assign(p, q) < 0)
        goto out;
    rc = 0;
out:
    geo_poly_free(q);
    free(side);
    free(edges);
    free(buf);
    free(oncap);
    free(pts);
    return rc;
}

geo_poly *gc_random_convex(uint64_t seed, uint32_t nplanes)
{
    const double lo[3] = {-2, -2, -2}, hi[3] = {2, 2, 2};
    double v[8][3];
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++)
            v[i][k] = (i >> k & 1) ? hi[k] : lo[k];
    static const uint32_t idx[] = {0, 2, 3, 1, 4, 5, 7, 6, 0, 1, 5, 4,
                                   2, 6, 7, 3, 0, 4, 6, 2, 1, 3, 7, 5};
    static const uint32_t start[] = {0, 4, 8, 12, 16, 20, 24};
    geo_poly *p = geo_poly_from_arrays(8, &v[0][0], 6, start, idx, NULL, NULL);
    uint64_t rng = seed * 0x9e3779b97f4a7c15ULL + 1;
    for (uint32_t i = 0; p && i < nplanes; i++) {
        double n[3];
        do {
            for (int k = 0; k < 3; k++)
                n[k] = 2 * geo_rand_unit(&rng) - 1;
        } while (geo_vdot(n, n) > 1 || geo_vdot(n, n) < 1e-6);
        geo_vnormalize(n);
        double plane[4] = {n[0], n[1], n[2], -1};
        if (gc_clip(p, plane) < 0)
            p = geo_poly_free(p);
    }
    return p;
}
