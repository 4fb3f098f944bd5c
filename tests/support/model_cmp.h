/* model_cmp.h — comparing two polyhedra in tests (round trips through the
 * model formats). */
#ifndef FACET_MODEL_CMP_H
#define FACET_MODEL_CMP_H

#include <stdbool.h>
#include <stddef.h>

#include "poly.h"

/* True when a and b have the same counts and facet index lists, vertex
 * coordinates within vtol of each other (vtol 0: bit for bit, the sign of
 * zero included) and planes within ptol (ptol < 0: planes not compared).
 * Otherwise false, with the first difference described in why (size n). */
bool tu_poly_same(const geo_poly *a, const geo_poly *b, double vtol,
                  double ptol, char *why, size_t n);

#endif
