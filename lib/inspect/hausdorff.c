/* hausdorff.c — the Hausdorff distance estimate of hausdorff.h.
 * Invariant: the best distance found so far only shrinks, and a BVH node
 * is opened only when its box could hold something nearer. */
#include "hausdorff.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bvh.h"
#include "selfint.h"
#include "vec.h"

/* Facets of the target above this size are looked at as triangles. */
enum { FAN_MIN = 32 };

/* b with every convex facet of more than FAN_MIN vertices fanned into
 * triangles that keep its plane: they cover the polygon exactly, so the
 * distance to the surface is unchanged, but a query near such a facet
 * (a prism's 60,000-gon cap) costs O(log n) instead of O(n). *ret is NULL
 * when no facet needs it (then b is used as is). 0 or -ENOMEM. */
static int fan_large_facets(const geo_poly *b, geo_poly **ret)
{
    *ret = NULL;
    uint32_t nbig = 0;
    for (uint32_t f = 0; f < b->nfacets; f++)
        nbig += geo_poly_facet_size(b, f) > FAN_MIN;
    if (nbig == 0)
        return 0;
    geo_poly *q = geo_poly_new();
    if (!q || geo_poly_reserve(q, b->nverts, b->nfacets, 0) < 0) {
        geo_poly_free(q);
        return -ENOMEM;
    }
    memcpy(q->verts, b->verts, (size_t)b->nverts * sizeof *b->verts);
    q->nverts = b->nverts;
    for (uint32_t f = 0; f < b->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(b, f);
        const uint32_t *vs = geo_poly_facet(b, f);
        geo_facet_shape sh;
        if (n > FAN_MIN)
            geo_facet_shape_of(b, f, &sh);
        if (n <= FAN_MIN || !sh.convex) {
            int64_t g = geo_poly_add_facet(q, vs, n);
            if (g < 0)
                goto oom;
            memcpy(q->planes[g], b->planes[f], sizeof q->planes[g]);
            continue;
        }
        for (uint32_t i = 1; i + 1 < n; i++) {
            uint32_t t[3] = {vs[0], vs[i], vs[i + 1]};
            int64_t g = geo_poly_add_facet(q, t, 3);
            if (g < 0)
                goto oom;
            memcpy(q->planes[g], b->planes[f], sizeof q->planes[g]);
        }
    }
    *ret = q;
    return 0;
oom:
    geo_poly_free(q);
    return -ENOMEM;
}

static double seg_dist2(const double p[3], const double a[3], const double b[3])
{
    double ab[3], ap[3];
    geo_vsub(b, a, ab);
    geo_vsub(p, a, ap);
    double l2 = geo_vdot(ab, ab), t = l2 > 0 ? geo_vdot(ap, ab) / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double q[3], d[3];
    geo_vmadd(a, t, ab, q);
    geo_vsub(p, q, d);
    return geo_vdot(d, d);
}

/* Squared distance from p to facet f of g: to its plane when p projects
 * inside the polygon (winding number in the plane's dominant
 * projection), else to its nearest edge. The distance to the plane is a
 * lower bound, so a facet whose plane is already as far as bound is not
 * looked at further (the plane distance² is returned). */
static double facet_dist2(const geo_poly *g, uint32_t f, const double p[3],
                          double bound)
{
    uint32_t n = geo_poly_facet_size(g, f);
    const uint32_t *vs = geo_poly_facet(g, f);
    const double *pl = g->planes[f];
    int k = 0;
    for (int j = 1; j < 3; j++)
        if (fabs(pl[j]) > fabs(pl[k]))
            k = j;
    int u = (k + 1) % 3, w = (k + 2) % 3;
    double h = geo_plane_eval(pl, p), q[3];
    if (h * h >= bound)
        return h * h;
    geo_vmadd(p, -h, pl, q);
    int wn = 0;
    for (uint32_t i = 0; i < n; i++) {
        const double *a = g->verts[vs[i]], *b = g->verts[vs[(i + 1) % n]];
        double cr = (b[u] - a[u]) * (q[w] - a[w]) - (b[w] - a[w]) * (q[u] - a[u]);
        if (a[w] <= q[w]) {
            if (b[w] > q[w] && cr > 0)
                wn++;
        } else if (b[w] <= q[w] && cr < 0) {
            wn--;
        }
    }
    if (wn != 0)
        return h * h;
    double best = INFINITY;
    for (uint32_t i = 0; i < n; i++)
        best = fmin(best, seg_dist2(p, g->verts[vs[i]], g->verts[vs[(i + 1) % n]]));
    return best;
}

static double box_dist2(const geo_bbox *b, const double p[3])
{
    double s = 0;
    for (int k = 0; k < 3; k++) {
        double d = p[k] < b->lo[k] ? b->lo[k] - p[k]
                 : p[k] > b->hi[k] ? p[k] - b->hi[k] : 0;
        s += d * d;
    }
    return s;
}

