/* inside.h — point in polyhedron ("Tests of graphic elements"): the bounding-box test gab3,
 * the convex test conv3_test, the random-ray parity test with the paper's
 * three rules, the generalized winding number, and batch classification.
 *
 * Answers use the paper's convention (conv3_test): GEO_LOC_INSIDE = −1,
 * GEO_LOC_BOUNDARY = 0, GEO_LOC_OUTSIDE = 1.
 *
 * The surface. A facet is read as the fan of triangles (v0, vi, vi+1) from
 * its first vertex. Counted with signs, the fan covers an exactly planar
 * polygon once inside and zero times outside, even a non-convex one, so
 * ray crossings counted on fan triangles are the polygon's; for a facet
 * whose vertices are not exactly coplanar (a scanned model's, within
 * geo_poly_eps) the fan is the surface. Every decision — which side of a
 * triangle's plane, does a segment pass through a triangle, does a point
 * lie on a facet — is an exact sign (lib/core/predicates.h), so answers are
 * exact for the given doubles, including points exactly on facets, edges
 * or vertices (GEO_LOC_BOUNDARY) and points one ulp off them.
 *
 * Degeneracies. A ray that passes exactly through an edge or a vertex of a
 * fan triangle, or that runs inside a triangle's plane, is detected exactly
 * (an orient3d of zero) and shot again in another seeded random direction
 * (the ray test of "Tests of graphic elements": "re-shoot"); a point on a facet's plane but off the
 * facet is not a degeneracy. The first ray a batch casts runs along +x
 * through a 2D grid of the fan triangles' yz boxes; only when that ray
 * is degenerate is the point handed to the random-ray test.
 *
 * What the methods need. The ray tests decide by parity ("Tests of graphic elements",
 * ray test, rules 1–2) and are right for closed surfaces, whatever the facet orientation.
 * For open or dirty models (holes, gaps) parity depends on the ray; the
 * generalized winding number (sum of the fan triangles' solid angles over
 * 4π) degrades gracefully there: inside when it is ≥ 1/2 (Jacobson et
 * al. 2013), which needs outward-listed facets.
 *
 * A geo_inside borrows the geo_poly it was built from: the model must
 * outlive it and must not change meanwhile. All queries are read-only and
 * thread-safe; geo_inside_classify runs chunks of points through the
 * caller's parallel_for and its results do not depend on the number of
 * threads. */
#ifndef GEO_INSIDE_H
#define GEO_INSIDE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "bvh.h"
#include "ctx.h"
#include "poly.h"

enum geo_loc {
    GEO_LOC_INSIDE = -1,
    GEO_LOC_BOUNDARY = 0,
    GEO_LOC_OUTSIDE = 1,
};

/* gab3_test: true when q lies outside the closed box (certainly outside
 * any polyhedron inside the box). A NaN coordinate counts as outside. */
bool geo_gab3_test(const geo_bbox *box, const double q[3]);

/* conv3_test ("Tests of graphic elements") for a convex model listed outward: GEO_LOC_INSIDE
 * when q is strictly below every facet's plane, GEO_LOC_OUTSIDE when it is
 * strictly above some facet's plane, else GEO_LOC_BOUNDARY. The planes are
 * the facets' reference corners (classify.h: geo_nf_facet_sign); exact.
 * Stops at the first facet above. O(nfacets). Meaningless for non-convex
 * models. */
int geo_conv3_test(const geo_poly *p, const double q[3]);

/* True when q lies exactly on facet f: on one of its edges (closed
 * segments), or — for an exactly planar facet — in its plane and inside
 * the polygon (exact crossing test in the projection along the dominant
 * normal axis), or — for a facet that is not exactly planar — on one of
 * its fan triangles. O(facet size). */
bool geo_point_on_facet(const geo_poly *p, uint32_t f, const double q[3]);

