/* selfint.h — self-intersections of a polyhedron (spec algorithms.md §2):
 * every pair of facets that meet other than along their shared edges and
 * vertices, and every facet whose own polygon crosses or touches itself.
 *
 * What counts. Two facets F ≠ G "intersect" when the closed polygons have a
 * common point that is neither a vertex both of them list (same index) nor
 * a point of an edge both of them list. That covers an edge piercing a
 * facet, a vertex touching another facet (interior, edge or vertex of a
 * different index), coplanar facets that overlap or touch, adjacent facets
 * folded onto each other, two facets crossing along a diagonal, and
 * T-junctions (a vertex on another facet's edge). Facets that share a
 * vertex or an edge and otherwise stay apart do not count, whatever the
 * angle between them. Shared means the same vertex index: two vertices of
 * different index at one position are a contact (a pinch).
 *
 * Exactness model. Every decision is a sign of geo_orient3d/geo_orient2d
 * on input coordinates, never a tolerance, and never on a triangulation.
 * A facet is its polygon (vertex cycle), not its stored plane. Its
 * reference plane π_F passes exactly through three of its own vertices
 * (the reference triple: far apart, spanning the largest triangle found);
 * "side of π_F" is orient3d against that triple. A vertex the facet lists
 * counts as lying on π_F by definition, even when a slightly non-planar
 * facet puts it a rounding error off: shared vertices and edges therefore
 * never produce false contacts. Inside/outside questions are decided on
 * the facet's own vertices: for a segment pq that crosses π_F, outside
 * when pq and the polygon, both projected by dropping the dominant
 * coordinate of π_F's normal, have no point in common (the crossing
 * point projects onto pq), else the crossing point's winding number with
 * respect to the facet's polygon projected along pq (orient3d(p, q, vᵢ,
 * vᵢ₊₁) and two auxiliary planes through pq) — the first test keeps a
 * segment running nearly in π_F beside the polygon, like an edge of a
 * coplanar neighbour, from being read as crossing it where the polygon,
 * seen along pq, shrinks to a sliver of its non-planarity's width; for
 * points and segments lying on π_F, orient2d in the
 * projection that drops the dominant coordinate of π_F's normal. For an
 * exactly planar facet these are the exact answers; for a facet planar
 * within geo_poly_eps the polygon is interpreted, per query, as its
 * vertices projected onto π_F along the query direction, which moves its
 * outline by at most about the non-planarity divided by the sine of the
 * angle between the query and the facet.
 *
 * Degenerate facets (fewer than three distinct points, or all points on
 * one line: decided exactly) have no plane; they are flagged and left out
 * of the pair search.
 *
 * Complexity: O(n log n) for the BVH (built here unless given), then the
 * exact test of each pair of facets whose boxes overlap, O(|F|·|G|) at
 * worst for a coplanar pair and O(|F| + |G|) typically; own-polygon tests
 * by a sweep over the facet's edges. */
#ifndef GEO_SELFINT_H
#define GEO_SELFINT_H

#include <stdbool.h>
#include <stdint.h>

#include "bvh.h"
#include "ctx.h"
#include "poly.h"
#include "topo.h"

/* How a facet is looked at by the exact tests (see the model above). */
typedef struct geo_facet_shape {
    uint32_t ref[3];  /* vertex indices of the reference triple */
    int8_t axis;      /* coordinate (0, 1, 2) dropped for 2D decisions */
    int8_t turn;      /* +1 counter-clockwise, −1 clockwise: the polygon's
                         turn in that projection (axes in cyclic order, as
                         geo_orient2d_proj) */
    bool degenerate;  /* fewer than 3 distinct points or all collinear */
    bool simple;      /* the polygon does not touch or cross itself
                         (geo_facet_self_intersects is false) */
    bool convex;      /* simple and no reflex corner (flat ones allowed) */
} geo_facet_shape;

/* Fills *ret for facet f (f < p->nfacets, valid indices). The reference
 * triple is chosen in floating point and checked exactly; turn is decided
 * exactly at the facet's lexicographically lowest projected vertex (a
 * convex corner of a simple polygon), falling back to the Newell normal's
 * sign when that corner is flat; simple and convex are exact in the
 * projection (both false for a degenerate facet). Thread-safe; allocates
 * only for facets of more than 24 vertices (see
 * geo_facet_self_intersects). */
void geo_facet_shape_of(const geo_poly *p, uint32_t f, geo_facet_shape *ret);

/* True when facet f's own polygon touches or crosses itself: a vertex
 * index listed twice, two non-adjacent edges meeting, or adjacent edges
 * overlapping (a spike). Decided in the 2D projection of s. False for a
 * degenerate facet (reported as degenerate instead). O(n²) for small
 * facets, a sweep over edge extents for large ones (its scratch is
 * malloc'd; without memory the O(n²) loop gives the same answer). */
