/* fuzz_model.h — the property every model-reader fuzz target checks: any
 * input gives an error message or a model that keeps geo_poly's
 * invariants and survives an exact facet-model/1 round trip. Included by
 * the fuzz_model_*.c targets (one per format), each a libFuzzer entry
 * point LLVMFuzzerTestOneInput. */
#ifndef FACET_FUZZ_MODEL_H
#define FACET_FUZZ_MODEL_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "model_io.h"

static int fuzz_model(const uint8_t *data, size_t size, proto_format fmt)
{
    proto_limits lim;
    proto_limits_default(&lim);
    lim.max_vertices = 100000; /* keep each run small */
    lim.max_facets = 100000;
    lim.max_corners = 400000;
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_mem(data, size, fmt, &lim, &err);
    if (!p) {
        if (err.msg[0] == '\0')
            abort();
        return 0;
    }
    if (geo_poly_validate_indices(p, NULL) < 0)
        abort();
    for (uint32_t i = 0; i < p->nverts; i++)
        for (int k = 0; k < 3; k++)
            if (!isfinite(p->verts[i][k]))
                abort();
    char *buf;
    size_t len;
    if (proto_model_write_mem(p, PROTO_FMT_JSON, &buf, &len, &err) < 0)
        abort();
    geo_poly *q = proto_model_read_mem(buf, len, PROTO_FMT_JSON, NULL, &err);
    if (!q || q->nverts != p->nverts || q->nfacets != p->nfacets)
        abort();
    if (p->nverts &&
        memcmp(q->verts, p->verts, p->nverts * sizeof *p->verts) != 0)
        abort();
    if (geo_poly_ncorners(p) &&
        memcmp(q->fidx, p->fidx, geo_poly_ncorners(p) * sizeof *p->fidx) != 0)
        abort();
    free(buf);
    geo_poly_free(q);
    geo_poly_free(p);
    return 0;
}

#endif
