/* fuzz_job_body.c — libFuzzer target: a POST /v1/jobs body taken apart
 * the way facetd does it (JSON with duplicate keys rejected, then the
 * pipeline, the model or the two meshes, the F-rep object). Property: no
 * crash, every refusal has a message, an accepted pipeline survives its
 * canonical JSON round trip and an accepted model keeps geo_poly's
 * invariants. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "frep_json.h"
#include "model_io.h"
#include "pipeline.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void check_pipeline(const json_t *v)
{
    proto_pipeline pl = {0};
    geo_err err = {{0}};
    if (proto_pipeline_from_json(v, "pipeline", &pl, &err) < 0) {
        if (err.msg[0] == '\0')
            abort();
        return;
    }
    json_t *canon = proto_pipeline_to_json(&pl);
    proto_pipeline again = {0};
    if (!canon || proto_pipeline_from_json(canon, "pipeline", &again, &err) < 0 ||
        again.nops != pl.nops)
        abort();
    json_t *canon2 = proto_pipeline_to_json(&again);
    if (!canon2 || !json_equal(canon, canon2))
        abort();
    json_decref(canon2);
    json_decref(canon);
    proto_pipeline_free(&again);
    proto_pipeline_free(&pl);
}

static void check_model(const json_t *v, const char *where)
{
    proto_limits lim;
    proto_limits_default(&lim);
    lim.max_vertices = 100000;
    lim.max_facets = 100000;
    lim.max_corners = 400000;
    proto_read_report rep = {0};
    geo_err err = {{0}};
    geo_poly *p = proto_model_from_json_ex(v, &lim, where, &rep, &err);
    if (!p) {
        if (err.msg[0] == '\0')
            abort();
        return;
    }
    if (geo_poly_validate_indices(p, NULL) < 0)
        abort();
    geo_poly_free(p);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    json_error_t je;
    json_t *root = json_loadb((const char *)data, size,
                              JSON_REJECT_DUPLICATES, &je);
    if (!root)
        return 0;
    if (json_is_object(root)) {
        const json_t *v;
        if ((v = json_object_get(root, "pipeline")))
            check_pipeline(v);
        if ((v = json_object_get(root, "model")))
            check_model(v, "model");
        const json_t *meshes = json_object_get(root, "meshes");
        for (size_t k = 0; k < json_array_size(meshes) && k < 2; k++) {
            char where[32];
            snprintf(where, sizeof where, "meshes[%zu]", k);
            check_model(json_array_get(meshes, k), where);
        }
        if ((v = json_object_get(root, "frep"))) {
            geo_err err = {{0}};
            geo_frep *f = proto_frep_from_json(v, NULL, "frep", &err);
            if (!f && err.msg[0] == '\0')
                abort();
            geo_frep_free(f);
        }
    } else {
        /* a bare pipeline, as `facet run` reads it */
        check_pipeline(root);
    }
    json_decref(root);
    return 0;
}
