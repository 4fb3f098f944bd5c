/* model_ply.c — PLY (Stanford polygon files): ASCII, binary little-endian
 * and binary big-endian on reading; binary little-endian and ASCII on
 * writing.
 *
 * Reading understands any header: every element and property is parsed
 * (so unknown elements are skipped correctly), "vertex" must have scalar
 * x, y, z of any numeric type, "face" a list "vertex_indices" (or
 * "vertex_index") with integer count and item types. Faces are kept as
 * polygons. When "face" also has scalar nx, ny, nz and d — the facet's
 * plane, which this writer adds — they are taken as given planes and
 * checked (proto_read_report); otherwise planes are computed.
 *
 * Counts come from the header: they are checked against the limits and
 * against the bytes that follow (every element needs at least its fixed
 * size in binary, 2 bytes per value in ASCII) before anything is
 * allocated. Errors name the byte offset (binary) or line (ASCII) and the
 * element: "byte 1234: face 12: vertex_indices[3]: index 9001 out of
 * range (8000 vertices)".
 *
 * Writing uses double coordinates and planes, so a binary round trip is
 * bit-exact, and an ASCII one too (shortest round-trip decimals). */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model_codec.h"

enum ptype { T_NONE, T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_F32, T_F64 };

static const struct {
    const char *name, *alias;
    enum ptype t;
    unsigned size;
} ptypes[] = {
    {"char", "int8", T_I8, 1},     {"uchar", "uint8", T_U8, 1},
    {"short", "int16", T_I16, 2},  {"ushort", "uint16", T_U16, 2},
    {"int", "int32", T_I32, 4},    {"uint", "uint32", T_U32, 4},
    {"float", "float32", T_F32, 4}, {"double", "float64", T_F64, 8},
};

enum { MAX_ELEMENTS = 32, MAX_PROPS = 64, MAX_HEADER = 65536 };

typedef struct prop {
    char name[32];
    enum ptype type;  /* scalar type, or list item type */
    enum ptype count; /* list count type, T_NONE for a scalar */
} prop;

typedef struct element {
    char name[32];
    uint32_t count;
    unsigned nprops;
    prop props[MAX_PROPS];
} element;

typedef struct header {
    bool ascii, big;
    unsigned nelems;
    element elems[MAX_ELEMENTS];
    size_t body; /* offset of the first body byte */
} header;

static unsigned type_size(enum ptype t)
{
    for (size_t i = 0; i < sizeof ptypes / sizeof ptypes[0]; i++)
        if (ptypes[i].t == t)
            return ptypes[i].size;
    return 0;
}

static enum ptype type_named(const char *s, size_t n)
{
    for (size_t i = 0; i < sizeof ptypes / sizeof ptypes[0]; i++)
        if ((strlen(ptypes[i].name) == n && !memcmp(s, ptypes[i].name, n)) ||
            (strlen(ptypes[i].alias) == n && !memcmp(s, ptypes[i].alias, n)))
            return ptypes[i].t;
    return T_NONE;
}

static bool is_int_type(enum ptype t)
{
    return t != T_NONE && t != T_F32 && t != T_F64;
}

static bool tok_is(const char *t, size_t n, const char *s)
{
    return strlen(s) == n && memcmp(t, s, n) == 0;
}

static int copy_name(char *dst, const char *t, size_t n, uint32_t line,
                     geo_err *err)
{
    if (n >= 32)
        return geo_err_set(err, -EINVAL, "line %u: name longer than 31 "
                                         "bytes", line);
    memcpy(dst, t, n);
    dst[n] = '\0';
    return 0;
}

