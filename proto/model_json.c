/* model_json.c — facet-model/1 (formats.md): the JSON form of a
 * polyhedron, read through jansson and written directly as text.
 *
 * Reading: the text is parsed with JSON_REJECT_DUPLICATES (jansson also
 * rejects NaN/Infinity literals and numbers that overflow a double), then
 * the value is validated strictly, every error naming its place
 * ("facets[12].vertices[3]: index 9001 out of range (8000 vertices)").
 * "format" is required and must be "facet-model/1": the contract is
 * versioned by that key, so a model without it cannot be told apart from
 * a later version. "units" is optional and must be "mm" when present.
 * Unknown keys are ignored. Counts are checked against the limits before
 * the model is allocated.
 *
 * Writing: one vertex and one facet per line, every double printed as the
 * shortest decimal that reads back to the same double, so a write/read
 * cycle reproduces the model bit for bit (negative zero included). */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "model_codec.h"

#define FORMAT_NAME "facet-model/1"

static int number_at(const json_t *v, double *ret, geo_err *err,
                     const char *what, uint32_t i, uint32_t k)
{
    if (!json_is_number(v))
        return geo_err_set(err, -EINVAL, "%s[%u][%u]: expected a number",
                           what, i, k);
    double d = json_number_value(v);
    if (!isfinite(d))
        return geo_err_set(err, -EINVAL, "%s[%u][%u]: not a finite number",
                           what, i, k);
    *ret = d;
    return 0;
}

static int read_header(const json_t *root, geo_err *err)
{
    if (!json_is_object(root))
        return geo_err_set(err, -EINVAL, "expected a JSON object");
    const json_t *fmt = json_object_get(root, "format");
    if (!fmt)
        return geo_err_set(err, -EINVAL,
                           "format: missing (expected \"" FORMAT_NAME "\")");
    if (!json_is_string(fmt))
        return geo_err_set(err, -EINVAL, "format: expected a string");
    if (strcmp(json_string_value(fmt), FORMAT_NAME) != 0)
        return geo_err_set(err, -EINVAL,
                           "format: \"%.100s\" is not supported (expected \""
                           FORMAT_NAME "\")", json_string_value(fmt));
    const json_t *units = json_object_get(root, "units");
    if (units) {
        if (!json_is_string(units))
            return geo_err_set(err, -EINVAL, "units: expected a string");
        if (strcmp(json_string_value(units), "mm") != 0)
            return geo_err_set(err, -EINVAL,
                               "units: \"%.100s\" is not supported (only "
                               "\"mm\")", json_string_value(units));
    }
    return 0;
}

static int read_vertices(const json_t *arr, geo_poly *p, geo_err *err)
{
    for (uint32_t i = 0; i < p->nverts; i++) {
        const json_t *v = json_array_get(arr, i);
        if (!json_is_array(v) || json_array_size(v) != 3)
            return geo_err_set(err, -EINVAL,
                               "vertices[%u]: expected an array of 3 numbers",
                               i);
        for (uint32_t k = 0; k < 3; k++) {
            int r = number_at(json_array_get(v, k), &p->verts[i][k], err,
                              "vertices", i, k);
            if (r < 0)
                return r;
        }
    }
    return 0;
}

/* First pass over the facets: their shapes, and the corner count that the
 * limits are checked against before anything is allocated. */
static int count_corners(const json_t *arr, uint32_t nf, uint64_t *ret,
                         geo_err *err)
{
    uint64_t nc = 0;
    for (uint32_t f = 0; f < nf; f++) {
        const json_t *fo = json_array_get(arr, f);
        if (!json_is_object(fo))
            return geo_err_set(err, -EINVAL, "facets[%u]: expected an object",
                               f);
        const json_t *iv = json_object_get(fo, "vertices");
        if (!iv)
            return geo_err_set(err, -EINVAL, "facets[%u].vertices: missing",
                               f);
        if (!json_is_array(iv))
            return geo_err_set(err, -EINVAL,
                               "facets[%u].vertices: expected an array", f);
        nc += json_array_size(iv);
    }
    *ret = nc;
    return 0;
}

