/* tu_load.c — a small facet-model/1 reader for the tests: vertices and
 * facets (vertex cycles, optional planes) into geo_poly_from_arrays. */
#include "tu_load.h"

#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>

#include "testutil.h"

static geo_poly *from_json(const json_t *root, geo_err *err)
{
    const json_t *jv = json_object_get(root, "vertices");
    const json_t *jf = json_object_get(root, "facets");
    if (!json_is_array(jv) || !json_is_array(jf)) {
        geo_err_set(err, -1, "missing vertices or facets");
        return NULL;
    }
    size_t nv = json_array_size(jv), nf = json_array_size(jf), nc = 0;
    for (size_t f = 0; f < nf; f++)
        nc += json_array_size(
            json_object_get(json_array_get(jf, f), "vertices"));
    double *xyz = malloc((3 * nv + 1) * sizeof *xyz);
    double *planes = malloc((4 * nf + 1) * sizeof *planes);
    uint32_t *start = malloc((nf + 1) * sizeof *start);
    uint32_t *idx = malloc((nc + 1) * sizeof *idx);
    geo_poly *p = NULL;
    bool have_planes = true, ok = xyz && planes && start && idx;
    for (size_t i = 0; ok && i < nv; i++) {
        const json_t *v = json_array_get(jv, i);
        for (size_t k = 0; k < 3; k++) {
            const json_t *c = json_array_get(v, k);
            ok = ok && json_is_number(c);
            xyz[3 * i + k] = json_number_value(c);
        }
    }
    size_t c = 0;
    for (size_t f = 0; ok && f < nf; f++) {
        const json_t *jo = json_array_get(jf, f);
        const json_t *vi = json_object_get(jo, "vertices");
        const json_t *pl = json_object_get(jo, "plane");
        start[f] = (uint32_t)c;
        for (size_t k = 0; k < json_array_size(vi); k++)
            idx[c++] = (uint32_t)json_integer_value(json_array_get(vi, k));
        if (json_array_size(pl) == 4)
            for (size_t k = 0; k < 4; k++)
                planes[4 * f + k] = json_number_value(json_array_get(pl, k));
        else
            have_planes = false;
    }
    start[nf] = (uint32_t)c;
    if (ok)
        p = geo_poly_from_arrays((uint32_t)nv, xyz, (uint32_t)nf, start, idx,
                                 have_planes ? planes : NULL, err);
    else
        geo_err_set(err, -1, "malformed vertices");
    free(xyz);
    free(planes);
    free(start);
    free(idx);
    return p;
}

geo_poly *tu_load_model(const char *name)
{
    const char *path = tu_model_path(name);
    json_error_t jerr;
    json_t *root = json_load_file(path, 0, &jerr);
    if (!root) {
        fprintf(stderr, "%s:%d: %s\n", path, jerr.line, jerr.text);
        return NULL;
    }
    geo_err err = {{0}};
    geo_poly *p = from_json(root, &err);
    json_decref(root);
    if (!p)
        fprintf(stderr, "%s: %s\n", path, err.msg);
    return p;
}
