/* model_json.c — facet-model/1 (formats.md): the JSON form of a
 * polyhedron, read from text with the pull tokenizer (proto/json_pull.h)
 * or from a jansson value, and written directly as text.
 *
 * Reading: duplicate keys, NaN/Infinity and numbers that overflow a double
 * are JSON errors; the model is then validated strictly, every error
 * naming its place ("facets[12].vertices[3]: index 9001 out of range
 * (8000 vertices)"). "format" is required and must be "facet-model/1":
 * the contract is versioned by that key, so a model without it cannot be
 * told apart from a later version. "units" is optional and must be "mm"
 * when present. Unknown keys are ignored. Counts are checked against the
 * limits before the model is allocated (tree reader) or while it is
 * filled (streaming reader, which stops storing past a limit). Both
 * readers give the same first error for every document. The streaming
 * reader takes the layout facet writes straight from the bytes (its fast
 * path, below) and anything else token by token.
 *
 * Writing: one vertex and one facet per line, every double printed as the
 * shortest decimal that reads back to the same double, so a write/read
 * cycle reproduces the model bit for bit (negative zero included). */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "json_digits.h"
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
                               "facets[%u].vertices[%u]: index %lld out of "
                               "range (%u vertices)", f, i, (long long)v,
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

    bool *given = NULL;
    geo_poly *p = proto_poly_alloc(nv, nf, nc, &given, err);
    if (!p)
        return NULL;
    p->nverts = (uint32_t)nv;
    if (read_vertices(va, p, err) < 0)
        goto fail;
    for (uint32_t f = 0; f < nf; f++) {
        if (read_facet(json_array_get(fa, f), f, p, given, err) < 0)
            goto fail;
        p->nfacets = f + 1;
    }
    return proto_read_done(p, given, lim, rep, err);
fail:
    free(given);
    return geo_poly_free(p);
}

/* The streaming reader: one pass over the tokens fills the model's arrays
 * directly. Members may come in any order, so every check is recorded and
 * decided at the end in the order of the tree reader above (header,
 * "vertices"/"facets" types, counts, facet shapes, corner count, vertices,
 * facets), which gives the same first error for any document. Storing
 * stops once a count passes its limit (the limit is then the error), so
 * memory stays bounded by the limits whatever the input claims. */

enum { M_ABSENT = 0, M_WRONG_TYPE, M_WRONG_VALUE, M_OK };

typedef struct mread {
    proto_jpull *j;
    const proto_limits *lim;
    geo_poly *p;
    bool *given;
    size_t cap_given;
    int format, units;            /* M_* */
    char format_text[101], units_text[101];
    int vertices, facets;         /* M_ABSENT, M_WRONG_TYPE or M_OK */
    uint64_t nv, nf, nc;
    bool store_v, store_f;        /* still within the limits and shapes */
    bool oom;
    char verr[160];               /* the first vertex error, "" if none */
    char shape_err[160];          /* the first facet shape error */
    uint32_t bad_f, bad_i;        /* first facet with a non-index element */
    bool bad_is_int;              /* ... an integer out of uint32 range */
    int64_t bad_value;
    uint32_t plane_f;             /* first facet with a bad plane */
    char plane_err[160];
} mread;

/* Reads a string member into text (at most 100 bytes, as "%.100s" shows)
 * and tells whether it equals want. */
static int read_name(mread *m, proto_jtok t, char text[101], const char *want)
{
    if (t != PROTO_JT_STRING)
        return proto_jpull_skip(m->j) == PROTO_JT_ERROR ? -1 : M_WRONG_TYPE;
    snprintf(text, 101, "%s", m->j->str);
    return strcmp(m->j->str, want) == 0 && m->j->str_len == strlen(want)
               ? M_OK
               : M_WRONG_VALUE;
}

static bool is_number(proto_jtok t)
{
    return t == PROTO_JT_INTEGER || t == PROTO_JT_REAL;
}

static double number_value(const proto_jpull *j, proto_jtok t)
{
    return t == PROTO_JT_INTEGER ? (double)j->integer : j->real;
}