static int parse_property(header *h, proto_scan *ls, uint32_t line,
                          geo_err *err)
{
    if (h->nelems == 0)
        return geo_err_set(err, -EINVAL,
                           "line %u: property before any element", line);
    element *el = &h->elems[h->nelems - 1];
    if (el->nprops == MAX_PROPS)
        return geo_err_set(err, -EINVAL,
                           "line %u: more than %d properties in element %s",
                           line, MAX_PROPS, el->name);
    prop *pr = &el->props[el->nprops];
    const char *t;
    size_t n;
    char shown[32];
    if (!proto_scan_token(ls, &t, &n))
        return geo_err_set(err, -EINVAL, "line %u: property without a type",
                           line);
    pr->count = T_NONE;
    if (tok_is(t, n, "list")) {
        if (!proto_scan_token(ls, &t, &n) ||
            !is_int_type(pr->count = type_named(t, n)))
            return geo_err_set(err, -EINVAL,
                               "line %u: a list count needs an integer type",
                               line);
        if (!proto_scan_token(ls, &t, &n))
            return geo_err_set(err, -EINVAL, "line %u: list without an item "
                                             "type", line);
    }
    pr->type = type_named(t, n);
    if (pr->type == T_NONE)
        return geo_err_set(err, -EINVAL, "line %u: unknown property type "
                                         "\"%s\"", line,
                           proto_tok_show(t, n, shown));
    if (!proto_scan_token(ls, &t, &n))
        return geo_err_set(err, -EINVAL, "line %u: property without a name",
                           line);
    if (copy_name(pr->name, t, n, line, err) < 0)
        return -EINVAL;
    for (unsigned i = 0; i < el->nprops; i++)
        if (strcmp(el->props[i].name, pr->name) == 0)
            return geo_err_set(err, -EINVAL,
                               "line %u: property %s repeated in element %s",
                               line, pr->name, el->name);
    el->nprops++;
    return 0;
}

static int parse_header(const char *d, size_t len, header *h, geo_err *err)
{
    proto_scan s;
    const char *line;
    size_t n;
    proto_scan_init(&s, d, len < MAX_HEADER ? len : MAX_HEADER, false);
    if (!proto_scan_line(&s, &line, &n) || !tok_is(line, n, "ply"))
        return geo_err_set(err, -EINVAL, "line 1: not a PLY file (expected "
                                         "\"ply\")");
    bool have_format = false;
    while (proto_scan_line(&s, &line, &n)) {
        uint32_t ln = s.tok_line;
        proto_scan ls;
        proto_scan_init(&ls, line, n, false);
        const char *t;
        size_t tn;
        char shown[32];
        if (!proto_scan_token(&ls, &t, &tn))
            continue;
        if (tok_is(t, tn, "comment") || tok_is(t, tn, "obj_info"))
            continue;
        if (tok_is(t, tn, "end_header")) {
            if (!have_format)
                return geo_err_set(err, -EINVAL, "line %u: no format line",
                                   ln);
            if (s.p == s.end && s.end == d + MAX_HEADER)
                break;
            h->body = (size_t)(s.p - d);
            return 0;
        }
        if (tok_is(t, tn, "format")) {
            const char *v;
            size_t vn;
            if (!proto_scan_token(&ls, &t, &tn) ||
                !proto_scan_token(&ls, &v, &vn) || !tok_is(v, vn, "1.0"))
                return geo_err_set(err, -EINVAL, "line %u: expected \"format "
                                                 "<kind> 1.0\"", ln);
            if (tok_is(t, tn, "ascii"))
                h->ascii = true;
            else if (tok_is(t, tn, "binary_big_endian"))
                h->big = true;
            else if (!tok_is(t, tn, "binary_little_endian"))
                return geo_err_set(err, -EINVAL, "line %u: unknown format "
                                                 "\"%s\"", ln,
                                   proto_tok_show(t, tn, shown));
            have_format = true;
        } else if (tok_is(t, tn, "element")) {
            if (h->nelems == MAX_ELEMENTS)
                return geo_err_set(err, -EINVAL, "line %u: more than %d "
                                                 "elements", ln, MAX_ELEMENTS);
            element *el = &h->elems[h->nelems];
            el->nprops = 0;
            if (!proto_scan_token(&ls, &t, &tn) ||
                copy_name(el->name, t, tn, ln, err) < 0)
                return geo_err_set(err, -EINVAL, "line %u: element needs a "
                                                 "short name", ln);
            if (!proto_scan_token(&ls, &t, &tn) ||
                proto_parse_u32(t, tn, &el->count) < 0)
                return geo_err_set(err, -EINVAL, "line %u: element %s: "
                                                 "expected a count below "
                                                 "2^32", ln, el->name);
            h->nelems++;
        } else if (tok_is(t, tn, "property")) {
            if (parse_property(h, &ls, ln, err) < 0)
                return -EINVAL;
        } else {
            return geo_err_set(err, -EINVAL, "line %u: unknown header line "
                                             "\"%s\"", ln,
                               proto_tok_show(t, tn, shown));
        }
    }
    return geo_err_set(err, -EINVAL, "no \"end_header\" line within the first "
                                     "%d bytes", MAX_HEADER);
}

