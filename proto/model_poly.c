/* model_poly.c — the paper's text format of a polyhedron (Palachev 2012, §1.3,
 * ".poly"): the number of vertices and the number of facets; x y z of
 * every vertex; then per facet its vertex count, its plane a b c d
 * (a·x+b·y+c·z+d = 0, normal outward) and its vertex indices (0-based,
 * counter-clockwise seen from outside, as in facet-model/1).
 *
 * Tokens are separated by any whitespace, so line breaks are free; '#'
 * starts a comment running to the end of the line. Errors name the line
 * and the place ("line 17: facets[3].vertices[1]: index 9 out of range
 * (8 vertices)"). The declared counts are checked against the limits and
 * against the input's length (every vertex needs at least 6 bytes, every
 * facet 16) before anything is allocated, so a short file that claims a
 * huge model fails at once. Planes are given in this format: they are
 * checked like facet-model/1's (proto_read_report). Numbers are written
 * as the shortest decimal that reads back exactly. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model_codec.h"

typedef struct reader {
    proto_scan s;
    geo_err *err;
} reader;

/* The place of the token being read, formatted only for an error:
 * fmt takes up to two unsigned arguments ("facets[%u].plane[%u]"). */
static int fail_at(reader *r, const char *fmt, uint32_t a, uint32_t b,
                   const char *t, size_t n, const char *problem)
{
    char where[64], shown[32];
    snprintf(where, sizeof where, fmt, a, b);
    if (!t)
        return geo_err_set(r->err, -EINVAL,
                           "line %u: %s: unexpected end of file", r->s.line,
                           where);
    return geo_err_set(r->err, -EINVAL, "line %u: %s: %s, found \"%s\"",
                       r->s.tok_line, where, problem,
                       proto_tok_show(t, n, shown));
}

static int next_double(reader *r, double *ret, const char *fmt, uint32_t a,
                       uint32_t b)
{
    const char *t;
    size_t n;
    if (!proto_scan_token(&r->s, &t, &n))
        return fail_at(r, fmt, a, b, NULL, 0, NULL);
    int e = proto_parse_double(t, n, ret);
    if (e < 0)
        return fail_at(r, fmt, a, b, t, n,
                       e == -ERANGE ? "number out of range"
                                    : "expected a number");
    return 0;
}

static int next_u32(reader *r, uint32_t *ret, const char *fmt, uint32_t a,
                    uint32_t b)
{
    const char *t;
    size_t n;
    if (!proto_scan_token(&r->s, &t, &n))
        return fail_at(r, fmt, a, b, NULL, 0, NULL);
    if (proto_parse_u32(t, n, ret) < 0)
        return fail_at(r, fmt, a, b, t, n, "expected a non-negative integer");
    return 0;
}

static int over_limits(reader *r, const proto_limits *lim, uint64_t nv,
                       uint64_t nf, uint64_t nc)
{
    int e = proto_check_limits(lim, nv, nf, nc, r->err);
    if (e < 0) {
        char where[32];
        snprintf(where, sizeof where, "line %u", r->s.tok_line);
        geo_err_prefix(r->err, where);
    }
    return e;
}

