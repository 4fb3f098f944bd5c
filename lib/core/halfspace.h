/* halfspace.h — the exact intersection of half-spaces as a convex
 * polyhedron.
 *
 * Input: n planes a·x+b·y+c·z+d (four doubles each, taken as exact;
 * normals of any non-zero length); the region kept is plane(x) ≤ 0 for
 * all of them. Output: the closed convex polyhedron bounding that region
 * (poly.h), facets counter-clockwise seen from outside, each facet's
 * plane the input plane normalised to a unit normal, vertices in mm.
 *
 * Topology is exact: every vertex is the meet of three input planes, and
 * which side of a plane a vertex lies on — including exactly on it — is
 * decided by geo_plane_meet_sign (predicates.h) on the plane coefficients,
 * never on rounded coordinates. So a point where many planes meet (the
 * culet of a brilliant, a girdle corner on four facets) is one vertex,
 * a plane through an existing vertex or edge splits nothing, and
 * duplicated or redundant planes leave no facet. Only the output
 * coordinates are rounded: each vertex is solved in doubles from the best
 * conditioned triple of the facets meeting there.
 *
 * Facet order follows the input plane order; ret_source maps each facet
 * to its input plane. Costs O(n · V) time for V vertices.
 *
 * All functions are reentrant and thread-safe. */
#ifndef GEO_HALFSPACE_H
#define GEO_HALFSPACE_H

#include <stdint.h>

#include "ctx.h"
#include "poly.h"

/* The default contraction length, relative (see above): far above the
 * rounding of coordinates, far below any edge a cutter or scanner makes. */
#define GEO_HALFSPACE_MERGE 1e-9

/* Why an intersection failed (besides -ENOMEM). */
enum geo_halfspace_status {
    GEO_HALFSPACE_OK = 0,
    GEO_HALFSPACE_BAD_PLANE, /* a plane with a zero or non-finite coefficient
                                vector */
    GEO_HALFSPACE_EMPTY,     /* the planes bound nothing: the region is empty
                                or flat (no interior) */
    GEO_HALFSPACE_UNBOUNDED, /* the region is unbounded (or reaches farther
                                than 1e6 × the largest plane offset) */
};

/* Intersects the half-spaces planes[4i..4i+3] (x) ≤ 0, i < n, with
 * edges shorter than merge_tol mm contracted (see above).
 * On success returns 0, *ret the new polyhedron (the caller frees it with
 * geo_poly_free) and, when ret_source is non-NULL, *ret_source a malloc'd
 * array of (*ret)->nfacets input plane indices (the caller frees it).
 * On failure returns -EINVAL (see *ret_status, may be NULL) with err
 * naming the plane ("planes[7]: ...") or the reason ("the planes bound
 * nothing", "the planes do not bound the region: it is unbounded towards
 * +x"), or -ENOMEM; ret and ret_source are left untouched. */
int geo_halfspace_intersect(const double *planes, uint32_t n,
                            double merge_tol, geo_poly **ret,
                            uint32_t **ret_source,
                            enum geo_halfspace_status *ret_status,
                            geo_err *err);

#endif
