/* gen_convex.h — random convex polyhedra for tests: the intersection of
 * random half-spaces tangent to the unit sphere, clipped out of a cube.
 * Vertices are computed by interpolation along clipped edges, so facets
 * are planar to rounding (≈1e-16), like a scanner's models. */
#ifndef FACET_GEN_CONVEX_H
#define FACET_GEN_CONVEX_H

#include <stdint.h>

#include "poly.h"

/* The cube [-2, 2]³ cut by nplanes planes n·x = 1 with random unit
 * normals n (seeded), keeping n·x ≤ 1. Facets are counter-clockwise from
 * outside, planes are the exact cutting planes. Returns NULL on
 * out-of-memory. */
geo_poly *gc_random_convex(uint64_t seed, uint32_t nplanes);

/* Clips p in place by the half-space plane(x) ≤ 0 (plane a,b,c,d with a
 * unit normal), closing the cut with one new facet whose plane is `plane`.
 * p must be convex and closed. 0, or -ENOMEM. */
int gc_clip(geo_poly *p, const double plane[4]);

#endif