static int read_facet(reader *r, geo_poly *p, uint32_t f)
{
    uint32_t n;
    int e = next_u32(r, &n, "facets[%u]: vertex count", f, 0);
    if (e < 0)
        return e;
    if (n < 3)
        return geo_err_set(r->err, -EINVAL,
                           "line %u: facets[%u]: %u vertices, a facet needs "
                           "at least 3", r->s.tok_line, f, n);
    /* every index needs at least 2 bytes: a count beyond the rest of the
     * input is a lie, refused before reserving room for it */
    if (n > (size_t)(r->s.end - r->s.p) / 2 + 1)
        return geo_err_set(r->err, -EINVAL,
                           "line %u: facets[%u]: %u vertices cannot fit in "
                           "the rest of the file", r->s.tok_line, f, n);
    size_t nc = geo_poly_ncorners(p);
    if (geo_poly_reserve(p, 0, (size_t)f + 1, nc + n) < 0)
        return geo_err_set(r->err, -ENOMEM, "out of memory");
    for (uint32_t k = 0; k < 4; k++)
        if ((e = next_double(r, &p->planes[f][k], "facets[%u].plane[%u]", f,
                             k)) < 0)
            return e;
    uint32_t *dst = p->fidx + nc;
    for (uint32_t i = 0; i < n; i++) {
        if ((e = next_u32(r, &dst[i], "facets[%u].vertices[%u]", f, i)) < 0)
            return e;
        if (dst[i] >= p->nverts)
            return geo_err_set(r->err, -EINVAL,
                               "line %u: facets[%u].vertices[%u]: index %u "
                               "out of range (%u vertices)", r->s.tok_line, f,
                               i, dst[i], p->nverts);
        if (i > 0 && dst[i] == dst[i - 1])
            return geo_err_set(r->err, -EINVAL,
                               "line %u: facets[%u].vertices[%u]: index %u "
                               "repeated consecutively", r->s.tok_line, f, i,
                               dst[i]);
    }
    if (dst[0] == dst[n - 1])
        return geo_err_set(r->err, -EINVAL,
                           "line %u: facets[%u].vertices[0]: index %u "
                           "repeated consecutively", r->s.tok_line, f,
                           dst[0]);
    p->fstart[f + 1] = (uint32_t)(nc + n);
    p->nfacets = f + 1;
    return 0;
}

geo_poly *proto_polytxt_read(const void *data, size_t len,
                             const proto_limits *lim, proto_read_report *rep,
                             geo_err *err)
{
    reader r = {.err = err};
    proto_scan_init(&r.s, data, len, true);
    uint32_t nv, nf;
    if (next_u32(&r, &nv, "number of vertices", 0, 0) < 0 ||
        next_u32(&r, &nf, "number of facets", 0, 0) < 0)
        return NULL;
    if (over_limits(&r, lim, nv, nf, 0) < 0)
        return NULL;
    size_t rest = (size_t)(r.s.end - r.s.p) + 1;
    if (nv > rest / 6 || nf > rest / 16) {
        geo_err_set(err, -EINVAL,
                    "line %u: %u vertices and %u facets cannot fit in the "
                    "remaining %zu bytes (file truncated?)", r.s.tok_line, nv,
                    nf, rest - 1);
        return NULL;
    }
    bool *given = NULL;
    geo_poly *p = proto_poly_alloc(nv, nf, (uint64_t)nf * 3, &given, err);
    if (!p)
        return NULL;
    for (uint32_t i = 0; i < nv; i++)
        for (uint32_t k = 0; k < 3; k++)
            if (next_double(&r, &p->verts[i][k], "vertices[%u][%u]", i, k) < 0)
                goto fail;
    p->nverts = nv;
    for (uint32_t f = 0; f < nf; f++) {
        if (read_facet(&r, p, f) < 0)
            goto fail;
        given[f] = true;
        if (over_limits(&r, lim, nv, nf, geo_poly_ncorners(p)) < 0)
            goto fail;
    }
    const char *t;
    size_t tl;
    if (proto_scan_token(&r.s, &t, &tl)) {
        char shown[32];
        geo_err_set(err, -EINVAL,
                    "line %u: unexpected \"%s\" after the last facet (the "
                    "header declares %u facets)", r.s.tok_line,
                    proto_tok_show(t, tl, shown), nf);
        goto fail;
    }
    return proto_read_done(p, given, lim, rep, err);
fail:
    free(given);
    return geo_poly_free(p);
}

int proto_polytxt_write(const geo_poly *p, proto_buf *b, geo_err *err)
{
    (void)err;
    proto_buf_puts(b, "# polyhedron: vertex and facet counts; x y z per "
                      "vertex; per facet: vertex count, plane a b c d "
                      "(outward), 0-based vertex indices counter-clockwise "
                      "from outside\n");
    proto_buf_printf(b, "%u %u\n", p->nverts, p->nfacets);
    proto_buf_vertex_lines(b, p, "");
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *v = geo_poly_facet(p, f);
        proto_buf_printf(b, "%u", n);
        for (int k = 0; k < 4; k++) {
            proto_buf_puts(b, " ");
            proto_buf_double(b, p->planes[f][k]);
        }
        for (uint32_t i = 0; i < n; i++)
            proto_buf_printf(b, " %u", v[i]);
        proto_buf_puts(b, "\n");
    }
    return 0;
}
