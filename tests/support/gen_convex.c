/* gen_convex.c — random convex polyhedra as intersections of half-spaces:
 * every triple of planes is intersected, points inside all half-spaces are
 * the vertices, and each plane's vertices sorted by angle are its facet.
 * Also convex clipping (gc_clip: Sutherland–Hodgman per facet, one new
 * vertex per crossed edge shared by both facets on it, the cap ordered by
 * angle around its centroid; sides decided exactly, so a vertex on the
 * plane is kept and reused by the cap). */
#include "gen_convex.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "plane.h"
#include "predicates.h"
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