/* One element of "vertices" (its first token t). -1 on a syntax error. */
static int read_vertex(mread *m, proto_jtok t)
{
    proto_jpull *j = m->j;
    uint64_t i = m->nv++;
    if (m->store_v && m->nv > m->lim->max_vertices)
        m->store_v = false;
    if (t != PROTO_JT_ARRAY) {
        if (!m->verr[0])
            snprintf(m->verr, sizeof m->verr, "vertices[%llu]: expected an "
                     "array of 3 numbers", (unsigned long long)i);
        return proto_jpull_skip(j) == PROTO_JT_ERROR ? -1 : 0;
    }
    double xyz[3] = {0, 0, 0};
    int n = 0, bad = -1;
    while ((t = proto_jpull_next(j)) != PROTO_JT_ARRAY_END) {
        if (t == PROTO_JT_ERROR)
            return -1;
        if (is_number(t)) {
            if (n < 3)
                xyz[n] = number_value(j, t);
        } else {
            if (bad < 0 && n < 3)
                bad = n;
            if (proto_jpull_skip(j) == PROTO_JT_ERROR)
                return -1;
        }
        n++;
    }
    if (!m->verr[0]) {
        if (n != 3)
            snprintf(m->verr, sizeof m->verr, "vertices[%llu]: expected an "
                     "array of 3 numbers", (unsigned long long)i);
        else if (bad >= 0)
            snprintf(m->verr, sizeof m->verr, "vertices[%llu][%d]: expected "
                     "a number", (unsigned long long)i, bad);
    }
    if (m->store_v) {
        geo_poly *p = m->p;
        if (i >= p->cap_verts && geo_poly_reserve(p, i + 1, 0, 0) < 0) {
            m->oom = true;
            m->store_v = false;
            return 0;
        }
        memcpy(p->verts[i], xyz, sizeof xyz);
    }
    return 0;
}

static void facet_shape_error(mread *m, const char *fmt, uint64_t f)
{
    if (!m->shape_err[0])
        snprintf(m->shape_err, sizeof m->shape_err, fmt,
                 (unsigned long long)f);
    m->store_f = false;
}

/* The "vertices" array of facet f (its first token was ARRAY). */
static int read_indices(mread *m, uint64_t f)
{
    proto_jpull *j = m->j;
    geo_poly *p = m->p;
    uint64_t start = m->nc;
    proto_jtok t;
    while ((t = proto_jpull_next(j)) != PROTO_JT_ARRAY_END) {
        if (t == PROTO_JT_ERROR)
            return -1;
        uint64_t i = m->nc++ - start;
        if (m->store_f && m->nc > m->lim->max_corners)
            m->store_f = false;
        uint32_t v = 0;
        if (t == PROTO_JT_INTEGER && j->integer >= 0 &&
            j->integer <= (int64_t)UINT32_MAX) {
            v = (uint32_t)j->integer;
        } else {
            if (m->bad_f == UINT32_MAX && m->store_f) {
                m->bad_f = (uint32_t)f;
                m->bad_i = (uint32_t)i;
                m->bad_is_int = t == PROTO_JT_INTEGER;
                m->bad_value = j->integer;
            }
            if (proto_jpull_skip(j) == PROTO_JT_ERROR)
                return -1;
        }
        if (m->store_f) {
            if (m->nc > p->cap_idx &&
                geo_poly_reserve(p, 0, 0, (size_t)m->nc) < 0) {
                m->oom = true;
                m->store_f = false;
                continue;
            }
            p->fidx[m->nc - 1] = v;
        }
    }
    return 0;
}

/* The "plane" member of facet f (first token t). */
static int read_plane(mread *m, proto_jtok t, uint64_t f, double pl[4])
{
    proto_jpull *j = m->j;
    if (t != PROTO_JT_ARRAY) {
        if (m->plane_f == UINT32_MAX) {
            m->plane_f = (uint32_t)f;
            snprintf(m->plane_err, sizeof m->plane_err, "facets[%llu].plane: "
                     "expected an array of 4 numbers", (unsigned long long)f);
        }
        return proto_jpull_skip(j) == PROTO_JT_ERROR ? -1 : 0;
    }
    int n = 0, bad = -1;
    while ((t = proto_jpull_next(j)) != PROTO_JT_ARRAY_END) {
        if (t == PROTO_JT_ERROR)
            return -1;
        if (is_number(t)) {
            if (n < 4)
                pl[n] = number_value(j, t);
        } else {
            if (bad < 0 && n < 4)
                bad = n;
            if (proto_jpull_skip(j) == PROTO_JT_ERROR)
                return -1;
        }
        n++;
    }
    if (m->plane_f == UINT32_MAX && (n != 4 || bad >= 0)) {
        m->plane_f = (uint32_t)f;
        if (n != 4)
            snprintf(m->plane_err, sizeof m->plane_err, "facets[%llu].plane: "
                     "expected an array of 4 numbers", (unsigned long long)f);
        else
            snprintf(m->plane_err, sizeof m->plane_err, "facets[%llu].plane"
                     "[%d]: expected a number", (unsigned long long)f, bad);
    }
    return 0;
}

