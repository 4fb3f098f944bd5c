/* tu_load.h — loading the sample models in tests and benchmarks. */
#ifndef FACET_TU_LOAD_H
#define FACET_TU_LOAD_H

#include "poly.h"

/* Reads tests/data/models/NAME (see tu_model_path) with
 * proto_model_read_file; returns a new geo_poly or NULL, printing the
 * reason to stderr. */
geo_poly *tu_load_model(const char *name);

#endif
