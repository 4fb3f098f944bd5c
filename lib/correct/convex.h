/* convex.h — correction of a convex scan by recovering the true facet
 * planes (docs/kernels/correct-convex.md).
 *
 * A shadow-profile scan (seed 000 §1.2) of a convex stone is the
 * intersection of silhouette half-spaces: each plane contains its view's
 * direction and, to the silhouette noise, one true edge of the stone, so a
 * true facet comes out as a fan of slivers hinged on its own edges and
 * tilted by up to about a view step. Averaging the slivers (the merge of
 * seed 000 §2.5) gives a plane tilted by a fraction of that step; the
 * hinges themselves lie on the true plane. So:
 *
 *  1. groups: the scan's facets are grouped into true facets, grown from
 *     the largest facet not yet in a group, each joining neighbour within
 *     the scan's own error (its surface noise and the roof its view step
 *     leaves) of the group's plane — the criterion of the merge's
 *     automatic groups (merge_groups.c), applied once to the raw scan;
 *  2. planes: each group's plane is fitted to the group's boundary — the
 *     edges it shares with other groups, where the slivers hinge on the
 *     true edges — by least squares over the boundary segments (each
 *     weighted by its length), with the segments that lie more than a few
 *     residual scales off rejected and the fit repeated (a boundary stretch
 *     no sliver hinges on lies outside the true plane);
 *  3. support: a group whose plane cuts the polytope of its neighbours'
 *     planes by no more than the scan's noise allows (a bevel strip along
 *     a true edge) is dropped;
 *  4. the result is the intersection of the kept half-spaces.
 *
 * Steps 1–3 are geo_convex_planes; geo_correct_convex runs them and step
 * 4 and checks the result (see there). Conventions of lib/core/poly.h; mm.
 * Reentrant; thread-safe on distinct models. */
#ifndef GEO_CONVEX_H
#define GEO_CONVEX_H

#include <stdint.h>

#include "ctx.h"
#include "poly.h"

typedef struct geo_convex_planes {
    uint32_t nplanes;     /* kept planes */
    double (*planes)[4];  /* nplanes unit outward planes */
    double *area;         /* nplanes: area of the scan facets of each */
    uint32_t ngroups;     /* groups found (kept or not) */
    uint32_t *group;      /* p->nfacets: group of each scan facet */
    uint32_t *kept;       /* ngroups: index into planes, or GEO_NONE */
    uint32_t dropped;     /* groups dropped as unsupported (step 3) */
} geo_convex_planes;

/* Releases the arrays and zeroes r; accepts NULL. */
void geo_convex_planes_clear(geo_convex_planes *r);

/* Steps 1–3 above on p, which must be a closed, outward, manifold model
 * (a raw convex scan; other models give planes too, meaningless ones).
 * views: the scanner's views over 180° (geo_merge_view_grid), 0 when not
 * known (no roof term); noise: the scan's surface noise in mm
 * (geo_merge_surface_noise), 0 for none. ret is filled (arrays malloc'd,
 * free with geo_convex_planes_clear). Returns 0, -EINVAL (p not closed
 * and manifold; err says so), -ENOMEM (ret zeroed). */
int geo_convex_planes_find(const geo_poly *p, uint32_t views, double noise,
                           geo_convex_planes *ret, geo_err *err);

#endif
