/* gen_sphere.h — a finely subdivided sphere for tests and benchmarks: a
 * cube whose six faces carry an n×n grid (equal-angle spacing), projected
 * onto the sphere, each cell split into two triangles: 12·n² triangles,
 * 6·n² + 2 vertices, closed, outward, free of self-intersections. */
#ifndef FACET_GEN_SPHERE_H
#define FACET_GEN_SPHERE_H

#include <stdint.h>

#include "poly.h"

/* The sphere of the given radius about the origin; planes by least
 * squares. NULL on out-of-memory. */
geo_poly *gs_sphere(uint32_t n, double radius);

#endif
