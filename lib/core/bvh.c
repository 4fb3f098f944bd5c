/* bvh.c — median-split bounding-volume hierarchy and its queries. */
#include "bvh.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "select.h"

void geo_bbox_empty(geo_bbox *b)
{
    for (int k = 0; k < 3; k++) {
        b->lo[k] = INFINITY;
        b->hi[k] = -INFINITY;
    }
}

/* Written as selections, not branches, so they compile to min/max
 * instructions: the same values (a NaN never replaces a bound; of equal
 * bounds the one already there stays). */
void geo_bbox_add(geo_bbox *b, const double p[3])
{
    for (int k = 0; k < 3; k++) {
        b->lo[k] = p[k] < b->lo[k] ? p[k] : b->lo[k];
        b->hi[k] = p[k] > b->hi[k] ? p[k] : b->hi[k];
    }
}

void geo_bbox_union(geo_bbox *b, const geo_bbox *o)
{
    for (int k = 0; k < 3; k++) {
        b->lo[k] = o->lo[k] < b->lo[k] ? o->lo[k] : b->lo[k];
        b->hi[k] = o->hi[k] > b->hi[k] ? o->hi[k] : b->hi[k];
    }
}

/* Which side of the plane (a,b,c,d; any normal length) the box lies on:
 * +1 entirely where plane(p) > 0, −1 entirely where < 0, 0 when the plane
 * may touch or cross it. Floating point with a relative margin, so a 0 is
 * conservative (a box reported ±1 truly is on that side). */
static int geo_bbox_plane_side(const geo_bbox *b, const double plane[4])
{
    double val = plane[3], r = 0, mag = fabs(plane[3]);
    for (int k = 0; k < 3; k++) {
        double c = 0.5 * (b->lo[k] + b->hi[k]), e = 0.5 * (b->hi[k] - b->lo[k]);
        val += plane[k] * c;
        r += fabs(plane[k]) * e;
        mag += fabs(plane[k]) * (fabs(c) + e);
    }
    double margin = 1e-12 * mag;
    if (val - r > margin)
        return 1;
    if (val + r < -margin)
        return -1;
    return 0;
}

void geo_poly_facet_bbox(const geo_poly *p, uint32_t f, geo_bbox *ret)
{
    geo_bbox_empty(ret);
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *v = geo_poly_facet(p, f);
    for (uint32_t i = 0; i < n; i++)
        geo_bbox_add(ret, p->verts[v[i]]);
}

geo_bvh *geo_bvh_free(geo_bvh *h)
{
    if (!h)
        return NULL;
    free(h->nodes);
    free(h->items);
    free(h->boxes);
    free(h);
    return NULL;
}

/* The state of one build: the split comes from the centroids, and each
 * item's box is copied from in[] as its leaf is formed (h->boxes then is
 * in leaf order without a pass of its own). */
typedef struct builder {
    geo_bvh *h;
    const geo_bbox *in;       /* input boxes by item index */
    const double (*cent)[3];  /* centroids by item index */
} builder;

/* The median split of items[lo, hi) on the longest axis of their
 * centroids' bounds. */
static uint32_t median_split(const builder *b, uint32_t lo, uint32_t hi)
{
    const geo_bvh *h = b->h;
    geo_bbox cb;
    geo_bbox_empty(&cb);
    for (uint32_t i = lo; i < hi; i++)
        geo_bbox_add(&cb, b->cent[h->items[i]]);
    int axis = 0;
    for (int k = 1; k < 3; k++)
        if (cb.hi[k] - cb.lo[k] > cb.hi[axis] - cb.lo[axis])
            axis = k;
    uint32_t mid = lo + (hi - lo) / 2;
    geo_select_axis(b->cent, h->items, lo, hi, mid, axis);
    return mid;
}

/* A node's box is the union of its children's (a leaf's: of its items'),
 * formed after the children are built: the same box as the union of all
 * its items, taken in the same order, without a pass over them per
 * level. */
static void build_node(const builder *b, uint32_t node, uint32_t lo,
                       uint32_t hi)
{
    geo_bvh *h = b->h;
    geo_bvh_node *n = &h->nodes[node];
    geo_bbox_empty(&n->box);
    if (hi - lo <= GEO_BVH_LEAF) {
        for (uint32_t i = lo; i < hi; i++) {
            h->boxes[i] = b->in[h->items[i]];
            geo_bbox_union(&n->box, &h->boxes[i]);
        }
        n->child = lo;
        n->count = hi - lo;
        return;
    }
    uint32_t mid = median_split(b, lo, hi);
    uint32_t child = h->nnodes;
    h->nnodes += 2;
    n->child = child;
    n->count = 0;
    build_node(b, child, lo, mid);
    build_node(b, child + 1, mid, hi);
    n = &h->nodes[node];
    geo_bbox_union(&n->box, &h->nodes[child].box);
    geo_bbox_union(&n->box, &h->nodes[child + 1].box);
}

