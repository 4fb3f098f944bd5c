/* model_stl.c — STL, binary and ASCII. STL stores loose triangles, so
 * reading merges vertices whose coordinates are exactly equal (a hash on
 * the coordinates; −0 and +0 are one value) and writing splits every
 * facet into triangles (lib/core/polygon_triangulate.h).
 *
 * Telling the two forms apart: a file whose size is exactly 84 + 50·n,
 * n being the triangle count at byte 80, is binary even if it starts with
 * "solid" (many exporters write that into the binary header); otherwise a
 * file that starts with "solid" and contains no NUL byte is ASCII; any
 * other file is binary, and a size that disagrees with its count is an
 * error (a truncated file).
 *
 * Exactness: binary STL holds IEEE binary32 coordinates, so a binary round
 * trip is exact only for coordinates representable as floats (others are
 * rounded to the nearest float; a coordinate beyond the float range is an
 * error on writing). ASCII STL is written with the shortest decimals that
 * read back as the same doubles, so an ASCII round trip keeps positions
 * exactly. Either way the facets come back as triangles, vertices in
 * order of first use, unused vertices dropped, planes recomputed. A
 * triangle whose corners merge into fewer than 3 vertices is an error. */
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "model_codec.h"
#include "polygon_triangulate.h"

/* Open-addressing hash from exact coordinates to vertex numbers of p. */
typedef struct merger {
    geo_poly *p;
    uint32_t *slots; /* vertex number + 1, 0 = empty */
    size_t mask;
    uint32_t max_vertices;
} merger;

static uint64_t mix(uint64_t h)
{
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ULL;
    return h ^ (h >> 33);
}

static size_t hash_point(const double v[3])
{
    uint64_t h = 0x9e3779b97f4a7c15ULL;
    for (int k = 0; k < 3; k++) {
        uint64_t u;
        memcpy(&u, &v[k], 8);
        h = mix(h ^ u);
    }
    return (size_t)h;
}

static int merger_init(merger *m, geo_poly *p, size_t expect, uint32_t maxv)
{
    size_t cap = 64;
    while (cap < 2 * expect)
        cap *= 2;
    m->p = p;
    m->slots = calloc(cap, sizeof *m->slots);
    m->mask = cap - 1;
    m->max_vertices = maxv;
    return m->slots ? 0 : -ENOMEM;
}

static int merger_grow(merger *m)
{
    size_t cap = 2 * (m->mask + 1);
    uint32_t *s = calloc(cap, sizeof *s);
    if (!s)
        return -ENOMEM;
    for (uint32_t i = 0; i < m->p->nverts; i++) {
        size_t h = hash_point(m->p->verts[i]) & (cap - 1);
        while (s[h])
            h = (h + 1) & (cap - 1);
        s[h] = i + 1;
    }
    free(m->slots);
    m->slots = s;
    m->mask = cap - 1;
    return 0;
}

/* The number of the vertex at xyz, added if new. 0, -ENOMEM or -ERANGE
 * (more vertices than the limit). */
static int merge(merger *m, const double xyz[3], uint32_t *ret)
{
    double v[3];
    for (int k = 0; k < 3; k++)
        v[k] = xyz[k] + 0.0; /* −0 becomes +0: one key for one value */
    size_t h = hash_point(v) & m->mask;
    while (m->slots[h]) {
        uint32_t i = m->slots[h] - 1;
        if (memcmp(m->p->verts[i], v, sizeof v) == 0) {
            *ret = i;
            return 0;
        }
        h = (h + 1) & m->mask;
    }
    if (m->p->nverts >= m->max_vertices)
        return -ERANGE;
    int64_t i = geo_poly_add_vertex(m->p, v);
    if (i < 0)
        return (int)i;
    m->slots[h] = (uint32_t)i + 1;
    *ret = (uint32_t)i;
    if (2 * (size_t)m->p->nverts > m->mask)
        return merger_grow(m);
    return 0;
}

/* Adds triangle tri (vertex numbers); place names it in errors. */
static int add_triangle(geo_poly *p, const uint32_t tri[3], const char *place,
                        geo_err *err)
{
    for (int k = 0; k < 3; k++)
        if (tri[k] == tri[(k + 1) % 3])
            return geo_err_set(err, -EINVAL,
                               "%s: corners %d and %d are the same point "
                               "(degenerate triangle)", place, k,
                               (k + 1) % 3);
    if (geo_poly_add_facet(p, tri, 3) < 0)
        return geo_err_set(err, -ENOMEM, "out of memory");
    return 0;
}

