/* fbvh.c — the Morton-ordered hierarchy of 16-bit grid boxes and its
 * pair search. */
#include "fbvh.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

/* g(x) of fbvh.h, with the seams at the grid's ends: at or below the
 * origin 0, at or above its far end the last cell, between them the
 * product, which rounding may carry past the end (clamped). Monotone. */
static double grid_of(const geo_fbvh *h, int k, double x, double far)
{
    if (x <= h->origin[k])
        return 0;
    if (x >= far)
        return GEO_FBVH_CELLS;
    double g = (x - h->origin[k]) * h->scale;
    return g < GEO_FBVH_CELLS ? g : GEO_FBVH_CELLS;
}

/* The far end of axis k of h's grid: origin + the cells' span. */
static double grid_far(const geo_fbvh *h, int k)
{
    return h->scale > 0 ? h->origin[k] + GEO_FBVH_CELLS / h->scale
                        : h->origin[k];
}

static void qbox_empty(geo_qbox *b)
{
    for (int k = 0; k < 3; k++) {
        b->lo[k] = GEO_FBVH_CELLS + 1;
        b->hi[k] = 0;
    }
}

/* Quantise with the axes' far ends given (computed once per build). */
static void quantize(const geo_fbvh *h, const double far[3],
                     const geo_bbox *b, geo_qbox *ret)
{
    for (int k = 0; k < 3; k++)
        if (isnan(b->lo[k]) || isnan(b->hi[k])) {
            qbox_empty(ret);
            return;
        }
    /* g is in [0, GEO_FBVH_CELLS]: truncation is its floor */
    for (int k = 0; k < 3; k++) {
        double lo = grid_of(h, k, b->lo[k], far[k]);
        double hi = grid_of(h, k, b->hi[k], far[k]);
        uint32_t l = (uint32_t)lo, u = (uint32_t)hi;
        ret->lo[k] = (uint16_t)l;
        ret->hi[k] = (uint16_t)(u + ((double)u < hi));
    }
}

void geo_fbvh_quantize(const geo_fbvh *h, const geo_bbox *b, geo_qbox *ret)
{
    double far[3];
    for (int k = 0; k < 3; k++)
        far[k] = grid_far(h, k);
    quantize(h, far, b, ret);
}

/* Selections (min/max instructions); an empty box changes nothing. */
static void qbox_union(geo_qbox *b, const geo_qbox *o)
{
    for (int k = 0; k < 3; k++) {
        b->lo[k] = o->lo[k] < b->lo[k] ? o->lo[k] : b->lo[k];
        b->hi[k] = o->hi[k] > b->hi[k] ? o->hi[k] : b->hi[k];
    }
}

static inline bool qbox_overlap(const geo_qbox *a, const geo_qbox *b)
{
    return a->lo[0] <= b->hi[0] && b->lo[0] <= a->hi[0] &&
           a->lo[1] <= b->hi[1] && b->lo[1] <= a->hi[1] &&
           a->lo[2] <= b->hi[2] && b->lo[2] <= a->hi[2];
}

/* qbox_overlap without branches (1 or 0), for the leaves' all-pairs
 * tests, whose outcomes follow no pattern a branch predictor learns. */
static inline unsigned qbox_meets(const geo_qbox *a, const geo_qbox *b)
{
    return (unsigned)(a->lo[0] <= b->hi[0]) & (b->lo[0] <= a->hi[0]) &
           (a->lo[1] <= b->hi[1]) & (b->lo[1] <= a->hi[1]) &
           (a->lo[2] <= b->hi[2]) & (b->lo[2] <= a->hi[2]);
}

_Static_assert(GEO_FBVH_LEAF <= 32, "a leaf's items are bits of a mask");

/* The items of leaf range [lo, lo + n) whose boxes meet box: bit k for
 * item lo + k (n ≤ GEO_FBVH_LEAF ≤ 32). With SSE2 a box is one vector:
 * lanes 0-2 hold lo_b − hi_a and lanes 3-5 lo_a − hi_b as saturating
 * differences, all 0 exactly when the boxes meet; lanes 6-7 (the next
 * box's first bytes, or the array's spare slot after the last box) come
 * out 0 whatever they hold. */
