/* tu_load.c — loading the sample models in tests and benchmarks through
 * the project's own reader (proto/model_io.h). */
#include "tu_load.h"

#include <stdio.h>

#include "model_io.h"
#include "testutil.h"

geo_poly *tu_load_model(const char *name)
{
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(tu_model_path(name),
                                        PROTO_FMT_UNKNOWN, NULL, &err);
    if (!p)
        fprintf(stderr, "%s\n", err.msg);
    return p;
}