static int merge_error(int e, const char *place, uint32_t maxv, geo_err *err)
{
    if (e == -ERANGE)
        return geo_err_set(err, -ERANGE,
                           "%s: vertices: more than the limit of %u", place,
                           maxv);
    return geo_err_set(err, -ENOMEM, "out of memory");
}

/* The end of both readers: the merger's table freed, then p completed
 * (ok) or freed. */
static geo_poly *read_end(merger *m, geo_poly *p, bool ok,
                          const proto_limits *lim, proto_read_report *rep,
                          geo_err *err)
{
    free(m->slots);
    return ok ? proto_read_done(p, NULL, lim, rep, err) : geo_poly_free(p);
}

static geo_poly *read_binary(const unsigned char *d, size_t len,
                             const proto_limits *lim, proto_read_report *rep,
                             geo_err *err)
{
    uint32_t nt = proto_ld_u32le(d + 80);
    if (84 + 50 * (uint64_t)nt != len) {
        geo_err_set(err, -EINVAL,
                    "byte 80: %u triangles need %llu bytes, the file has %zu "
                    "(truncated, or not an STL file)", nt,
                    84 + 50 * (unsigned long long)nt, len);
        return NULL;
    }
    if (proto_check_limits(lim, 0, nt, 3 * (uint64_t)nt, err) < 0) {
        geo_err_prefix(err, "byte 80");
        return NULL;
    }
    geo_poly *p = geo_poly_new();
    merger m = {0};
    if (!p || geo_poly_reserve(p, nt, nt, 3 * (size_t)nt) < 0 ||
        merger_init(&m, p, nt, lim->max_vertices) < 0) {
        geo_err_set(err, -ENOMEM, "out of memory");
        goto fail;
    }
    for (uint32_t t = 0; t < nt; t++) {
        size_t o = 84 + 50 * (size_t)t;
        char place[64];
        uint32_t tri[3];
        for (int c = 0; c < 3; c++) {
            double v[3];
            for (int k = 0; k < 3; k++) {
                size_t at = o + 12 + 12 * (size_t)c + 4 * (size_t)k;
                v[k] = proto_ld_f32le(d + at);
                if (!isfinite(v[k])) {
                    geo_err_set(err, -EINVAL,
                                "byte %zu: triangle %u, corner %d: not a "
                                "finite number", at, t, c);
                    goto fail;
                }
            }
            int e = merge(&m, v, &tri[c]);
            if (e < 0) {
                snprintf(place, sizeof place, "byte %zu", o);
                merge_error(e, place, lim->max_vertices, err);
                goto fail;
            }
        }
        snprintf(place, sizeof place, "byte %zu: triangle %u", o, t);
        if (add_triangle(p, tri, place, err) < 0)
            goto fail;
    }
    return read_end(&m, p, true, lim, rep, err);
fail:
    return read_end(&m, p, false, lim, rep, err);
}

static bool keyword(const char *t, size_t n, const char *kw)
{
    return n == strlen(kw) && strncasecmp(t, kw, n) == 0;
}

/* Reads the next token and requires it to be kw. */
static int expect(proto_scan *s, const char *kw, geo_err *err)
{
    const char *t;
    size_t n;
    char shown[32];
    if (!proto_scan_token(s, &t, &n))
        return geo_err_set(err, -EINVAL,
                           "line %u: expected \"%s\", found the end of the "
                           "file", s->line, kw);
    if (!keyword(t, n, kw))
        return geo_err_set(err, -EINVAL,
                           "line %u: expected \"%s\", found \"%s\"",
                           s->tok_line, kw, proto_tok_show(t, n, shown));
    return 0;
}

static int ascii_numbers(proto_scan *s, double *v, const char *what,
                         geo_err *err)
{
    for (int k = 0; k < 3; k++) {
        const char *t;
        size_t n;
        char shown[32];
        if (!proto_scan_token(s, &t, &n))
            return geo_err_set(err, -EINVAL,
                               "line %u: %s: expected 3 numbers, found the "
                               "end of the file", s->line, what);
        int e = proto_parse_double(t, n, &v[k]);
        if (e < 0)
            return geo_err_set(err, -EINVAL, "line %u: %s: %s, found \"%s\"",
                               s->tok_line, what,
                               e == -ERANGE ? "number out of range"
                                            : "expected a number",
                               proto_tok_show(t, n, shown));
    }
    return 0;
}

