/* surface.h — nearest-facet queries on a polyhedral surface: the distance
 * from any point to the surface and the facet that realises it, for the
 * Hausdorff estimate, comparisons of two models and the deviation of a
 * raw scan from a corrected model.
 *
 * The distance is exact up to rounding (nearest point inside the polygon,
 * on an edge or at a vertex). Candidates come from a BVH over the facets,
 * nearest box first; convex facets above 32 vertices are searched as
 * their fans of triangles (same distance, no O(n) walk of a large facet
 * per query). A query costs O(log F) for points near the surface.
 *
 * A built surface is read-only: concurrent queries are safe, each with
 * its own hint. Distances in the model's units (mm). */
#ifndef GEO_SURFACE_H
#define GEO_SURFACE_H

#include <stdint.h>

#include "ctx.h"
#include "poly.h"

typedef struct geo_surface geo_surface;

/* *ret = the index of b (valid indices and planes, at least one facet);
 * b must stay unchanged while the surface is used. 0, or -EINVAL (no
 * facets) / -ENOMEM with err set and *ret NULL. */
int geo_surface_new(const geo_poly *b, geo_surface **ret, geo_err *err);

void geo_surface_free(geo_surface *s);

/* Every facet of b once, in the order of the surface's leaves (near
 * facets near each other: queries from points in this order keep their
 * hint tight), into order (b->nfacets entries, caller-allocated). */
void geo_surface_facet_order(const geo_surface *s, uint32_t *order);

/* Squared distance from p to the surface. *hint (UINT32_MAX at first) is
 * the previous query's nearest piece: queries in surface order start from
 * a tight bound. facet (may be NULL) receives the index in b of the
 * nearest facet. */
double geo_surface_dist2(const geo_surface *s, const double p[3],
                         uint32_t *hint, uint32_t *facet);

/* For the largest of many distances: the squared distance from p when it
 * is above floor2, else some value in [it, floor2] (the search stops at
 * the first facet within floor2, which cannot raise a maximum already
 * at floor2: Taha & Hanbury's early break). *hint as above. */
double geo_surface_dist2_above(const geo_surface *s, const double p[3],
                               double floor2, uint32_t *hint);

#endif