/* A tree with room for n items and its nodes, or NULL. */
static geo_bvh *bvh_alloc(uint32_t n)
{
    geo_bvh *h = calloc(1, sizeof *h);
    if (!h)
        return NULL;
    h->nitems = n;
    h->nodes = malloc((2 * (size_t)n + 1) * sizeof *h->nodes);
    h->items = malloc(((size_t)n + 1) * sizeof *h->items);
    h->boxes = malloc(((size_t)n + 1) * sizeof *h->boxes);
    if (!h->nodes || !h->items || !h->boxes)
        return geo_bvh_free(h);
    return h;
}

geo_bvh *geo_bvh_build(const geo_bbox *boxes, uint32_t n, geo_err *err)
{
    geo_bvh *h = bvh_alloc(n);
    double (*cent)[3] = malloc(((size_t)n + 1) * sizeof *cent);
    if (!h || !cent) {
        free(cent);
        geo_err_set(err, -ENOMEM, "out of memory building the BVH");
        return geo_bvh_free(h);
    }
    for (uint32_t i = 0; i < n; i++) {
        h->items[i] = i;
        for (int k = 0; k < 3; k++)
            cent[i][k] = 0.5 * (boxes[i].lo[k] + boxes[i].hi[k]);
    }
    if (n > 0) {
        builder b = {h, boxes, (const double (*)[3])cent};
        h->nnodes = 1;
        build_node(&b, 0, 0, n);
    }
    free(cent);
    return h;
}

/* A BVH over p's facet boxes built by build (either builder). */
static geo_bvh *build_over_facets(const geo_poly *p, geo_err *err,
                                  geo_bvh *(*build)(const geo_bbox *,
                                                    uint32_t, geo_err *))
{
    geo_bbox *boxes = malloc(((size_t)p->nfacets + 1) * sizeof *boxes);
    if (!boxes) {
        geo_err_set(err, -ENOMEM, "out of memory building the BVH");
        return NULL;
    }
    for (uint32_t f = 0; f < p->nfacets; f++)
        geo_poly_facet_bbox(p, f, &boxes[f]);
    geo_bvh *h = build(boxes, p->nfacets, err);
    free(boxes);
    return h;
}

geo_bvh *geo_bvh_build_facets(const geo_poly *p, geo_err *err)
{
    return build_over_facets(p, err, geo_bvh_build);
}

/* An explicit stack: depth is bounded by the tree height (median splits:
 * ≤ 2·log2 n) plus one. */
enum { STACK = 128 };

/* Which boxes a query descends into and whose items it visits. */
typedef bool (*box_test_fn)(const geo_bbox *b, const void *query);

/* The one traversal of the queries. Always inlined, so that each query
 * gets it with its own test compiled in, not called through a pointer. */
static inline __attribute__((always_inline)) bool
query(const geo_bvh *h, box_test_fn hits, const void *q,
      geo_bvh_visit_fn visit, void *user)
{
    if (h->nitems == 0)
        return true;
    uint32_t stack[STACK], sp = 0;
    stack[sp++] = 0;
    while (sp) {
        const geo_bvh_node *n = &h->nodes[stack[--sp]];
        if (!hits(&n->box, q))
            continue;
        if (n->count) {
            for (uint32_t i = n->child; i < n->child + n->count; i++)
                if (hits(&h->boxes[i], q) && !visit(user, h->items[i]))
                    return false;
        } else {
            stack[sp++] = n->child;
            stack[sp++] = n->child + 1;
        }
    }
    return true;
}

static bool box_hits(const geo_bbox *b, const void *q)
{
    return geo_bbox_overlap(b, q);
}

bool geo_bvh_query_box(const geo_bvh *h, const geo_bbox *q,
                       geo_bvh_visit_fn visit, void *user)
{
    return query(h, box_hits, q, visit, user);
}

static bool plane_hits(const geo_bbox *b, const void *plane)
{
    return geo_bbox_plane_side(b, plane) == 0;
}

bool geo_bvh_query_plane(const geo_bvh *h, const double plane[4],
                         geo_bvh_visit_fn visit, void *user)
{
    return query(h, plane_hits, plane, visit, user);
}

static bool ray_hits_box(const geo_bbox *b, const double o[3],
                         const double d[3], double tmax)
{
    double t0 = 0, t1 = tmax;
    for (int k = 0; k < 3; k++) {
        double pad = 1e-9 * (fabs(b->lo[k]) + fabs(b->hi[k]) +
                             (b->hi[k] - b->lo[k])) + 1e-300;
        double lo = b->lo[k] - pad, hi = b->hi[k] + pad;
        if (d[k] == 0) {
            if (o[k] < lo || o[k] > hi)
                return false;
            continue;
        }
        double ta = (lo - o[k]) / d[k], tb = (hi - o[k]) / d[k];
        if (ta > tb) {
            double t = ta;
            ta = tb;
            tb = t;
        }
        if (ta > t0)
            t0 = ta;
        if (tb < t1)
            t1 = tb;
        if (t0 > t1)
            return false;
    }
    return true;
}