/* One "facet normal … endfacet" block after its "facet" keyword. A loop
 * of more than 3 vertices (some writers emit polygons) is kept whole. */
static int ascii_facet(proto_scan *s, merger *m, const proto_limits *lim,
                       geo_err *err)
{
    geo_poly *p = m->p;
    uint32_t f = p->nfacets, line = s->tok_line;
    double v[3];
    if (expect(s, "normal", err) < 0 ||
        ascii_numbers(s, v, "facet normal", err) < 0 ||
        expect(s, "outer", err) < 0 || expect(s, "loop", err) < 0)
        return -EINVAL;
    size_t nc = geo_poly_ncorners(p);
    uint32_t count = 0;
    for (;;) {
        const char *t;
        size_t n;
        char shown[32];
        if (!proto_scan_token(s, &t, &n))
            return geo_err_set(err, -EINVAL,
                               "line %u: facet %u: unexpected end of file",
                               s->line, f);
        if (keyword(t, n, "endloop"))
            break;
        if (!keyword(t, n, "vertex"))
            return geo_err_set(err, -EINVAL,
                               "line %u: expected \"vertex\" or \"endloop\", "
                               "found \"%s\"", s->tok_line,
                               proto_tok_show(t, n, shown));
        if (ascii_numbers(s, v, "vertex", err) < 0)
            return -EINVAL;
        uint32_t vi;
        int e = merge(m, v, &vi);
        char place[32];
        snprintf(place, sizeof place, "line %u", s->tok_line);
        if (e < 0)
            return merge_error(e, place, lim->max_vertices, err);
        if (proto_check_limits(lim, 0, (uint64_t)f + 1, nc + count + 1,
                               err) < 0) {
            geo_err_prefix(err, place);
            return -ERANGE;
        }
        if (geo_poly_reserve(p, 0, (size_t)f + 1, nc + count + 1) < 0)
            return geo_err_set(err, -ENOMEM, "out of memory");
        p->fidx[nc + count] = vi;
        if (count > 0 && p->fidx[nc + count - 1] == vi)
            return geo_err_set(err, -EINVAL,
                               "line %u: facet %u: vertex %u repeats the one "
                               "before it (degenerate facet)", s->tok_line, f,
                               count);
        count++;
    }
    if (count < 3)
        return geo_err_set(err, -EINVAL,
                           "line %u: facet %u: %u vertices, a facet needs at "
                           "least 3", line, f, count);
    if (p->fidx[nc] == p->fidx[nc + count - 1])
        return geo_err_set(err, -EINVAL,
                           "line %u: facet %u: the last vertex repeats the "
                           "first (degenerate facet)", line, f);
    p->fstart[f + 1] = (uint32_t)(nc + count);
    memset(p->planes[f], 0, sizeof p->planes[f]);
    p->nfacets = f + 1;
    return expect(s, "endfacet", err);
}

static geo_poly *read_ascii(const void *data, size_t len,
                            const proto_limits *lim, proto_read_report *rep,
                            geo_err *err)
{
    proto_scan s;
    proto_scan_init(&s, data, len, false);
    geo_poly *p = geo_poly_new();
    merger m = {0};
    if (!p || merger_init(&m, p, 1024, lim->max_vertices) < 0) {
        geo_err_set(err, -ENOMEM, "out of memory");
        goto fail;
    }
    const char *t, *rest;
    size_t n, rn;
    bool in_solid = false;
    while (proto_scan_token(&s, &t, &n)) {
        char shown[32];
        if (!in_solid) {
            if (!keyword(t, n, "solid")) {
                geo_err_set(err, -EINVAL, "line %u: expected \"solid\", "
                                          "found \"%s\"", s.tok_line,
                            proto_tok_show(t, n, shown));
                goto fail;
            }
            proto_scan_line(&s, &rest, &rn); /* the solid's name */
            in_solid = true;
        } else if (keyword(t, n, "facet")) {
            if (ascii_facet(&s, &m, lim, err) < 0)
                goto fail;
        } else if (keyword(t, n, "endsolid")) {
            proto_scan_line(&s, &rest, &rn);
            in_solid = false;
        } else {
            geo_err_set(err, -EINVAL, "line %u: expected \"facet\" or "
                                      "\"endsolid\", found \"%s\"",
                        s.tok_line, proto_tok_show(t, n, shown));
            goto fail;
        }
    }
    if (in_solid) {
        geo_err_set(err, -EINVAL, "line %u: expected \"endsolid\", found the "
                                  "end of the file", s.line);
        goto fail;
    }
    return read_end(&m, p, true, lim, rep, err);
fail:
    return read_end(&m, p, false, lim, rep, err);
}

