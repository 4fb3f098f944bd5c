/* hausdorff.h — how far apart two polyhedral surfaces are: an estimate of
 * the Hausdorff distance, for reporting how much a correction changed a
 * model.
 *
 * The directed distance from A to B is the largest distance from a
 * sample point of A's surface to B's surface; samples are the vertices of
 * A's facets, the midpoints of their edges and their vertex centroids.
 * The distance of a point to B is exact up to rounding (surface.h: a BVH
 * over B's facets searched nearest box first), so the cost is
 * O((V + E + F) log F). The symmetric estimate is
 * the larger of the two directions; it can only underestimate the true
 * Hausdorff distance (the maximum may fall between samples), by at most
 * the sampled surface's largest facet diameter in the worst case and far
 * less for the nearly identical surfaces it is used on.
 *
 * Distances in mm. Pure functions, reentrant. */
#ifndef GEO_HAUSDORFF_H
#define GEO_HAUSDORFF_H

#include "ctx.h"
#include "poly.h"

/* Directed estimate from a to b (both with valid indices, b non-empty).
 * 0 and *ret set, or -EINVAL (b has no facets) / -ENOMEM with err set. */
int geo_hausdorff_directed(const geo_poly *a, const geo_poly *b, double *ret,
                           geo_err *err);

/* Symmetric estimate: max of both directions. Errors as above. */
int geo_hausdorff(const geo_poly *a, const geo_poly *b, double *ret,
                  geo_err *err);

/* The same, stopping with -ECANCELED when ctx (may be NULL) is canceled:
 * a large non-convex facet makes each sample near it cost O(its size). */
int geo_hausdorff_ctx(const geo_poly *a, const geo_poly *b,
                      const geo_ctx *ctx, double *ret, geo_err *err);

#endif