/* One element of "facets" (its first token t). */
static int read_facet_pull(mread *m, proto_jtok t)
{
    proto_jpull *j = m->j;
    uint64_t f = m->nf++;
    if (m->store_f && m->nf > m->lim->max_facets)
        m->store_f = false;
    if (t != PROTO_JT_OBJECT) {
        facet_shape_error(m, "facets[%llu]: expected an object", f);
        return proto_jpull_skip(j) == PROTO_JT_ERROR ? -1 : 0;
    }
    geo_poly *p = m->p;
    if (m->store_f && f >= p->cap_facets) {
        if (geo_poly_reserve(p, 0, (size_t)f + 1, 0) < 0) {
            m->oom = true;
            m->store_f = false;
        }
    }
    if (m->store_f && f >= m->cap_given) {
        size_t cap = m->cap_given ? m->cap_given * 2 : 1024;
        bool *g = realloc(m->given, cap);
        if (!g) {
            m->oom = true;
            m->store_f = false;
        } else {
            m->given = g;
            m->cap_given = cap;
        }
    }
    double pl[4] = {0, 0, 0, 0};
    bool have_vertices = false, have_plane = false;
    while ((t = proto_jpull_next(j)) != PROTO_JT_OBJECT_END) {
        if (t == PROTO_JT_ERROR)
            return -1;
        if (strcmp(j->str, "vertices") == 0) {
            have_vertices = true;
            t = proto_jpull_next(j);
            if (t == PROTO_JT_ARRAY) {
                if (read_indices(m, f) < 0)
                    return -1;
            } else {
                facet_shape_error(m, "facets[%llu].vertices: expected an "
                                     "array", f);
                if (proto_jpull_skip(j) == PROTO_JT_ERROR)
                    return -1;
            }
        } else if (strcmp(j->str, "plane") == 0) {
            have_plane = true;
            if (read_plane(m, proto_jpull_next(j), f, pl) < 0)
                return -1;
        } else if (proto_jpull_skip(j) == PROTO_JT_ERROR) {
            return -1;
        }
    }
    if (!have_vertices)
        facet_shape_error(m, "facets[%llu].vertices: missing", f);
    if (m->store_f) {
        p->fstart[f + 1] = (uint32_t)m->nc;
        /* a plane not given is fitted by proto_finish_planes, or not
         * kept at all: its page is not written here */
        if (have_plane)
            memcpy(p->planes[f], pl, sizeof pl);
        m->given[f] = have_plane;
    }
    return 0;
}

/* Reads the elements of an array member with fn, or notes its wrong
 * type. */
static int read_list(mread *m, proto_jtok t, int *state,
                     int (*fn)(mread *, proto_jtok))
{
    if (t != PROTO_JT_ARRAY) {
        *state = M_WRONG_TYPE;
        return proto_jpull_skip(m->j) == PROTO_JT_ERROR ? -1 : 0;
    }
    *state = M_OK;
    while ((t = proto_jpull_next(m->j)) != PROTO_JT_ARRAY_END) {
        if (t == PROTO_JT_ERROR || fn(m, t) < 0)
            return -1;
    }
    return 0;
}

/* Decides, in the tree reader's order, the first error of what was read;
 * 0 when the model is complete and valid. */