static int read_facet(const json_t *fo, uint32_t f, geo_poly *p, bool *given,
                      geo_err *err)
{
    const json_t *iv = json_object_get(fo, "vertices");
    size_t n = json_array_size(iv);
    if (n < 3)
        return geo_err_set(err, -EINVAL,
                           "facets[%u].vertices: %zu vertices, a facet needs "
                           "at least 3", f, n);
    uint32_t *dst = p->fidx + p->fstart[f];
    for (uint32_t i = 0; i < n; i++) {
        const json_t *x = json_array_get(iv, i);
        if (!json_is_integer(x))
            return geo_err_set(err, -EINVAL,
                               "facets[%u].vertices[%u]: expected an integer",
                               f, i);
        json_int_t v = json_integer_value(x);
        if (v < 0 || v >= (json_int_t)p->nverts)
            return geo_err_set(err, -EINVAL,
                               "facets[%u].vertices[%u]: index %" JSON_INTEGER_FORMAT
                               " out of range (%u vertices)", f, i, v,
                               p->nverts);
        dst[i] = (uint32_t)v;
    }
    for (uint32_t i = 0; i < n; i++) {
        uint32_t j = (uint32_t)((i + 1) % n);
        if (dst[i] == dst[j])
            return geo_err_set(err, -EINVAL,
                               "facets[%u].vertices[%u]: index %u repeated "
                               "consecutively", f, j, dst[i]);
    }
    p->fstart[f + 1] = p->fstart[f] + (uint32_t)n;
    const json_t *pl = json_object_get(fo, "plane");
    given[f] = pl != NULL;
    if (!pl)
        return 0;
    if (!json_is_array(pl) || json_array_size(pl) != 4)
        return geo_err_set(err, -EINVAL,
                           "facets[%u].plane: expected an array of 4 numbers",
                           f);
    for (uint32_t k = 0; k < 4; k++) {
        const json_t *x = json_array_get(pl, k);
        if (!json_is_number(x))
            return geo_err_set(err, -EINVAL,
                               "facets[%u].plane[%u]: expected a number", f, k);
        p->planes[f][k] = json_number_value(x);
        if (!isfinite(p->planes[f][k]))
            return geo_err_set(err, -EINVAL,
                               "facets[%u].plane[%u]: not a finite number", f,
                               k);
    }
    return 0;
}

geo_poly *proto_json_from_value(const json_t *root, const proto_limits *lim,
                                proto_read_report *rep, geo_err *err)
{
    if (read_header(root, err) < 0)
        return NULL;
    const json_t *va = json_object_get(root, "vertices");
    const json_t *fa = json_object_get(root, "facets");
    if (!va) {
        geo_err_set(err, -EINVAL, "vertices: missing");
        return NULL;
    }
    if (!json_is_array(va)) {
        geo_err_set(err, -EINVAL, "vertices: expected an array");
        return NULL;
    }
    if (!fa) {
        geo_err_set(err, -EINVAL, "facets: missing");
        return NULL;
    }
    if (!json_is_array(fa)) {
        geo_err_set(err, -EINVAL, "facets: expected an array");
        return NULL;
    }
    size_t nv = json_array_size(va), nf = json_array_size(fa);
    if (proto_check_limits(lim, nv, nf, 0, err) < 0)
        return NULL;
    uint64_t nc = 0;
    if (count_corners(fa, (uint32_t)nf, &nc, err) < 0 ||
        proto_check_limits(lim, nv, nf, nc, err) < 0)
        return NULL;

    geo_poly *p = geo_poly_new();
    bool *given = malloc(nf ? nf : 1);
    if (!p || !given || geo_poly_reserve(p, nv, nf, nc) < 0) {
        geo_err_set(err, -ENOMEM, "out of memory");
        goto fail;
    }
    p->nverts = (uint32_t)nv;
    if (read_vertices(va, p, err) < 0)
        goto fail;
    for (uint32_t f = 0; f < nf; f++) {
        if (read_facet(json_array_get(fa, f), f, p, given, err) < 0)
            goto fail;
        p->nfacets = f + 1;
    }
    proto_finish_planes(p, given, rep);
    free(given);
    return p;
fail:
    free(given);
    return geo_poly_free(p);
}