static inline uint32_t qbox_meets_mask(const geo_fbvh *h, const geo_qbox *box,
                                       uint32_t lo, uint32_t n)
{
    uint32_t m = 0;
#ifdef __SSE2__
    const __m128i hi_a =
        _mm_setr_epi16((short)box->hi[0], (short)box->hi[1],
                       (short)box->hi[2], -1, -1, -1, -1, -1);
    const __m128i lo_a =
        _mm_setr_epi16(0, 0, 0, (short)box->lo[0], (short)box->lo[1],
                       (short)box->lo[2], 0, 0);
    const __m128i zero = _mm_setzero_si128();
    for (uint32_t k = 0; k < n; k++) {
        __m128i b = _mm_loadu_si128(
            (const __m128i *)(const void *)&h->boxes[lo + k]);
        __m128i d = _mm_or_si128(_mm_subs_epu16(b, hi_a),
                                 _mm_subs_epu16(lo_a, b));
        m |= (uint32_t)(_mm_movemask_epi8(_mm_cmpeq_epi16(d, zero)) ==
                        0xFFFF)
             << k;
    }
#else
    for (uint32_t k = 0; k < n; k++)
        m |= qbox_meets(box, &h->boxes[lo + k]) << k;
#endif
    return m;
}

/* Of the slots lo + k (bit k of m), those whose tags share none with
 * slot i's; all of m without tags. Without branches per slot: whether two
 * neighbours share a tag follows no pattern a predictor learns. */
static inline uint32_t untagged(const geo_fbvh *h, uint32_t i, uint32_t lo,
                                uint32_t m)
{
    if (!h->tags || !m)
        return m;
    const uint32_t x0 = h->tags[i][0], x1 = h->tags[i][1],
                   x2 = h->tags[i][2];
    uint32_t keep = 0;
    for (; m; m &= m - 1) {
        unsigned k = (unsigned)__builtin_ctz(m);
        const uint32_t *y = h->tags[lo + k];
        unsigned s = (x0 == y[0]) | (x0 == y[1]) | (x0 == y[2]) |
                     (x1 == y[0]) | (x1 == y[1]) | (x1 == y[2]) |
                     (x2 == y[0]) | (x2 == y[1]) | (x2 == y[2]);
        keep |= (uint32_t)(s ^ 1u) << k;
    }
    return keep;
}

/* The sum of the sides, in cells (cubic cells: as the sum in mm). */
static inline int32_t qbox_extent(const geo_qbox *b)
{
    return ((int32_t)b->hi[0] - b->lo[0]) + ((int32_t)b->hi[1] - b->lo[1]) +
           ((int32_t)b->hi[2] - b->lo[2]);
}

geo_fbvh *geo_fbvh_free(geo_fbvh *h)
{
    if (!h)
        return NULL;
    free(h->nodes);
    free(h->items);
    free(h->boxes);
    free(h);
    return NULL;
}

/* The 10 low bits of x spread to every third bit (bits 0, 3, ..., 27). */
static uint32_t spread10(uint32_t x)
{
    x &= 1023;
    x = (x | x << 16) & 0x030000FFu;
    x = (x | x << 8) & 0x0300F00Fu;
    x = (x | x << 4) & 0x030C30C3u;
    x = (x | x << 2) & 0x09249249u;
    return x;
}

/* Where a build takes its items' boxes from: an array by item index, or
 * the facets of a polyhedron (computed where needed, from the vertices,
 * rather than kept in a second array of boxes). */
typedef struct box_source {
    const geo_bbox *boxes;
    const geo_poly *p;
} box_source;

static inline void source_box(const box_source *src, uint32_t i,
                              geo_bbox *ret)
{
    if (src->boxes)
        *ret = src->boxes[i];
    else
        geo_poly_facet_bbox(src->p, i, ret);
}

/* The state of one build: the items' Morton codes by item index, the
 * items sorted by them. */
typedef struct builder {
    geo_fbvh *h;
    const uint32_t *code;
} builder;

/* The split of items[lo, hi): the first item whose code has the highest
 * differing bit set (codes are sorted, so a binary search), or the
 * middle when all codes are equal; lo < mid < hi. */
static uint32_t morton_split(const builder *b, uint32_t lo, uint32_t hi)
{
    const uint32_t *items = b->h->items;
    uint32_t c0 = b->code[items[lo]], c1 = b->code[items[hi - 1]];
    if (c0 == c1)
        return lo + (hi - lo) / 2;
    uint32_t bit = 31 - (uint32_t)__builtin_clz(c0 ^ c1);
    uint32_t l = lo + 1, r = hi - 1;
    while (l < r) {
        uint32_t m = l + (r - l) / 2;
        if (b->code[items[m]] >> bit & 1)
            r = m;
        else
            l = m + 1;
    }
    return l;
}

/* A node's box is the union of its children's (a leaf's: of its
 * items'), formed after the children are built. */
