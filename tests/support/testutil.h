/* testutil.h — helpers shared by the unit tests: paths of the sample
 * models, small hand-built polyhedra and the seeded generator. */
#ifndef FACET_TESTUTIL_H
#define FACET_TESTUTIL_H

#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include "poly.h"

/* Directory of the sample models: $FACET_MODELS, else "tests/data/models"
 * if it exists, else "../shared/models". */
const char *tu_models_dir(void);

/* Path of a sample model file (static buffer, overwritten by next call). */
const char *tu_model_path(const char *name);

/* An axis-aligned box [lo, hi] as 6 quads, counter-clockwise outward. */
geo_poly *tu_box(const double lo[3], const double hi[3]);

/* The example polyhedron of "Tests of graphic elements", H = {P, G} (11 vertices, 7 facets). */
geo_poly *tu_seed003_example(void);

/* The sample models' notch cube (volume 936) built in code. */
geo_poly *tu_notch_cube(void);

/* geo_inspect's verdict on p: a valid closed solid (false also when the
 * inspection itself fails: bad indices, out of memory). */
bool tu_is_valid(const geo_poly *p);

#endif