geo_poly *proto_json_read(const void *data, size_t len,
                          const proto_limits *lim, proto_read_report *rep,
                          geo_err *err)
{
    json_error_t je;
    json_t *root = json_loadb(data, len, JSON_REJECT_DUPLICATES, &je);
    if (!root) {
        geo_err_set(err, -EINVAL, "line %d, column %d: %s", je.line,
                    je.column, je.text);
        return NULL;
    }
    geo_poly *p = proto_json_from_value(root, lim, rep, err);
    json_decref(root);
    return p;
}

int proto_json_write(const geo_poly *p, proto_buf *b, geo_err *err)
{
    proto_buf_puts(b, "{\"format\":\"" FORMAT_NAME "\",\"units\":\"mm\",\n"
                      "\"vertices\":[\n");
    for (uint32_t i = 0; i < p->nverts; i++) {
        proto_buf_puts(b, "[");
        for (int k = 0; k < 3; k++) {
            if (k)
                proto_buf_puts(b, ",");
            proto_buf_double(b, p->verts[i][k]);
        }
        proto_buf_puts(b, i + 1 < p->nverts ? "],\n" : "]\n");
    }
    proto_buf_puts(b, "],\n\"facets\":[\n");
    for (uint32_t f = 0; f < p->nfacets; f++) {
        proto_buf_puts(b, "{\"vertices\":[");
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *v = geo_poly_facet(p, f);
        for (uint32_t i = 0; i < n; i++)
            proto_buf_printf(b, i ? ",%u" : "%u", v[i]);
        proto_buf_puts(b, "],\"plane\":[");
        for (int k = 0; k < 4; k++) {
            if (k)
                proto_buf_puts(b, ",");
            proto_buf_double(b, p->planes[f][k]);
        }
        proto_buf_puts(b, f + 1 < p->nfacets ? "]},\n" : "]}\n");
    }
    proto_buf_puts(b, "]}\n");
    (void)err;
    return 0;
}

/* Coordinates and planes become JSON reals, which jansson prints with 17
 * significant digits: exact on a round trip. */
json_t *proto_model_to_json(const geo_poly *p)
{
    json_t *root = json_object(), *va = json_array(), *fa = json_array();
    if (!root || !va || !fa)
        goto fail;
    if (json_object_set_new(root, "format", json_string(FORMAT_NAME)) < 0 ||
        json_object_set_new(root, "units", json_string("mm")) < 0)
        goto fail;
    for (uint32_t i = 0; i < p->nverts; i++) {
        json_t *v = json_pack("[ooo]", json_real(p->verts[i][0]),
                              json_real(p->verts[i][1]),
                              json_real(p->verts[i][2]));
        if (!v || json_array_append_new(va, v) < 0)
            goto fail;
    }
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *v = geo_poly_facet(p, f);
        json_t *iv = json_array();
        if (!iv)
            goto fail;
        for (uint32_t i = 0; i < n; i++)
            if (json_array_append_new(iv, json_integer(v[i])) < 0) {
                json_decref(iv);
                goto fail;
            }
        const double *pl = p->planes[f];
        json_t *fo = json_pack("{s:o,s:[oooo]}", "vertices", iv, "plane",
                               json_real(pl[0]), json_real(pl[1]),
                               json_real(pl[2]), json_real(pl[3]));
        if (!fo || json_array_append_new(fa, fo) < 0)
            goto fail;
    }
    if (json_object_set_new(root, "vertices", va) < 0) {
        va = NULL;
        goto fail;
    }
    va = NULL;
    if (json_object_set_new(root, "facets", fa) < 0) {
        fa = NULL;
        goto fail;
    }
    return root;
fail:
    json_decref(va);
    json_decref(fa);
    json_decref(root);
    return NULL;
}