/* The generalized winding number of the facets around q: Σ over fan
 * triangles of the signed solid angle (Van Oosterom–Strackee) / 4π.
 * 1 inside and 0 outside a closed model listed outward (up to rounding,
 * ~1e-13); between them where the surface has holes. Undefined (any value)
 * for q on the surface. O(corners), no allocation. */
double geo_winding_number(const geo_poly *p, const double q[3]);

/* A classifier prepared for one model: its box, a BVH of its facets and
 * the yz grid of the batch's +x rays. */
typedef struct geo_inside geo_inside;

/* Prepares p (borrowed: it must outlive the classifier, unchanged).
 * O(n log n). Returns NULL with err set on out-of-memory or when p has
 * invalid indices or non-finite coordinates (err names the place). */
geo_inside *geo_inside_new(const geo_poly *p, geo_err *err);

/* Releases ix (not the model); accepts NULL; returns NULL. */
geo_inside *geo_inside_free(geo_inside *ix);

/* The facets' bounding box (gab3's box). */
const geo_bbox *geo_inside_bbox(const geo_inside *ix);

/* Shots a ray test may take before it stops re-shooting; the answer then
 * comes from the generalized winding number (never observed: each
 * degeneracy is a set of directions of measure zero). */
#define GEO_INSIDE_MAX_SHOTS 64

/* The ray test of "Tests of graphic elements": gab3 first; then a segment from q in direction V =
 * (sin φ sin ψ, cos ψ, cos φ sin ψ), φ = rnd(2π), ψ = rnd(π), to beyond
 * the box, against every fan triangle whose facet box it meets (BVH).
 * Rule 3: q on a facet → GEO_LOC_BOUNDARY; rules 1–2: an odd number of
 * crossings → GEO_LOC_INSIDE, even or none → GEO_LOC_OUTSIDE; a
 * degenerate hit (through an edge or vertex, or along a plane) → a new
 * direction. dir0, if not NULL and not zero, is the direction of the
 * first shot (any length). *rng is the generator state (advanced).
 * *ret_shots, if not NULL, receives the number of rays cast (0 when gab3
 * decided). Exact; thread-safe with a separate rng per thread. */
int geo_inside_ray(const geo_inside *ix, const double q[3],
                   const double dir0[3], uint64_t *rng, unsigned *ret_shots);

/* Generalized winding number test: GEO_LOC_BOUNDARY when q lies exactly
 * on a facet (geo_point_on_facet over the facets whose box holds q), else
 * GEO_LOC_INSIDE when geo_winding_number ≥ 0.5, else GEO_LOC_OUTSIDE.
 * O(corners) per point. */
int geo_inside_winding(const geo_inside *ix, const double q[3]);

/* The batch's per-point test: gab3, then one +x ray over the yz grid
 * (exact; parity); when that ray is degenerate, geo_inside_ray with a
 * generator seeded by seed and q's coordinates (so a point's answer does
 * not depend on its position in a batch). Same answers as geo_inside_ray
 * on closed models. */
int geo_inside_point(const geo_inside *ix, const double q[3], uint64_t seed);

enum geo_inside_method {
    GEO_INSIDE_RAY = 0,     /* geo_inside_point: closed models */
    GEO_INSIDE_WINDING = 1, /* geo_inside_winding: open or dirty models */
};

/* Classifies n points (pts: n x,y,z triples, mm) into ret_loc[0..n)
 * (caller-allocated; enum geo_loc values) with the given method, in
 * chunks run through ctx->parallel_for (sequentially without one), with
 * ctx->seed for the re-shot rays. Reports progress and checks cancellation
 * between rounds of chunks. Returns 0; -EINVAL when a point is not finite
 * (err: "points[17]: coordinate is not finite"; nothing classified);
 * -ECANCELED (ret_loc partly filled). Results are identical for any
 * number of threads. */
int geo_inside_classify(const geo_inside *ix, const double (*pts)[3], size_t n,
                        enum geo_inside_method method, int8_t *ret_loc,
                        const geo_ctx *ctx, geo_err *err);

#endif