typedef struct segment {
    const double *o, *d;
    double tmax;
} segment;

static bool segment_hits(const geo_bbox *b, const void *q)
{
    const segment *sg = q;
    return ray_hits_box(b, sg->o, sg->d, sg->tmax);
}

bool geo_bvh_query_ray(const geo_bvh *h, const double o[3], const double d[3],
                       double tmax, geo_bvh_visit_fn visit, void *user)
{
    segment sg = {o, d, tmax};
    return query(h, segment_hits, &sg, visit, user);
}

static double box_extent(const geo_bbox *b)
{
    return (b->hi[0] - b->lo[0]) + (b->hi[1] - b->lo[1]) + (b->hi[2] - b->lo[2]);
}

bool geo_bvh_pairs(const geo_bvh *h, uint32_t na, uint32_t nb,
                   geo_bvh_pair_fn visit, void *user)
{
    const geo_bvh_node *a = &h->nodes[na], *b = &h->nodes[nb];
    if (na == nb) {
        if (a->count) {
            for (uint32_t i = a->child; i < a->child + a->count; i++)
                for (uint32_t j = i + 1; j < a->child + a->count; j++)
                    if (geo_bbox_overlap(&h->boxes[i], &h->boxes[j]) &&
                        !visit(user, h->items[i], h->items[j]))
                        return false;
            return true;
        }
        return geo_bvh_pairs(h, a->child, a->child, visit, user) &&
               geo_bvh_pairs(h, a->child + 1, a->child + 1, visit, user) &&
               geo_bvh_pairs(h, a->child, a->child + 1, visit, user);
    }
    if (!geo_bbox_overlap(&a->box, &b->box))
        return true;
    if (a->count && b->count) {
        for (uint32_t i = a->child; i < a->child + a->count; i++) {
            if (!geo_bbox_overlap(&h->boxes[i], &b->box))
                continue;
            for (uint32_t j = b->child; j < b->child + b->count; j++)
                if (geo_bbox_overlap(&h->boxes[i], &h->boxes[j]) &&
                    !visit(user, h->items[i], h->items[j]))
                    return false;
        }
        return true;
    }
    bool split_a = !a->count &&
                   (b->count || box_extent(&a->box) >= box_extent(&b->box));
    if (split_a)
        return geo_bvh_pairs(h, a->child, nb, visit, user) &&
               geo_bvh_pairs(h, a->child + 1, nb, visit, user);
    return geo_bvh_pairs(h, na, b->child, visit, user) &&
           geo_bvh_pairs(h, na, b->child + 1, visit, user);
}

uint32_t geo_bvh_pair_tasks(const geo_bvh *h, uint32_t *ret_a, uint32_t *ret_b,
                            uint32_t cap)
{
    if (h->nitems == 0 || cap == 0)
        return 0;
    uint32_t n = 0;
    ret_a[n] = 0;
    ret_b[n] = 0;
    n++;
    /* expand tasks breadth-first while the list has room for the largest
     * expansion (a self task of an internal node becomes three tasks, a
     * cross task of two internal nodes up to four) */
    for (uint32_t i = 0; i < n && n + 4 <= cap;) {
        const geo_bvh_node *a = &h->nodes[ret_a[i]], *b = &h->nodes[ret_b[i]];
        if (a->count || b->count) {
            i++;
            continue;
        }
        uint32_t na = ret_a[i], nb = ret_b[i];
        /* replace task i by its first sub-task, append the rest */
        if (na == nb) {
            uint32_t l = a->child, r = a->child + 1;
            ret_a[i] = l, ret_b[i] = l;
            ret_a[n] = r, ret_b[n] = r, n++;
            ret_a[n] = l, ret_b[n] = r, n++;
        } else {
            uint32_t sub[4][2] = {{a->child, b->child},
                                  {a->child, b->child + 1},
                                  {a->child + 1, b->child},
                                  {a->child + 1, b->child + 1}};
            uint32_t kept = 0;
            for (int k = 0; k < 4; k++) {
                if (!geo_bbox_overlap(&h->nodes[sub[k][0]].box,
                                      &h->nodes[sub[k][1]].box))
                    continue;
                uint32_t slot = kept++ == 0 ? i : n++;
                ret_a[slot] = sub[k][0];
                ret_b[slot] = sub[k][1];
            }
            if (kept == 0) { /* drop task i: move the last one here */
                n--;
                ret_a[i] = ret_a[n];
                ret_b[i] = ret_b[n];
            }
        }
    }
    return n;
}
