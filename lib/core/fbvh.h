/* fbvh.h — a bounding-volume hierarchy for the pair search over many
 * boxes (the self-intersection search over a model's facets), in a
 * quarter of the memory of a geo_bvh: its boxes are 16-bit integers on a
 * grid over all the boxes.
 *
 * Build in O(n): the boxes' centres are quantised to a 1024³ grid over
 * their bounds and ordered along its Morton (Z-order) curve by a radix
 * sort; a node splits its range where the curve leaves the half of the
 * grid cell its codes share (the highest bit in which its first and last
 * codes differ), or in the middle when they are all equal; leaves of at
 * most GEO_FBVH_LEAF items. Its depth is at most 30 + log2 n. A box with
 * a NaN centre goes to the grid's first cell.
 *
 * Boxes: the grid has cubic cells, GEO_FBVH_CELLS of them along the
 * longest side of the box around every finite bound; each bound maps to
 * g(x) = (x − origin)·scale, clamped to [0, GEO_FBVH_CELLS], lo taken
 * down (floor) and hi up (ceil). g is monotone (a correctly rounded
 * subtraction and product by a positive constant are), so lo ≤ hi'
 * implies floor(g(lo)) ≤ g(lo) ≤ g(hi') ≤ ceil(g(hi')): two items whose
 * exact boxes overlap overlap here too. Two may overlap here and not
 * exactly (within a cell). Boxes only prune; the caller's exact test
 * decides. A box with a NaN bound becomes the empty box (lo
 * GEO_FBVH_CELLS + 1 and hi 0 on every axis): it overlaps nothing, as
 * in a geo_bvh, and a union ignores it.
 *
 * Node layout as geo_bvh's: nodes[0] is the root; an internal node's
 * children are nodes[child] and nodes[child + 1]; a leaf (count > 0)
 * holds items[child .. child + count − 1], boxes[k] the box of items[k].
 *
 * Ownership: build allocates, geo_fbvh_free releases. Queries are
 * read-only and thread-safe on a finished hierarchy. */
#ifndef GEO_FBVH_H
#define GEO_FBVH_H

#include <stdbool.h>
#include <stdint.h>

#include "bvh.h"

#define GEO_FBVH_LEAF 16
#define GEO_FBVH_CELLS 65534

typedef struct geo_qbox {
    uint16_t lo[3], hi[3];
} geo_qbox;

typedef struct geo_fbvh_node {
    geo_qbox box;
    uint32_t child; /* first child (internal) or first item slot (leaf) */
    uint32_t count; /* 0 for internal nodes, else the leaf's item count */
} geo_fbvh_node;

typedef struct geo_fbvh {
    uint32_t nnodes, nitems;
    geo_fbvh_node *nodes; /* nnodes; nodes[0] is the root (if nitems > 0) */
    uint32_t *items;      /* nitems item indices in leaf order */
    geo_qbox *boxes;      /* nitems: boxes[k] is the box of items[k];
                             then a spare slot (an empty box) */
    double origin[3], scale; /* the grid: g(x) = (x − origin)·scale */
    /* Optional, the caller's (NULL: none): three tags per item slot, in
     * leaf order (tags[k] for items[k]); a pair of items with a tag in
     * common is not reported. The caller gives each item's tags values no
     * other item can hold where a pair must be reported. */
    const uint32_t (*tags)[3];
} geo_fbvh;

/* The grid box of b in h's grid (as the build stores an item's). */
void geo_fbvh_quantize(const geo_fbvh *h, const geo_bbox *b, geo_qbox *ret);

/* Builds the hierarchy over n boxes (rounded outward, in leaf order).
 * NULL on out-of-memory (err set). */
geo_fbvh *geo_fbvh_build(const geo_bbox *boxes, uint32_t n, geo_err *err);

/* geo_fbvh_build over the facets of p (their boxes computed where
 * needed, never all at once in double precision). */
geo_fbvh *geo_fbvh_build_facets(const geo_poly *p, geo_err *err);

/* Releases h; accepts NULL; returns NULL. */
geo_fbvh *geo_fbvh_free(geo_fbvh *h);

/* Visits every unordered pair (a, b), a ≠ b, of items whose stored boxes
 * overlap and (with tags) which share no tag, below node pair (na, nb);
 * na == nb enumerates the pairs within one subtree. Each pair is reported
 * once. As geo_bvh_pairs. */
bool geo_fbvh_pairs(const geo_fbvh *h, uint32_t na, uint32_t nb,
                    geo_bvh_pair_fn visit, void *user);

/* Splits the self-pair search of the whole tree into up to cap
 * independent node pairs, as geo_bvh_pair_tasks. */
uint32_t geo_fbvh_pair_tasks(const geo_fbvh *h, uint32_t *ret_a,
                             uint32_t *ret_b, uint32_t cap);

#endif