static int mread_verdict(mread *m, proto_read_report *rep, geo_err *err)
{
    if (m->format == M_ABSENT)
        return geo_err_set(err, -EINVAL,
                           "format: missing (expected \"" FORMAT_NAME "\")");
    if (m->format == M_WRONG_TYPE)
        return geo_err_set(err, -EINVAL, "format: expected a string");
    if (m->format == M_WRONG_VALUE)
        return geo_err_set(err, -EINVAL, "format: \"%s\" is not supported "
                           "(expected \"" FORMAT_NAME "\")", m->format_text);
    if (m->units == M_WRONG_TYPE)
        return geo_err_set(err, -EINVAL, "units: expected a string");
    if (m->units == M_WRONG_VALUE)
        return geo_err_set(err, -EINVAL, "units: \"%s\" is not supported "
                           "(only \"mm\")", m->units_text);
    if (m->vertices != M_OK)
        return geo_err_set(err, -EINVAL, m->vertices == M_ABSENT
                           ? "vertices: missing" : "vertices: expected an "
                           "array");
    if (m->facets != M_OK)
        return geo_err_set(err, -EINVAL, m->facets == M_ABSENT
                           ? "facets: missing" : "facets: expected an array");
    int r = proto_check_limits(m->lim, m->nv, m->nf, 0, err);
    if (r < 0)
        return r;
    if (m->shape_err[0])
        return geo_err_set(err, -EINVAL, "%s", m->shape_err);
    r = proto_check_limits(m->lim, m->nv, m->nf, m->nc, err);
    if (r < 0)
        return r;
    if (m->oom)
        return geo_err_set(err, -ENOMEM, "out of memory");
    if (m->verr[0])
        return geo_err_set(err, -EINVAL, "%s", m->verr);
    geo_poly *p = m->p;
    p->nverts = (uint32_t)m->nv;
    for (uint32_t f = 0; f < m->nf; f++) {
        uint32_t n = p->fstart[f + 1] - p->fstart[f];
        if (n < 3)
            return geo_err_set(err, -EINVAL, "facets[%u].vertices: %u "
                               "vertices, a facet needs at least 3", f, n);
        const uint32_t *v = p->fidx + p->fstart[f];
        for (uint32_t i = 0; i < n; i++) {
            if (f == m->bad_f && i == m->bad_i) {
                if (!m->bad_is_int)
                    return geo_err_set(err, -EINVAL, "facets[%u].vertices[%u]"
                                       ": expected an integer", f, i);
                return geo_err_set(err, -EINVAL, "facets[%u].vertices[%u]: "
                                   "index %lld out of range (%u vertices)", f,
                                   i, (long long)m->bad_value, p->nverts);
            }
            if (v[i] >= p->nverts)
                return geo_err_set(err, -EINVAL, "facets[%u].vertices[%u]: "
                                   "index %u out of range (%u vertices)", f,
                                   i, v[i], p->nverts);
        }
        for (uint32_t i = 0; i < n; i++) {
            uint32_t k = (i + 1) % n;
            if (v[i] == v[k])
                return geo_err_set(err, -EINVAL, "facets[%u].vertices[%u]: "
                                   "index %u repeated consecutively", f, k,
                                   v[i]);
        }
        if (f == m->plane_f)
            return geo_err_set(err, -EINVAL, "%s", m->plane_err);
        p->nfacets = f + 1;
    }
    return proto_finish_planes(p, m->given, m->lim, rep, err);
}

/* The fast path: a model object in the layout facet writes (members
 * "format", "units", "vertices" and "facets" in any order, each once; a
 * vertex an array of three numbers; a facet {"vertices": [indices]} with
 * an optional "plane": [four numbers] after them; whitespace anywhere),
 * read straight from the bytes into the same mread the token reader
 * fills, number by number through the tokenizer's own conversion
 * (proto_json_number). A model's text is 9 parts in 10 such arrays, where
 * a token at a time costs three times the bytes' own work. Whatever else
 * it meets — another member, an escape, a string that is not the
 * expected name, a number the tokenizer would refuse, a count past its
 * limit, a depth near the limit — it leaves to the token reader, which
 * then reads the object from its start: every error a document can
 * have is that reader's. */

enum { FN_FORMAT, FN_UNITS, FN_VERTICES, FN_FACETS, FN_OTHER };

typedef struct fast {
    const unsigned char *d;
    size_t n, p;
    const proto_jpull *j; /* its behind callback */
    size_t behind_next;
} fast;

static void f_space(fast *f)
{
    const unsigned char *d = f->d;
    size_t p = f->p;
    while (p < f->n &&
           (d[p] == ' ' || d[p] == '\n' || d[p] == '\r' || d[p] == '\t'))
        p++;
    f->p = p;
}

/* Whitespace, then the byte c (taken) or false. Inlined, the byte
 * itself first: the layout facet writes has a newline after each vertex
 * and facet and no other whitespace. */
