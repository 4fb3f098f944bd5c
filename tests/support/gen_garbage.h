/* gen_garbage.h — random "garbage" polyhedra for the inspection tests:
 * random facets of 3–7 indices over 4–15 vertices on a 3×3×3 grid, so
 * that non-manifold edges, coincident and collinear points, degenerate
 * and self-intersecting facets all occur. */
#ifndef TEST_GEN_GARBAGE_H
#define TEST_GEN_GARBAGE_H

#include <stdint.h>

#include "poly.h"

/* One such model from the generator state *rng (advanced), planes fitted
 * unweighted; NULL on out-of-memory. The caller frees it. */
geo_poly *gen_garbage_model(uint64_t *rng);

#endif
