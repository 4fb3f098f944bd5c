/* merge_shapes.h — polyhedra and helpers for the facet-merging tests and
 * benchmark: a model whose merge group borders non-convex facets, the
 * search for groups of nearly coplanar neighbours in a scan, and a
 * validity check naming what is wrong. */
#ifndef FACET_MERGE_SHAPES_H
#define FACET_MERGE_SHAPES_H

#include <stdint.h>

#include "poly.h"

/* An L-shaped prism: the L (0,0) (3,0) (3,1) (1,1) (1,3) (0,3) in the xz
 * plane, extruded over y in [0, 1], so its front and back facets are
 * non-convex L's. Its bottom (z = 0) is split at x = 1.5 into two facets
 * whose common edge is lowered by dip (mm): two nearly coplanar facets
 * (at an angle of atan(dip / 1.5)) bordered by both non-convex L's.
 * The two bottom facets are facets 0 and 1. NULL on out-of-memory. */
geo_poly *ms_dipped_l_prism(double dip);

/* The box [0, size]³ whose edge along y at x = z = size is chamfered:
 * the chamfer meets the top (z = size) depth_top and the side (x = size)
 * depth_side from the edge, so its vertices lie depth_side from the side's
 * plane and depth_top from the top's. Facets: 0 bottom, 1 top, 2 front
 * (y = 0), 3 back, 4 left (x = 0), 5 side (x = size), 6 the chamfer.
 * NULL on out-of-memory. */
geo_poly *ms_chamfered_box(double size, double depth_top, double depth_side);

/* A connected set of n facets of p around seed (the seed first), each
 * sharing an edge with an earlier one and with a normal within max_deg of
 * the seed's; written to ret (room for n). Returns how many were found
 * (< n when the neighbourhood has fewer). */
uint32_t ms_coplanar_group(const geo_poly *p, uint32_t seed, double max_deg,
                           uint32_t n, uint32_t *ret);

/* NULL when geo_inspect finds p valid, else a description of what is
 * wrong (static buffer). */
const char *ms_invalid(const geo_poly *p);

#endif
