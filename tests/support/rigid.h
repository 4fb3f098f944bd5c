/* rigid.h — a model moved rigidly, for tests and benchmarks that need a
 * stone in another orientation and place (comparison, alignment). */
#ifndef TU_RIGID_H
#define TU_RIGID_H

#include "poly.h"

/* p's vertices and planes turned by deg degrees about axis (any
 * non-zero length, right-handed), then shifted by t. */
void tu_rigid_move(geo_poly *p, const double axis[3], double deg,
                   const double t[3]);

#endif
