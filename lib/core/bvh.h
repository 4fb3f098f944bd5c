/* bvh.h — a bounding-volume hierarchy of axis-aligned boxes, built in
 * O(n log n) by median splits on the longest axis (quickselect), leaves of
 * at most GEO_BVH_LEAF items. Used by point-in-polyhedron, the plane cut
 * and the replanar and fill checks (the self-intersection search has its
 * own, smaller tree: fbvh.h). Items are identified by their index in the input
 * box array (for geo_bvh_build_facets: the facet index).
 *
 * Node layout: nodes[0] is the root; an internal node's children are
 * nodes[n.child] and nodes[n.child + 1]; a leaf (count > 0) holds
 * items[n.child .. n.child + count − 1].
 *
 * Boxes are closed: touching boxes overlap. Box tests are plain floating
 * point comparisons on the stored (exact input) bounds; boxes only prune,
 * they never decide topology.
 *
 * Ownership: build allocates, geo_bvh_free releases. Queries are
 * read-only and thread-safe on a finished hierarchy. */
#ifndef GEO_BVH_H
#define GEO_BVH_H

#include <stdbool.h>
#include <stdint.h>

#include "poly.h"

#define GEO_BVH_LEAF 4

typedef struct geo_bbox {
    double lo[3], hi[3];
} geo_bbox;

typedef struct geo_bvh_node {
    geo_bbox box;
    uint32_t child; /* first child (internal) or first item slot (leaf) */
    uint32_t count; /* 0 for internal nodes, else the leaf's item count */
} geo_bvh_node;

typedef struct geo_bvh {
    uint32_t nnodes, nitems;
    geo_bvh_node *nodes; /* nnodes; nodes[0] is the root (if nitems > 0) */
    uint32_t *items;     /* nitems item indices in leaf order */
    geo_bbox *boxes;     /* nitems: boxes[k] is the box of items[k] */
} geo_bvh;

/* An empty box (lo = +inf, hi = −inf) that geo_bbox_add grows. */
void geo_bbox_empty(geo_bbox *b);
void geo_bbox_add(geo_bbox *b, const double p[3]);
void geo_bbox_union(geo_bbox *b, const geo_bbox *other);
static inline bool geo_bbox_overlap(const geo_bbox *a, const geo_bbox *b)
{
    return a->lo[0] <= b->hi[0] && b->lo[0] <= a->hi[0] &&
           a->lo[1] <= b->hi[1] && b->lo[1] <= a->hi[1] &&
           a->lo[2] <= b->hi[2] && b->lo[2] <= a->hi[2];
}
static inline bool geo_bbox_contains(const geo_bbox *b, const double p[3])
{
    return b->lo[0] <= p[0] && p[0] <= b->hi[0] && b->lo[1] <= p[1] &&
           p[1] <= b->hi[1] && b->lo[2] <= p[2] && p[2] <= b->hi[2];
}


/* The bounding box of facet f of p. */
void geo_poly_facet_bbox(const geo_poly *p, uint32_t f, geo_bbox *ret);

/* Builds a hierarchy over n boxes (copied, in leaf order). Returns NULL
 * on out-of-memory (err set). */
geo_bvh *geo_bvh_build(const geo_bbox *boxes, uint32_t n, geo_err *err);

/* Builds a hierarchy over the facets of p. NULL on out-of-memory. */
geo_bvh *geo_bvh_build_facets(const geo_poly *p, geo_err *err);

/* Releases h; accepts NULL; returns NULL. */
geo_bvh *geo_bvh_free(geo_bvh *h);

/* A visitor returns false to stop the whole query early. */
typedef bool (*geo_bvh_visit_fn)(void *user, uint32_t item);
typedef bool (*geo_bvh_pair_fn)(void *user, uint32_t a, uint32_t b);

/* Visits every item whose own box overlaps q. Returns false when a
 * visitor stopped the query. */
bool geo_bvh_query_box(const geo_bvh *h, const geo_bbox *q,
                       geo_bvh_visit_fn visit, void *user);

/* Visits every item whose box the plane may touch
 * (geo_bbox_plane_side == 0). */
bool geo_bvh_query_plane(const geo_bvh *h, const double plane[4],
                         geo_bvh_visit_fn visit, void *user);

/* Visits every item whose box the segment o + t·d, t in [0, tmax], may
 * hit (tmax may be INFINITY for a ray). Boxes are inflated by a relative
 * 1e-9 so that rounding never drops a box the ray touches. */
bool geo_bvh_query_ray(const geo_bvh *h, const double o[3], const double d[3],
                       double tmax, geo_bvh_visit_fn visit, void *user);

/* Visits every unordered pair (a, b), a ≠ b, of items whose own boxes
 * overlap, below node pair (na, nb); na == nb enumerates the pairs within
 * one subtree. Each pair is reported once. */
bool geo_bvh_pairs(const geo_bvh *h, uint32_t na, uint32_t nb,
                   geo_bvh_pair_fn visit, void *user);

/* Splits the self-pair search of the whole tree into independent tasks
 * (node pairs) so callers can run them with a parallel_for: fills up to
 * cap pairs into ret_a/ret_b (node indices) and returns the count; running
 * geo_bvh_pairs on every task reports every overlapping pair exactly once.
 * Returns 0 for an empty tree. */
uint32_t geo_bvh_pair_tasks(const geo_bvh *h, uint32_t *ret_a, uint32_t *ret_b,
                            uint32_t cap);

#endif