static inline __attribute__((always_inline)) bool f_byte(fast *f,
                                                         unsigned char c)
{
    if (f->p < f->n && f->d[f->p] == c) {
        f->p++;
        return true;
    }
    f_space(f);
    if (f->p < f->n && f->d[f->p] == c) {
        f->p++;
        return true;
    }
    return false;
}

static bool f_number(fast *f, double *ret)
{
    f_space(f);
    bool is_int;
    int64_t i;
    if (!proto_json_number(f->d, f->n, f->p, &f->p, &is_int, &i, ret))
        return false;
    if (is_int)
        *ret = (double)i; /* as number_value */
    return true;
}

/* An index: a non-negative integer of 32 bits (a short one inline). */
static bool f_index(fast *f, uint32_t *ret)
{
    f_space(f);
    if (proto_json_short_uint(f->d, f->n, f->p, &f->p, ret))
        return true;
    bool is_int;
    int64_t i;
    double r;
    if (!proto_json_number(f->d, f->n, f->p, &f->p, &is_int, &i, &r) ||
        !is_int || i < 0 || i > (int64_t)UINT32_MAX)
        return false;
    *ret = (uint32_t)i;
    return true;
}

/* A string of printable ASCII without escapes, its bytes in [*s, *e). */
static bool f_plain_string(fast *f, size_t *s, size_t *e)
{
    if (!f_byte(f, '"'))
        return false;
    size_t p = f->p;
    while (p < f->n && f->d[p] >= 0x20 && f->d[p] < 0x7F && f->d[p] != '"' &&
           f->d[p] != '\\')
        p++;
    if (p >= f->n || f->d[p] != '"')
        return false;
    *s = f->p;
    *e = p;
    f->p = p + 1;
    return true;
}

static bool f_string_is(fast *f, const char *want)
{
    size_t s, e;
    return f_plain_string(f, &s, &e) && e - s == strlen(want) &&
           memcmp(f->d + s, want, e - s) == 0;
}

/* Whitespace, then the len bytes of lit (taken) or false. */
static bool f_literal(fast *f, const char *lit, size_t len)
{
    f_space(f);
    if (f->n - f->p < len || memcmp(f->d + f->p, lit, len) != 0)
        return false;
    f->p += len;
    return true;
}

/* A member name and its colon: FN_*, FN_OTHER for anything else. */
static int f_name(fast *f)
{
    static const char *const names[] = {"format", "units", "vertices",
                                        "facets"};
    size_t s, e;
    if (!f_plain_string(f, &s, &e) || !f_byte(f, ':'))
        return FN_OTHER;
    for (int k = 0; k < FN_OTHER; k++)
        if (e - s == strlen(names[k]) && memcmp(f->d + s, names[k], e - s) == 0)
            return k;
    return FN_OTHER;
}

/* The pages behind are offered back as the tokenizer does. */
static void f_behind(fast *f)
{
    if (f->j->behind && f->p >= f->behind_next) {
        f->behind_next = f->p + PROTO_JPULL_BEHIND_STEP;
        f->j->behind(f->j->behind_user, f->p);
    }
}

static bool f_vertices(fast *f, mread *m)
{
    if (!f_byte(f, '['))
        return false;
    if (f_byte(f, ']'))
        return true;
    geo_poly *p = m->p;
    do {
        double xyz[3];
        if (!f_byte(f, '[') || !f_number(f, &xyz[0]) || !f_byte(f, ',') ||
            !f_number(f, &xyz[1]) || !f_byte(f, ',') ||
            !f_number(f, &xyz[2]) || !f_byte(f, ']'))
            return false;
        uint64_t i = m->nv++;
        if (m->nv > m->lim->max_vertices ||
            (i >= p->cap_verts && geo_poly_reserve(p, i + 1, 0, 0) < 0))
            return false;
        memcpy(p->verts[i], xyz, sizeof xyz);
        f_behind(f);
    } while (f_byte(f, ','));
    return f_byte(f, ']');
}