/* Nearest facet distance², depth-first with the nearer child first;
 * *arg is the facet that gave *best. */
static void nearest(const geo_poly *g, const geo_bvh *h, uint32_t node,
                    const double p[3], double *best, uint32_t *arg)
{
    const geo_bvh_node *n = &h->nodes[node];
    if (box_dist2(&n->box, p) >= *best)
        return;
    if (n->count) {
        for (uint32_t i = n->child; i < n->child + n->count; i++)
            if (h->items[i] != *arg && box_dist2(&h->boxes[i], p) < *best) {
                double d = facet_dist2(g, h->items[i], p, *best);
                if (d < *best) {
                    *best = d;
                    *arg = h->items[i];
                }
            }
        return;
    }
    uint32_t c0 = n->child, c1 = n->child + 1;
    double d0 = box_dist2(&h->nodes[c0].box, p), d1 = box_dist2(&h->nodes[c1].box, p);
    if (d1 < d0) {
        uint32_t t = c0;
        c0 = c1;
        c1 = t;
    }
    nearest(g, h, c0, p, best, arg);
    nearest(g, h, c1, p, best, arg);
}

/* Distance² from p to b, the search started with the bound given by the
 * facet nearest to the previous sample (*hint): samples come in surface
 * order, so that bound is usually tight and prunes almost every box. */
static double dist2(const geo_poly *b, const geo_bvh *h, const double p[3],
                    uint32_t *hint)
{
    double best = INFINITY;
    if (*hint != UINT32_MAX)
        best = facet_dist2(b, *hint, p, INFINITY);
    nearest(b, h, 0, p, &best, hint);
    return best;
}

static int directed(const geo_poly *a, const geo_poly *b, const geo_ctx *ctx,
                    double *ret, geo_err *err)
{
    if (b->nfacets == 0)
        return geo_err_set(err, -EINVAL, "hausdorff: the second surface has "
                           "no facets");
    geo_poly *fanned;
    if (fan_large_facets(b, &fanned) < 0)
        return geo_err_set(err, -ENOMEM, "out of memory");
    if (fanned)
        b = fanned;
    geo_bvh *h = geo_bvh_build_facets(b, err);
    if (!h) {
        geo_poly_free(fanned);
        return -ENOMEM;
    }
    double worst = 0;
    uint32_t hint = UINT32_MAX;
    uint8_t *seen = calloc((size_t)a->nverts + 1, 1);
    if (!seen) {
        geo_bvh_free(h);
        geo_poly_free(fanned);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    int rc = 0;
    for (uint32_t f = 0; f < a->nfacets; f++) {
        /* a sample near a large non-convex facet costs O(its size) */
        if ((f & 255) == 255 && geo_ctx_canceled(ctx)) {
            rc = geo_err_set(err, -ECANCELED, "hausdorff: canceled");
            break;
        }
        uint32_t n = geo_poly_facet_size(a, f);
        const uint32_t *vs = geo_poly_facet(a, f);
        double c[3] = {0, 0, 0};
        for (uint32_t i = 0; i < n; i++) {
            double m[3];
            geo_vadd(c, a->verts[vs[i]], c);
            geo_vadd(a->verts[vs[i]], a->verts[vs[(i + 1) % n]], m);
            geo_vscale(m, 0.5, m);
            if (!seen[vs[i]]) {
                seen[vs[i]] = 1;
                worst = fmax(worst, dist2(b, h, a->verts[vs[i]], &hint));
            }
            worst = fmax(worst, dist2(b, h, m, &hint));
        }
        if (n) {
            geo_vscale(c, 1.0 / n, c);
            worst = fmax(worst, dist2(b, h, c, &hint));
        }
    }
    free(seen);
    geo_bvh_free(h);
    geo_poly_free(fanned);
    *ret = sqrt(worst);
    return rc;
}

int geo_hausdorff_directed(const geo_poly *a, const geo_poly *b, double *ret,
                           geo_err *err)
{
    return directed(a, b, NULL, ret, err);
}

int geo_hausdorff_ctx(const geo_poly *a, const geo_poly *b,
                      const geo_ctx *ctx, double *ret, geo_err *err)
{
    double ab, ba;
    int r = directed(a, b, ctx, &ab, err);
    if (r == 0)
        r = directed(b, a, ctx, &ba, err);
    if (r == 0)
        *ret = fmax(ab, ba);
    return r;
}

int geo_hausdorff(const geo_poly *a, const geo_poly *b, double *ret,
                  geo_err *err)
{
    return geo_hausdorff_ctx(a, b, NULL, ret, err);
}
