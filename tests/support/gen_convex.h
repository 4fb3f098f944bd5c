/* gen_convex.h — random convex polyhedra for tests: the intersection of
 * random half-spaces, like a shadow-profile scanner's model (each facet a
 * convex polygon whose vertices are rounded three-plane intersections, so
 * facets are planar within rounding, not exactly).
 *
 * Self-contained (lib/ only); deterministic for a seed. */
#ifndef FACET_GEN_CONVEX_H
#define FACET_GEN_CONVEX_H

#include <stdint.h>

#include "poly.h"

/* A convex polyhedron around center: the six faces of the cube of
 * half-side 1.5·radius and nplanes half-spaces with uniformly random unit
 * normals at distances radius·[0.8, 1.2) from center. Samples where four
 * planes meet at a point or two vertices nearly coincide are redrawn, so
 * the result is simple: every vertex in exactly three facets. Facets are
 * listed counter-clockwise seen from outside; planes are the generating
 * ones (unit outward normal). Returns NULL on out-of-memory, or when no
 * clean sample was found in 100 draws (never seen). Free with
 * geo_poly_free. */
geo_poly *gen_convex_polyhedron(uint64_t seed, unsigned nplanes,
                                const double center[3], double radius);

#endif