static bool f_facet(fast *f, mread *m)
{
    geo_poly *p = m->p;
    uint64_t fi = m->nf++;
    if (m->nf > m->lim->max_facets ||
        (fi >= p->cap_facets && geo_poly_reserve(p, 0, (size_t)fi + 1, 0) < 0))
        return false;
    if (fi >= m->cap_given) {
        size_t cap = m->cap_given ? m->cap_given * 2 : 1024;
        bool *g = realloc(m->given, cap);
        if (!g)
            return false;
        m->given = g;
        m->cap_given = cap;
    }
    if (!f_literal(f, "\"vertices\"", 10) || !f_byte(f, ':') ||
        !f_byte(f, '['))
        return false;
    do {
        uint32_t v;
        if (!f_index(f, &v))
            return false;
        m->nc++;
        if (m->nc > m->lim->max_corners ||
            (m->nc > p->cap_idx &&
             geo_poly_reserve(p, 0, 0, (size_t)m->nc) < 0))
            return false;
        p->fidx[m->nc - 1] = v;
    } while (f_byte(f, ','));
    if (!f_byte(f, ']'))
        return false;
    double pl[4];
    bool have_plane = f_byte(f, ',');
    if (have_plane &&
        (!f_literal(f, "\"plane\"", 7) || !f_byte(f, ':') ||
         !f_byte(f, '[') || !f_number(f, &pl[0]) ||
         !f_byte(f, ',') || !f_number(f, &pl[1]) || !f_byte(f, ',') ||
         !f_number(f, &pl[2]) || !f_byte(f, ',') || !f_number(f, &pl[3]) ||
         !f_byte(f, ']')))
        return false;
    if (!f_byte(f, '}'))
        return false;
    p->fstart[fi + 1] = (uint32_t)m->nc;
    if (have_plane)
        memcpy(p->planes[fi], pl, sizeof pl);
    m->given[fi] = have_plane;
    return true;
}

static bool f_facets(fast *f, mread *m)
{
    if (!f_byte(f, '['))
        return false;
    if (f_byte(f, ']'))
        return true;
    do {
        if (!f_byte(f, '{') || !f_facet(f, m))
            return false;
        f_behind(f);
    } while (f_byte(f, ','));
    return f_byte(f, ']');
}

/* The members of the model object whose '{' j has just returned, into
 * m (as the token reader initialises it); the position just past its
 * '}', or 0 when the token reader must read it. */
static size_t fast_model(proto_jpull *j, mread *m)
{
    if (j->depth + 4 > PROTO_JSON_MAX_DEPTH)
        return 0; /* the indices' depth: the tokenizer's limit decides */
    fast f = {(const unsigned char *)j->data, j->len, j->tok_end, j,
              j->tok_end + PROTO_JPULL_BEHIND_STEP};
    bool seen[FN_OTHER] = {false};
    do {
        int k = f_name(&f);
        if (k == FN_OTHER || seen[k])
            return 0;
        seen[k] = true;
        bool ok;
        switch (k) {
        case FN_FORMAT:
            ok = f_string_is(&f, FORMAT_NAME);
            m->format = M_OK;
            break;
        case FN_UNITS:
            ok = f_string_is(&f, "mm");
            m->units = M_OK;
            break;
        case FN_VERTICES:
            ok = f_vertices(&f, m);
            m->vertices = M_OK;
            break;
        default:
            ok = f_facets(&f, m);
            m->facets = M_OK;
            break;
        }
        if (!ok)
            return 0;
    } while (f_byte(&f, ','));
    return f_byte(&f, '}') ? f.p : 0;
}