bool geo_facet_self_intersects(const geo_poly *p, uint32_t f,
                               const geo_facet_shape *s);

/* True when facets f ≠ g intersect other than along shared edges and
 * vertices (the definition above). sf, sg are their shapes. Returns false
 * when either is degenerate. Allocates only for facets of more than 64
 * vertices; returns -ENOMEM (negative) if that fails, 1 or 0 otherwise. */
int geo_facets_intersect(const geo_poly *p, uint32_t f, uint32_t g,
                         const geo_facet_shape *sf, const geo_facet_shape *sg);

/* Where segment ab meets facet f (shape s), exactly under the model
 * above, a and b being any points (not taken as the facet's vertices):
 * +1 when a and b lie strictly on opposite sides of the facet's plane and
 * the crossing point is strictly inside the polygon; 0 when the segment
 * touches the closed facet in any other way (an endpoint on it, a pass
 * through its boundary, a run along its plane over it); −1 when it misses
 * it, and for a degenerate facet. Used for ray parity (point in
 * polyhedron): 0 means "degenerate ray, shoot another". */
int geo_segment_meets_facet(const geo_poly *p, uint32_t f,
                            const geo_facet_shape *s, const double a[3],
                            const double b[3]);

/* Per-facet flags of geo_selfint.facet_flags. */
enum {
    GEO_SI_PAIR = 1,       /* the facet is in an intersecting pair */
    GEO_SI_SELF = 2,       /* its own polygon intersects itself */
    GEO_SI_DEGENERATE = 4, /* degenerate: no plane, not tested */
    GEO_SI_NONCONVEX = 8,  /* not degenerate and not convex (shape) */
};

typedef struct geo_selfint_opts {
    uint32_t max_pairs; /* pairs to list (the smallest in sorted order);
                           the count is always complete. Default 1000. */
    uint32_t max_tasks; /* parallel work units; default 1024 */
    const uint8_t *simple_fans; /* NULL (default), or per vertex of a mesh
                           of triangles geo_selfint_simple_fans' answer:
                           pairs of triangles that share a vertex marked
                           there are known to meet only where they share
                           and are not tested */
    bool indices_checked; /* false (default), or the caller has just
                           had geo_poly_validate_indices pass on p (the
                           search does not check them again) */
} geo_selfint_opts;

/* Fills the defaults. */
void geo_selfint_opts_default(geo_selfint_opts *o);

/* For each vertex of p (every facet a triangle; t its topology,
 * geo_topo_build or _lean) sets ret[v] (p->nverts bytes) to 1 when the
 * triangles around v meet only at v and along their shared edges, shown
 * exactly: v's facets form one closed fan, and dropping the coordinate
 * its normals share most, every triangle of the fan projects with the
 * same nonzero orientation and the fan winds once around v — then the
 * projections overlap only on the shared rays, and a triangle not
 * parallel to the dropped axis meets the line through v along it only
 * at v. Else 0 (the pair tests decide). */
void geo_selfint_simple_fans(const geo_poly *p, const geo_topo *t,
                             uint8_t *ret);

typedef struct geo_selfint {
    uint64_t count;       /* intersecting pairs f < g, plus one per facet
                             whose polygon intersects itself */
    uint32_t npairs;      /* listed pairs, min(count, max_pairs) */
    uint32_t (*pairs)[2]; /* npairs pairs (a, b), a ≤ b, sorted; a facet
                             intersecting itself is listed as (f, f) */
    uint32_t nfacets;     /* size of facet_flags */
    uint8_t *facet_flags; /* GEO_SI_* per facet */
    uint32_t nflagged;    /* facets with GEO_SI_PAIR or GEO_SI_SELF */
    uint32_t ndegenerate; /* facets with GEO_SI_DEGENERATE */
} geo_selfint;

/* Finds all self-intersections of p. bvh may be NULL (then one is built
 * over p's facets and freed), else it must be geo_bvh_build_facets(p).
 * opts NULL means defaults. Pair tests run through ctx->parallel_for;
 * the result is identical for any thread count. Progress is reported
 * from the calling thread only; cancellation is honoured within
 * milliseconds. On success *ret owns malloc'd arrays (release with
 * geo_selfint_clear) and 0 is returned; on error (-ENOMEM, -ECANCELED,
 * -EINVAL for invalid indices or a BVH whose item count is not p's facet
 * count) *ret is zeroed and err set. */
int geo_selfint_find(const geo_poly *p, const geo_bvh *bvh,
                     const geo_selfint_opts *opts, const geo_ctx *ctx,
                     geo_selfint *ret, geo_err *err);

/* Releases the arrays of r and zeroes it; accepts NULL. */
void geo_selfint_clear(geo_selfint *r);

#endif