static void build_node(const builder *b, uint32_t node, uint32_t lo,
                       uint32_t hi)
{
    geo_fbvh *h = b->h;
    geo_fbvh_node *n = &h->nodes[node];
    qbox_empty(&n->box);
    if (hi - lo <= GEO_FBVH_LEAF) {
        for (uint32_t i = lo; i < hi; i++)
            qbox_union(&n->box, &h->boxes[i]);
        n->child = lo;
        n->count = hi - lo;
        return;
    }
    uint32_t mid = morton_split(b, lo, hi);
    uint32_t child = h->nnodes;
    h->nnodes += 2;
    n->child = child;
    n->count = 0;
    build_node(b, child, lo, mid);
    build_node(b, child + 1, mid, hi);
    n = &h->nodes[node];
    qbox_union(&n->box, &h->nodes[child].box);
    qbox_union(&n->box, &h->nodes[child + 1].box);
}

/* The grid from the finite bounds, then in one pass the codes from the
 * box centres and the grid boxes in item order (kept in the node array,
 * not yet used: 20 bytes a node, 2n + 1 nodes), a radix sort of the
 * items (its buffer the box array, not yet filled), the boxes gathered
 * in leaf order, then the nodes, whose array is cut to the nodes used
 * (about 0.7 per item, of the 2 per item a tree may need). Every array
 * touched is the tree's own. -ENOMEM. */
static int build(geo_fbvh *h, const box_source *src)
{
    uint32_t n = h->nitems;
    uint32_t *code = malloc(((size_t)n + 1) * sizeof *code);
    uint32_t *tmp = (uint32_t *)h->boxes; /* 12 bytes an item: room */
    geo_qbox *byitem = (geo_qbox *)h->nodes;
    if (!code)
        return -ENOMEM;
    geo_bbox cb, b, all;
    geo_bbox_empty(&cb);
    geo_bbox_empty(&all);
    /* a facet's box and centre lie within its vertices' box: over the
     * polyhedron's finite coordinates (a pass over the vertices, not over
     * the facets) for both grids; any grid keeps the boxes conservative,
     * and the codes only shape the tree */
    for (uint32_t v = 0; src->p && v < src->p->nverts; v++)
        for (int k = 0; k < 3; k++) {
            double x = src->p->verts[v][k];
            if (!isfinite(x))
                continue;
            all.lo[k] = x < all.lo[k] ? x : all.lo[k];
            all.hi[k] = x > all.hi[k] ? x : all.hi[k];
        }
    if (src->p)
        cb = all;
    for (uint32_t i = 0; !src->p && i < n; i++) {
        double c[3];
        source_box(src, i, &b);
        for (int k = 0; k < 3; k++) {
            c[k] = 0.5 * (b.lo[k] + b.hi[k]);
            /* the grid spans every finite bound, lo or hi */
            for (int e = 0; e < 2; e++) {
                double x = e ? b.hi[k] : b.lo[k];
                if (!isfinite(x))
                    continue;
                all.lo[k] = x < all.lo[k] ? x : all.lo[k];
                all.hi[k] = x > all.hi[k] ? x : all.hi[k];
            }
        }
        geo_bbox_add(&cb, c);
    }
    double scale[3], side = 0;
    for (int k = 0; k < 3; k++) {
        scale[k] = cb.hi[k] > cb.lo[k] ? 1024.0 / (cb.hi[k] - cb.lo[k]) : 0;
        h->origin[k] = all.lo[k] <= all.hi[k] ? all.lo[k] : 0;
        if (all.lo[k] <= all.hi[k] && all.hi[k] - all.lo[k] > side)
            side = all.hi[k] - all.lo[k];
    }
    /* side may be infinite (bounds beyond ±DBL_MAX/2): scale 0, every
     * finite bound in cell 0 or the last, still monotone */
    h->scale = side > 0 && isfinite(side) ? GEO_FBVH_CELLS / side : 0;
    double far[3];
    for (int k = 0; k < 3; k++)
        far[k] = grid_far(h, k);
    for (uint32_t i = 0; i < n; i++) {
        uint32_t q[3];
        source_box(src, i, &b);
        quantize(h, far, &b, &byitem[i]);
        for (int k = 0; k < 3; k++) {
            double x = (0.5 * (b.lo[k] + b.hi[k]) - cb.lo[k]) * scale[k];
            q[k] = x >= 0 ? (x < 1023 ? (uint32_t)x : 1023) : 0;
        }
        code[i] = spread10(q[0]) << 2 | spread10(q[1]) << 1 | spread10(q[2]);
        h->items[i] = i;
    }
    /* least significant digit first, 10 bits a pass, stable */
    for (int shift = 0; shift < 30; shift += 10) {
        uint32_t count[1025] = {0};
        for (uint32_t i = 0; i < n; i++)
            count[(code[i] >> shift & 1023) + 1]++;
        for (int d = 0; d < 1024; d++)
            count[d + 1] += count[d];
        for (uint32_t i = 0; i < n; i++) {
            uint32_t it = h->items[i];
            tmp[count[code[it] >> shift & 1023]++] = it;
        }
        memcpy(h->items, tmp, (size_t)n * sizeof *tmp);
    }
    for (uint32_t k = 0; k < n; k++)
        h->boxes[k] = byitem[h->items[k]];
    /* the spare slot: the pair search's vector load of the last box
     * reads 4 bytes into it (qbox_meets_mask) */
    qbox_empty(&h->boxes[n]);
    if (n > 0) {
        builder mb = {h, code};
        h->nnodes = 1;
        build_node(&mb, 0, 0, n);
        geo_fbvh_node *cut =
            realloc(h->nodes, (size_t)h->nnodes * sizeof *h->nodes);
        if (cut)
            h->nodes = cut;
    }
    free(code);
    return 0;
}