/* An mread with its empty model (one facet start, 0). -ENOMEM. */
static int mread_start(mread *m, proto_jpull *j, const proto_limits *lim,
                       geo_err *err)
{
    *m = (mread){
        .j = j, .lim = lim, .store_v = true, .store_f = true,
        .bad_f = UINT32_MAX, .plane_f = UINT32_MAX,
    };
    m->p = geo_poly_new();
    if (!m->p || geo_poly_reserve(m->p, 0, 1, 0) < 0) {
        m->p = geo_poly_free(m->p);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    m->p->fstart[0] = 0;
    return 0;
}

geo_poly *proto_json_from_pull(proto_jpull *j, proto_jtok first,
                               const proto_limits *lim, proto_read_report *rep,
                               bool *ret_syntax, geo_err *err)
{
    *ret_syntax = false;
    mread m = {0}; /* no model unless the text is an object */
    int r = 0;
    if (first == PROTO_JT_OBJECT) {
        if (mread_start(&m, j, lim, err) < 0)
            return NULL;
        size_t end = fast_model(j, &m);
        if (end) {
            proto_jpull_end_object_at(j, end);
        } else {
            /* from the start, with nothing of the fast path's kept */
            free(m.given);
            geo_poly_free(m.p);
            if (mread_start(&m, j, lim, err) < 0)
                return NULL;
        }
        proto_jtok t;
        while (!end && r == 0 &&
               (t = proto_jpull_next(j)) != PROTO_JT_OBJECT_END) {
            if (t == PROTO_JT_ERROR) {
                r = -1;
            } else if (strcmp(j->str, "format") == 0) {
                r = m.format = read_name(&m, proto_jpull_next(j),
                                         m.format_text, FORMAT_NAME);
            } else if (strcmp(j->str, "units") == 0) {
                r = m.units = read_name(&m, proto_jpull_next(j),
                                        m.units_text, "mm");
            } else if (strcmp(j->str, "vertices") == 0) {
                r = read_list(&m, proto_jpull_next(j), &m.vertices,
                              read_vertex);
            } else if (strcmp(j->str, "facets") == 0) {
                r = read_list(&m, proto_jpull_next(j), &m.facets,
                              read_facet_pull);
            } else if (proto_jpull_skip(j) == PROTO_JT_ERROR) {
                r = -1;
            }
            if (r > 0)
                r = 0;
        }
    } else if (first == PROTO_JT_ERROR ||
               proto_jpull_skip(j) == PROTO_JT_ERROR) {
        r = -1;
    }
    if (r < 0) {
        *ret_syntax = true;
        geo_err_set(err, j->error.code, "line %d, column %d: %s",
                    j->error.line, j->error.column, j->error.text);
    } else if (first != PROTO_JT_OBJECT) {
        geo_err_set(err, -EINVAL, "expected a JSON object");
        r = -1;
    } else if (mread_verdict(&m, rep, err) < 0) {
        r = -1;
    }
    free(m.given);
    if (r < 0)
        return geo_poly_free(m.p);
    return m.p;
}

geo_poly *proto_json_read_pull(proto_jpull *j, const proto_limits *lim,
                               proto_read_report *rep, geo_err *err)
{
    bool syntax;
    geo_err model_err;
    geo_poly *p = proto_json_from_pull(j, proto_jpull_next(j), lim, rep,
                                       &syntax, &model_err);
    /* a syntax error after the model outranks what the model lacks */
    if (!syntax && proto_jpull_next(j) == PROTO_JT_ERROR) {
        p = geo_poly_free(p);
        geo_err_set(err, j->error.code, "line %d, column %d: %s",
                    j->error.line, j->error.column, j->error.text);
    } else if (!p && err) {
        *err = model_err;
    }
    return p;
}

geo_poly *proto_json_read(const void *data, size_t len,
                          const proto_limits *lim, proto_read_report *rep,
                          geo_err *err)
{
    proto_jpull j;
    proto_jpull_init(&j, data, len);
    geo_poly *p = proto_json_read_pull(&j, lim, rep, err);
    proto_jpull_clear(&j);
    return p;
}

#define PUT(b, lit) proto_buf_append(b, lit, sizeof lit - 1)

int proto_json_write(const geo_poly *p, proto_buf *b, geo_err *err)
{
    PUT(b, "{\"format\":\"" FORMAT_NAME "\",\"units\":\"mm\",\n"
           "\"vertices\":[\n");
    for (uint32_t i = 0; i < p->nverts; i++) {
        PUT(b, "[");
        proto_buf_double(b, p->verts[i][0]);
        PUT(b, ",");
        proto_buf_double(b, p->verts[i][1]);
        PUT(b, ",");
        proto_buf_double(b, p->verts[i][2]);
        if (i + 1 < p->nverts)
            PUT(b, "],\n");
        else
            PUT(b, "]\n");
    }
    PUT(b, "],\n\"facets\":[\n");
    for (uint32_t f = 0; f < p->nfacets; f++) {
        PUT(b, "{\"vertices\":[");
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *v = geo_poly_facet(p, f);
        for (uint32_t i = 0; i < n; i++) {
            if (i)
                PUT(b, ",");
            proto_buf_u32(b, v[i]);
        }
        PUT(b, "],\"plane\":[");
        for (int k = 0; k < 4; k++) {
            if (k)
                PUT(b, ",");
            proto_buf_double(b, p->planes[f][k]);
        }
        if (f + 1 < p->nfacets)
            PUT(b, "]},\n");
        else
            PUT(b, "]}\n");
    }
    PUT(b, "]}\n");
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