static bool starts_with_solid(const unsigned char *d, size_t len)
{
    size_t i = 0;
    while (i < len && (d[i] == ' ' || d[i] == '\t' || d[i] == '\r' ||
                       d[i] == '\n'))
        i++;
    return len - i >= 5 && strncasecmp((const char *)d + i, "solid", 5) == 0;
}

geo_poly *proto_stl_read(const void *data, size_t len,
                         const proto_limits *lim, proto_read_report *rep,
                         geo_err *err)
{
    const unsigned char *d = data;
    if (len >= 84 && 84 + 50 * (uint64_t)proto_ld_u32le(d + 80) == len)
        return read_binary(d, len, lim, rep, err);
    if (starts_with_solid(d, len) && !memchr(d, 0, len))
        return read_ascii(data, len, lim, rep, err);
    if (len >= 84)
        return read_binary(d, len, lim, rep, err);
    geo_err_set(err, -EINVAL,
                "%zu bytes: neither an ASCII STL (\"solid ...\") nor a binary "
                "one (84 bytes at least)", len);
    return NULL;
}

static void emit_binary(const geo_poly *p, uint32_t f, const uint32_t *q,
                        void *arg)
{
    proto_buf *b = arg;
    const uint32_t *v = geo_poly_facet(p, f);
    for (int k = 0; k < 3; k++)
        proto_buf_f32le(b, (float)p->planes[f][k]);
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < 3; k++)
            proto_buf_f32le(b, (float)p->verts[v[q[c]]][k]);
    proto_buf_u16le(b, 0);
}

static void emit_ascii(const geo_poly *p, uint32_t f, const uint32_t *q,
                       void *arg)
{
    proto_buf *b = arg;
    const uint32_t *v = geo_poly_facet(p, f);
    proto_buf_puts(b, "  facet normal");
    for (int k = 0; k < 3; k++) {
        proto_buf_puts(b, " ");
        proto_buf_double(b, p->planes[f][k]);
    }
    proto_buf_puts(b, "\n    outer loop\n");
    for (int c = 0; c < 3; c++) {
        proto_buf_puts(b, "      vertex");
        for (int k = 0; k < 3; k++) {
            proto_buf_puts(b, " ");
            proto_buf_double(b, p->verts[v[q[c]]][k]);
        }
        proto_buf_puts(b, "\n");
    }
    proto_buf_puts(b, "    endloop\n  endfacet\n");
}

int proto_stl_write(const geo_poly *p, bool ascii, proto_buf *b,
                    geo_err *err)
{
    if (ascii) {
        proto_buf_puts(b, "solid facetd\n");
        int e = proto_each_triangle(p, emit_ascii, b, err);
        proto_buf_puts(b, "endsolid facetd\n");
        return e;
    }
    for (uint32_t i = 0; i < p->nverts; i++)
        for (int k = 0; k < 3; k++)
            if (fabs(p->verts[i][k]) > FLT_MAX)
                return geo_err_set(err, -ERANGE,
                                   "vertices[%u][%d]: %g does not fit the "
                                   "32-bit floats of binary STL", i, k,
                                   p->verts[i][k]);
    uint64_t nt = geo_poly_ncorners(p) - 2 * (uint64_t)p->nfacets;
    if (nt > UINT32_MAX)
        return geo_err_set(err, -ERANGE, "%llu triangles are too many for "
                                         "binary STL",
                           (unsigned long long)nt);
    /* the header must not begin with "solid": readers would take the
     * file for ASCII */
    char header[80];
    memset(header, ' ', sizeof header);
    static const char title[] = "binary STL from facetd, millimetres";
    memcpy(header, title, sizeof title - 1);
    proto_buf_append(b, header, sizeof header);
    proto_buf_u32le(b, (uint32_t)nt);
    return proto_each_triangle(p, emit_binary, b, err);
}
