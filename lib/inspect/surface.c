/* surface.c — nearest-facet queries of surface.h.
 * Invariant: the best distance found so far only shrinks, and a BVH node
 * is opened only when its box could hold something nearer. */
#include "surface.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bvh.h"
#include "selfint.h"
#include "vec.h"

/* Facets of the target above this size are looked at as triangles. */
enum { FAN_MIN = 32 };

struct geo_surface {
    const geo_poly *g;  /* the searched pieces: b, or its fanned copy */
    geo_poly *fanned;   /* owned, NULL when b is searched as is */
    uint32_t *origin;   /* piece → facet of b; NULL when g is b */
    geo_bvh *bvh;
};

/* b with every convex facet of more than FAN_MIN vertices fanned into
 * triangles that keep its plane: they cover the polygon exactly, so the
 * distance to the surface is unchanged, but a query near such a facet
 * (a prism's 60,000-gon cap) costs O(log n) instead of O(n). Leaves
 * s->fanned NULL when no facet needs it. 0 or -ENOMEM. */
static int fan_large_facets(const geo_poly *b, geo_surface *s)
{
    uint32_t nbig = 0;
    for (uint32_t f = 0; f < b->nfacets; f++)
        nbig += geo_poly_facet_size(b, f) > FAN_MIN;
    if (nbig == 0)
        return 0;
    geo_poly *q = geo_poly_new();
    uint32_t cap = 0;
    for (uint32_t f = 0; f < b->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(b, f);
        cap += n > FAN_MIN ? n - 2 : 1;
    }
    uint32_t *origin = malloc((size_t)cap * sizeof *origin);
    if (!q || !origin || geo_poly_reserve(q, b->nverts, b->nfacets, 0) < 0)
        goto oom;
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
            origin[g] = f;
            continue;
        }
        for (uint32_t i = 1; i + 1 < n; i++) {
            uint32_t t[3] = {vs[0], vs[i], vs[i + 1]};
            int64_t g = geo_poly_add_facet(q, t, 3);
            if (g < 0)
                goto oom;
            memcpy(q->planes[g], b->planes[f], sizeof q->planes[g]);
            origin[g] = f;
        }
    }
    s->fanned = q;
    s->origin = origin;
    return 0;
oom:
    geo_poly_free(q);
    free(origin);
    return -ENOMEM;
}

int geo_surface_new(const geo_poly *b, geo_surface **ret, geo_err *err)
{
    *ret = NULL;
    if (b->nfacets == 0)
        return geo_err_set(err, -EINVAL, "surface: the model has no facets");
    geo_surface *s = calloc(1, sizeof *s);
    if (!s || fan_large_facets(b, s) < 0) {
        free(s);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    s->g = s->fanned ? s->fanned : b;
    s->bvh = geo_bvh_build_facets(s->g, err);
    if (!s->bvh) {
        geo_surface_free(s);
        return -ENOMEM;
    }
    *ret = s;
    return 0;
}

void geo_surface_free(geo_surface *s)
{
    if (!s)
        return;
    geo_bvh_free(s->bvh);
    geo_poly_free(s->fanned);
    free(s->origin);
    free(s);
}

void geo_surface_facet_order(const geo_surface *s, uint32_t *order)
{
    const geo_bvh *h = s->bvh;
    if (!s->origin) {
        memcpy(order, h->items, (size_t)h->nitems * sizeof *order);
        return;
    }
    /* a fanned facet's pieces are consecutive in the fanned copy: the
     * facet is placed where its first piece is met in leaf order */
    uint32_t n = 0;
    for (uint32_t i = 0; i < h->nitems; i++) {
        uint32_t piece = h->items[i], f = s->origin[piece];
        if (piece == 0 || s->origin[piece - 1] != f)
            order[n++] = f;
    }
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
    /* edges as (previous, current) pairs: no division per edge */
    int wn = 0;
    for (uint32_t i = 0, j = n - 1; i < n; j = i++) {
        const double *a = g->verts[vs[j]], *b = g->verts[vs[i]];
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
    double best = INFINITY; /* compared, not fmin: a libm call here */
    for (uint32_t i = 0, j = n - 1; i < n; j = i++) {
        double d = seg_dist2(p, g->verts[vs[j]], g->verts[vs[i]]);
        if (d < best)
            best = d;
    }
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
 * *arg is the facet that gave *best. The search ends as soon as *best ≤
 * stop (stop < 0: never). */
static void nearest(const geo_poly *g, const geo_bvh *h, uint32_t node,
                    const double p[3], double *best, uint32_t *arg,
                    double stop)
{
    const geo_bvh_node *n = &h->nodes[node];
    if (*best <= stop || box_dist2(&n->box, p) >= *best)
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
    nearest(g, h, c0, p, best, arg, stop);
    nearest(g, h, c1, p, best, arg, stop);
}

static double query(const geo_surface *s, const double p[3], double stop,
                    uint32_t *hint)
{
    double best = INFINITY;
    if (*hint != UINT32_MAX && *hint < s->g->nfacets)
        best = facet_dist2(s->g, *hint, p, INFINITY);
    else
        *hint = UINT32_MAX;
    nearest(s->g, s->bvh, 0, p, &best, hint, stop);
    return best;
}

/* The search starts with the bound given by the piece nearest to the
 * previous query (*hint): queries in surface order make that bound tight,
 * and it prunes almost every box. */
double geo_surface_dist2(const geo_surface *s, const double p[3],
                         uint32_t *hint, uint32_t *facet)
{
    double best = query(s, p, -1, hint);
    if (facet)
        *facet = s->origin ? s->origin[*hint] : *hint;
    return best;
}

double geo_surface_dist2_above(const geo_surface *s, const double p[3],
                               double floor2, uint32_t *hint)
{
    return query(s, p, floor2, hint);
}
