/* tu_load.h — loading the sample models (facet-model/1 JSON) in tests and
 * benchmarks. */
#ifndef FACET_TU_LOAD_H
#define FACET_TU_LOAD_H

#include "poly.h"

/* Reads tests/data/models/NAME (see tu_model_path); returns a new
 * geo_poly (planes as stored, or fitted when absent) or NULL, printing the
 * reason to stderr. */
geo_poly *tu_load_model(const char *name);

#endif