/* The body being read: a byte cursor (binary) or a tokenizer (ASCII). */
typedef struct body {
    const header *h;
    const unsigned char *d;
    size_t len, pos, at; /* at: offset of the value being read */
    proto_scan s;
    geo_err *err;
    const char *el_name; /* the element instance being read ("face 12") */
    uint32_t el_index;
} body;

static int body_fail(body *b, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static int body_fail(body *b, const char *fmt, ...)
{
    char msg[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (b->h->ascii)
        return geo_err_set(b->err, -EINVAL, "line %u: %s %u: %s",
                           b->s.tok_line, b->el_name, b->el_index, msg);
    return geo_err_set(b->err, -EINVAL, "byte %zu: %s %u: %s", b->at,
                       b->el_name, b->el_index, msg);
}

static uint64_t load_bits(body *b, unsigned size)
{
    const unsigned char *p = b->d + b->pos;
    uint64_t u = 0;
    for (unsigned i = 0; i < size; i++)
        u |= (uint64_t)p[b->h->big ? size - 1 - i : i] << (8 * i);
    b->pos += size;
    return u;
}

/* Reads one value of type t as a double (integers are exact). */
static int get_value(body *b, enum ptype t, const char *what, double *ret)
{
    if (b->h->ascii) {
        const char *tok;
        size_t n;
        char shown[32];
        if (!proto_scan_token(&b->s, &tok, &n)) {
            b->s.tok_line = b->s.line;
            return body_fail(b, "%s: unexpected end of file", what);
        }
        if (is_int_type(t)) {
            int64_t v;
            if (proto_parse_i64(tok, n, &v) < 0)
                return body_fail(b, "%s: expected an integer, found \"%s\"",
                                 what, proto_tok_show(tok, n, shown));
            *ret = (double)v;
        } else {
            int e = proto_parse_double(tok, n, ret);
            if (e < 0)
                return body_fail(b, "%s: %s, found \"%s\"", what,
                                 e == -ERANGE ? "number out of range"
                                              : "expected a number",
                                 proto_tok_show(tok, n, shown));
        }
        return 0;
    }
    unsigned size = type_size(t);
    b->at = b->pos;
    if (b->len - b->pos < size)
        return body_fail(b, "%s: unexpected end of file", what);
    uint64_t u = load_bits(b, size);
    switch (t) {
    case T_I8: *ret = (int8_t)u; break;
    case T_U8: *ret = (uint8_t)u; break;
    case T_I16: *ret = (int16_t)u; break;
    case T_U16: *ret = (uint16_t)u; break;
    case T_I32: *ret = (int32_t)u; break;
    case T_U32: *ret = (uint32_t)u; break;
    case T_F32: {
        uint32_t w = (uint32_t)u;
        float f;
        memcpy(&f, &w, 4);
        *ret = f;
        break;
    }
    default:
        memcpy(ret, &u, 8);
        break;
    }
    if (!isfinite(*ret))
        return body_fail(b, "%s: not a finite number", what);
    return 0;
}

static unsigned min_bytes(const header *h, const element *el)
{
    unsigned s = 0;
    for (unsigned i = 0; i < el->nprops; i++) {
        const prop *pr = &el->props[i];
        s += h->ascii ? 2 : type_size(pr->count != T_NONE ? pr->count
                                                          : pr->type);
    }
    return s;
}

static int find_prop(const element *el, const char *name)
{
    for (unsigned i = 0; i < el->nprops; i++)
        if (strcmp(el->props[i].name, name) == 0)
            return (int)i;
    return -1;
}

/* Roles of the properties of the elements we use. */
typedef struct roles {
    int x, y, z;        /* in vertex */
    int list;           /* vertex_indices in face */
    int plane[4];       /* nx ny nz d in face, all or none */
} roles;

static int check_roles(const element *vx, const element *fc, roles *r,
                       geo_err *err)
{
    r->x = r->y = r->z = r->list = -1;
    for (int k = 0; k < 4; k++)
        r->plane[k] = -1;
    if (vx) {
        r->x = find_prop(vx, "x");
        r->y = find_prop(vx, "y");
        r->z = find_prop(vx, "z");
        const int xyz[3] = {r->x, r->y, r->z};
        for (int k = 0; k < 3; k++) {
            if (xyz[k] < 0)
                return geo_err_set(err, -EINVAL, "header: element vertex has "
                                                 "no property %c", "xyz"[k]);
            if (vx->props[xyz[k]].count != T_NONE)
                return geo_err_set(err, -EINVAL, "header: vertex property %c "
                                                 "is a list", "xyz"[k]);
        }
    }
    if (fc) {
        r->list = find_prop(fc, "vertex_indices");
        if (r->list < 0)
            r->list = find_prop(fc, "vertex_index");
        if (r->list < 0 || fc->props[r->list].count == T_NONE)
            return geo_err_set(err, -EINVAL, "header: element face has no "
                                             "list vertex_indices");
        if (!is_int_type(fc->props[r->list].type))
            return geo_err_set(err, -EINVAL, "header: face vertex_indices "
                                             "needs an integer item type");
        static const char *const pn[4] = {"nx", "ny", "nz", "d"};
        int found = 0;
        for (int k = 0; k < 4; k++) {
            r->plane[k] = find_prop(fc, pn[k]);
            if (r->plane[k] >= 0 && fc->props[r->plane[k]].count == T_NONE)
                found++;
            else
                r->plane[k] = -1;
        }
        if (found < 4)
            for (int k = 0; k < 4; k++)
                r->plane[k] = -1;
    }
    return 0;
}

/* Skips or reads a list; for the face's index list, stores into p. */
static int read_list(body *b, const prop *pr, geo_poly *p, uint32_t f,
                     const proto_limits *lim, bool is_index_list)
{
    double cnt;
    if (get_value(b, pr->count, pr->name, &cnt) < 0)
        return -EINVAL;
    if (cnt < 0)
        return body_fail(b, "%s: negative count %.0f", pr->name, cnt);
    uint64_t n = (uint64_t)cnt;
    /* a count beyond what the rest of the input can hold is a lie */
    size_t rest = b->h->ascii ? (size_t)(b->s.end - b->s.p) + 1
                              : b->len - b->pos;
    unsigned each = b->h->ascii ? 2 : type_size(pr->type);
    if (n > rest / each)
        return body_fail(b, "%s: %llu items cannot fit in the remaining %zu "
                            "bytes", pr->name, (unsigned long long)n, rest);
    if (!is_index_list) {
        double v;
        for (uint64_t i = 0; i < n; i++)
            if (get_value(b, pr->type, pr->name, &v) < 0)
                return -EINVAL;
        return 0;
    }
    if (n < 3)
        return body_fail(b, "%s: %llu vertices, a facet needs at least 3",
                         pr->name, (unsigned long long)n);
    size_t nc = geo_poly_ncorners(p);
    if (proto_check_limits(lim, 0, 0, nc + n, b->err) < 0) {
        char msg[sizeof b->err->msg];
        memcpy(msg, b->err->msg, sizeof msg);
        body_fail(b, "%s", msg);
        return -ERANGE;
    }
    if (geo_poly_reserve(p, 0, (size_t)f + 1, nc + n) < 0)
        return geo_err_set(b->err, -ENOMEM, "out of memory");
    uint32_t *dst = p->fidx + nc;
    for (uint32_t i = 0; i < n; i++) {
        double v;
        char what[48];
        snprintf(what, sizeof what, "%s[%u]", pr->name, i);
        if (get_value(b, pr->type, what, &v) < 0)
            return -EINVAL;
        if (v < 0 || v >= p->nverts)
            return body_fail(b, "%s: index %.0f out of range (%u vertices)",
                             what, v, p->nverts);
        dst[i] = (uint32_t)v;
        if (i > 0 && dst[i] == dst[i - 1])
            return body_fail(b, "%s: index %u repeated consecutively", what,
                             dst[i]);
    }
    if (dst[0] == dst[n - 1])
        return body_fail(b, "%s[0]: index %u repeated consecutively",
                         pr->name, dst[0]);
    p->fstart[f + 1] = (uint32_t)(nc + n);
    return 0;
}

static int read_elements(body *b, const header *h, const roles *r,
                         geo_poly *p, bool *given, const proto_limits *lim)
{
    for (unsigned e = 0; e < h->nelems; e++) {
        const element *el = &h->elems[e];
        bool is_vertex = strcmp(el->name, "vertex") == 0;
        bool is_face = strcmp(el->name, "face") == 0;
        b->el_name = el->name;
        /* an element without properties has no bytes: nothing to read,
         * however large its count */
        for (uint32_t i = 0; el->nprops && i < el->count; i++) {
            b->el_index = i;
            if (!h->ascii)
                b->at = b->pos;
            for (unsigned k = 0; k < el->nprops; k++) {
                const prop *pr = &el->props[k];
                if (pr->count != T_NONE) {
                    bool idx = is_face && (int)k == r->list;
                    if (read_list(b, pr, p, i, lim, idx) < 0)
                        return -EINVAL;
                    continue;
                }
                double v;
                if (get_value(b, pr->type, pr->name, &v) < 0)
                    return -EINVAL;
                if (is_vertex) {
                    if ((int)k == r->x)
                        p->verts[i][0] = v;
                    else if ((int)k == r->y)
                        p->verts[i][1] = v;
                    else if ((int)k == r->z)
                        p->verts[i][2] = v;
                } else if (is_face) {
                    for (int q = 0; q < 4; q++)
                        if ((int)k == r->plane[q])
                            p->planes[i][q] = v;
                }
            }
            if (is_face) {
                given[i] = r->plane[0] >= 0;
                p->nfacets = i + 1;
            }
        }
    }
    return 0;
}

geo_poly *proto_ply_read(const void *data, size_t len,
                         const proto_limits *lim, proto_read_report *rep,
                         geo_err *err)
{
    header *h = calloc(1, sizeof *h);
    if (!h) {
        geo_err_set(err, -ENOMEM, "out of memory");
        return NULL;
    }
    geo_poly *p = NULL;
    bool *given = NULL;
    if (parse_header(data, len, h, err) < 0)
        goto fail;
    const element *vx = NULL, *fc = NULL;
    uint64_t need = 0;
    for (unsigned e = 0; e < h->nelems; e++) {
        const element *el = &h->elems[e];
        if (strcmp(el->name, "vertex") == 0 && !vx)
            vx = el;
        else if (strcmp(el->name, "face") == 0 && !fc)
            fc = el;
        else if (strcmp(el->name, "vertex") == 0 ||
                 strcmp(el->name, "face") == 0) {
            geo_err_set(err, -EINVAL, "header: element %s declared twice",
                        el->name);
            goto fail;
        }
        need += (uint64_t)el->count * min_bytes(h, el);
    }
    roles r;
    if (check_roles(vx, fc, &r, err) < 0)
        goto fail;
    uint32_t nv = vx ? vx->count : 0, nf = fc ? fc->count : 0;
    if (proto_check_limits(lim, nv, nf, 3 * (uint64_t)nf, err) < 0) {
        geo_err_prefix(err, "header");
        goto fail;
    }
    size_t rest = len - h->body + (h->ascii ? 1 : 0);
    if (need > rest) {
        geo_err_set(err, -EINVAL, "header: the declared elements need at "
                                  "least %llu bytes, %zu follow the header "
                                  "(truncated?)",
                    (unsigned long long)need, len - h->body);
        goto fail;
    }
    p = proto_poly_alloc(nv, nf, 3 * (uint64_t)nf, &given, err);
    if (!p)
        goto fail;
    p->nverts = nv;
    body b = {.h = h, .d = data, .len = len, .pos = h->body, .err = err};
    if (h->ascii)
        proto_scan_init(&b.s, (const char *)data + h->body, len - h->body,
                        false);
    /* line numbers of the body continue those of the header */
    if (h->ascii)
        for (size_t i = 0; i < h->body; i++)
            b.s.line += ((const char *)data)[i] == '\n';
    if (read_elements(&b, h, &r, p, given, lim) < 0)
        goto fail;
    const char *t;
    size_t tn;
    if (h->ascii ? proto_scan_token(&b.s, &t, &tn) : b.pos != len) {
        if (h->ascii)
            geo_err_set(err, -EINVAL, "line %u: data after the last element",
                        b.s.tok_line);
        else
            geo_err_set(err, -EINVAL, "byte %zu: %zu bytes after the last "
                                      "element", b.pos, len - b.pos);
        goto fail;
    }
    free(h);
    return proto_read_done(p, given, lim, rep, err);
fail:
    free(given);
    free(h);
    return geo_poly_free(p);
}

int proto_ply_write(const geo_poly *p, bool ascii, proto_buf *b,
                    geo_err *err)
{
    (void)err;
    uint32_t maxn = 0;
    for (uint32_t f = 0; f < p->nfacets; f++)
        if (geo_poly_facet_size(p, f) > maxn)
            maxn = geo_poly_facet_size(p, f);
    bool wide = maxn > 255;
    proto_buf_printf(b,
                     "ply\nformat %s 1.0\n"
                     "comment millimetres; face nx ny nz d is the facet's "
                     "plane (unit outward normal, offset)\n"
                     "element vertex %u\n"
                     "property double x\nproperty double y\n"
                     "property double z\n"
                     "element face %u\n"
                     "property list %s uint vertex_indices\n"
                     "property double nx\nproperty double ny\n"
                     "property double nz\nproperty double d\n"
                     "end_header\n",
                     ascii ? "ascii" : "binary_little_endian", p->nverts,
                     p->nfacets, wide ? "uint" : "uchar");
    for (uint32_t i = 0; i < p->nverts; i++)
        for (int k = 0; k < 3; k++) {
            if (!ascii) {
                proto_buf_f64le(b, p->verts[i][k]);
                continue;
            }
            proto_buf_double(b, p->verts[i][k]);
            proto_buf_puts(b, k < 2 ? " " : "\n");
        }
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *v = geo_poly_facet(p, f);
        if (ascii) {
            proto_buf_printf(b, "%u", n);
            for (uint32_t i = 0; i < n; i++)
                proto_buf_printf(b, " %u", v[i]);
            for (int k = 0; k < 4; k++) {
                proto_buf_puts(b, " ");
                proto_buf_double(b, p->planes[f][k]);
            }
            proto_buf_puts(b, "\n");
            continue;
        }
        if (wide)
            proto_buf_u32le(b, n);
        else
            proto_buf_append(b, &(unsigned char){(unsigned char)n}, 1);
        for (uint32_t i = 0; i < n; i++)
            proto_buf_u32le(b, v[i]);
        for (int k = 0; k < 4; k++)
            proto_buf_f64le(b, p->planes[f][k]);
    }
    return 0;
}