static geo_fbvh *build_over(const box_source *src, uint32_t n, geo_err *err)
{
    geo_fbvh *h = calloc(1, sizeof *h);
    if (h) {
        h->nitems = n;
        h->nodes = malloc((2 * (size_t)n + 1) * sizeof *h->nodes);
        h->items = malloc(((size_t)n + 1) * sizeof *h->items);
        h->boxes = malloc(((size_t)n + 1) * sizeof *h->boxes);
    }
    if (!h || !h->nodes || !h->items || !h->boxes || build(h, src) < 0) {
        geo_err_set(err, -ENOMEM, "out of memory building the BVH");
        return geo_fbvh_free(h);
    }
    return h;
}

geo_fbvh *geo_fbvh_build(const geo_bbox *boxes, uint32_t n, geo_err *err)
{
    box_source src = {boxes, NULL};
    return build_over(&src, n, err);
}

geo_fbvh *geo_fbvh_build_facets(const geo_poly *p, geo_err *err)
{
    box_source src = {NULL, p};
    return build_over(&src, p->nfacets, err);
}

bool geo_fbvh_pairs(const geo_fbvh *h, uint32_t na, uint32_t nb,
                    geo_bvh_pair_fn visit, void *user)
{
    const geo_fbvh_node *a = &h->nodes[na], *b = &h->nodes[nb];
    if (na == nb) {
        if (a->count) {
            uint32_t end = a->child + a->count;
            for (uint32_t i = a->child; i + 1 < end; i++)
                for (uint32_t m = untagged(
                         h, i, i + 1,
                         qbox_meets_mask(h, &h->boxes[i], i + 1,
                                         end - i - 1));
                     m; m &= m - 1)
                    if (!visit(user, h->items[i],
                               h->items[i + 1 + __builtin_ctz(m)]))
                        return false;
            return true;
        }
        return geo_fbvh_pairs(h, a->child, a->child, visit, user) &&
               geo_fbvh_pairs(h, a->child + 1, a->child + 1, visit, user) &&
               geo_fbvh_pairs(h, a->child, a->child + 1, visit, user);
    }
    if (!qbox_overlap(&a->box, &b->box))
        return true;
    if (a->count && b->count) {
        for (uint32_t ma = qbox_meets_mask(h, &b->box, a->child, a->count);
             ma; ma &= ma - 1) {
            uint32_t i = a->child + __builtin_ctz(ma);
            for (uint32_t m = untagged(h, i, b->child,
                                       qbox_meets_mask(h, &h->boxes[i],
                                                       b->child, b->count));
                 m; m &= m - 1)
                if (!visit(user, h->items[i],
                           h->items[b->child + __builtin_ctz(m)]))
                    return false;
        }
        return true;
    }
    bool split_a = !a->count &&
                   (b->count || qbox_extent(&a->box) >= qbox_extent(&b->box));
    if (split_a)
        return geo_fbvh_pairs(h, a->child, nb, visit, user) &&
               geo_fbvh_pairs(h, a->child + 1, nb, visit, user);
    return geo_fbvh_pairs(h, na, b->child, visit, user) &&
           geo_fbvh_pairs(h, na, b->child + 1, visit, user);
}

uint32_t geo_fbvh_pair_tasks(const geo_fbvh *h, uint32_t *ret_a,
                             uint32_t *ret_b, uint32_t cap)
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
        const geo_fbvh_node *a = &h->nodes[ret_a[i]],
                            *b = &h->nodes[ret_b[i]];
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
                if (!qbox_overlap(&h->nodes[sub[k][0]].box,
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
