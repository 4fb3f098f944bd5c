/* model_obj.c — Wavefront OBJ, the geometry part: "v x y z" vertices and
 * "f" polygonal faces whose corners are "i", "i/t", "i//n" or "i/t/n"
 * (only i is used). Indices are 1-based; a negative index counts back
 * from the last vertex defined so far (-1 is the latest). Faces are kept
 * as polygons; extra vertex components (w, colours) and every other
 * statement (vt, vn, g, o, s, usemtl, l, ...) are ignored; '#' starts a
 * comment.
 *
 * A first pass counts the "v" and "f" statements, so the limits are
 * checked and the vertex array sized before the model is built, and a
 * positive index may refer to a vertex defined later in the file. OBJ has
 * no planes: they are computed by least squares. Errors name the line
 * ("line 17: facets[4].vertices[3]: index 9 out of range (8 vertices)").
 * Writing emits v and f lines with the shortest exact decimals. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model_codec.h"

/* The statement keyword of a line: "v" or "f" (exactly), else other. */
enum stmt { STMT_OTHER, STMT_V, STMT_F };

static enum stmt statement(const char *line, size_t n)
{
    if (n >= 1 && (n == 1 || line[1] == ' ' || line[1] == '\t')) {
        if (line[0] == 'v')
            return STMT_V;
        if (line[0] == 'f')
            return STMT_F;
    }
    return STMT_OTHER;
}

static int read_vertex(proto_scan *ls, geo_poly *p, uint32_t line,
                       geo_err *err)
{
    int e = proto_scan_coords(ls, line, p->nverts, 3, p->verts[p->nverts],
                              err);
    if (e < 0)
        return e;
    p->nverts++;
    return 0;
}

static int read_face(proto_scan *ls, geo_poly *p, uint32_t total_verts,
                     const proto_limits *lim, uint32_t line, geo_err *err)
{
    uint32_t f = p->nfacets;
    size_t nc = geo_poly_ncorners(p);
    const char *t;
    size_t n;
    uint32_t count = 0;
    while (proto_scan_token(ls, &t, &n)) {
        char shown[32];
        const char *slash = memchr(t, '/', n);
        size_t vl = slash ? (size_t)(slash - t) : n;
        int64_t v;
        if (proto_parse_i64(t, vl, &v) < 0)
            return geo_err_set(err, -EINVAL,
                               "line %u: facets[%u].vertices[%u]: expected a "
                               "vertex index, found \"%s\"", line, f, count,
                               proto_tok_show(t, n, shown));
        /* negative: relative to the vertices defined so far */
        int64_t idx = v < 0 ? (int64_t)p->nverts + v : v - 1;
        if (v == 0 || idx < 0 || idx >= (int64_t)total_verts)
            return geo_err_set(err, -EINVAL,
                               "line %u: facets[%u].vertices[%u]: index %lld "
                               "out of range (%u vertices%s)", line, f, count,
                               (long long)v,
                               v < 0 ? p->nverts : total_verts,
                               v < 0 ? " so far" : ", 1-based");
        if (proto_check_limits(lim, 0, 0, nc + count + 1, err) < 0) {
            char where[32];
            snprintf(where, sizeof where, "line %u", line);
            geo_err_prefix(err, where);
            return -ERANGE;
        }
        if (geo_poly_reserve(p, 0, (size_t)f + 1, nc + count + 1) < 0)
            return geo_err_set(err, -ENOMEM, "out of memory");
        uint32_t *dst = p->fidx + nc;
        dst[count] = (uint32_t)idx;
        if (count > 0 && dst[count] == dst[count - 1])
            return geo_err_set(err, -EINVAL,
                               "line %u: facets[%u].vertices[%u]: index %lld "
                               "repeated consecutively", line, f, count,
                               (long long)idx + 1);
        count++;
    }
    if (count < 3)
        return geo_err_set(err, -EINVAL,
                           "line %u: facets[%u]: %u vertices, a facet needs "
                           "at least 3", line, f, count);
    if (p->fidx[nc] == p->fidx[nc + count - 1])
        return geo_err_set(err, -EINVAL,
                           "line %u: facets[%u].vertices[0]: index %u "
                           "repeated consecutively", line, f, p->fidx[nc] + 1);
    p->fstart[f + 1] = (uint32_t)(nc + count);
    p->nfacets = f + 1;
    return 0;
}

geo_poly *proto_obj_read(const void *data, size_t len,
                         const proto_limits *lim, proto_read_report *rep,
                         geo_err *err)
{
    proto_scan s;
    const char *line;
    size_t n;
    uint64_t nv = 0, nf = 0;
    proto_scan_init(&s, data, len, false);
    while (proto_scan_line(&s, &line, &n)) {
        enum stmt st = statement(line, n);
        nv += st == STMT_V;
        nf += st == STMT_F;
    }
    if (proto_check_limits(lim, nv, nf, 0, err) < 0)
        return NULL;
    geo_poly *p = proto_poly_alloc(nv, nf, nf * 3, NULL, err);
    if (!p)
        return NULL;
    proto_scan_init(&s, data, len, false);
    while (proto_scan_line(&s, &line, &n)) {
        uint32_t ln = s.tok_line;
        const char *hash = memchr(line, '#', n);
        if (hash)
            n = (size_t)(hash - line);
        enum stmt st = statement(line, n);
        if (st == STMT_OTHER)
            continue;
        proto_scan ls;
        proto_scan_init(&ls, line + 1, n - 1, false);
        int e = st == STMT_V ? read_vertex(&ls, p, ln, err)
                             : read_face(&ls, p, (uint32_t)nv, lim, ln, err);
        if (e < 0)
            return geo_poly_free(p);
    }
    return proto_read_done(p, NULL, lim, rep, err);
}

int proto_obj_write(const geo_poly *p, proto_buf *b, geo_err *err)
{
    (void)err;
    proto_buf_printf(b, "# %u vertices, %u facets (counter-clockwise seen "
                        "from outside), millimetres\n",
                     p->nverts, p->nfacets);
    proto_buf_vertex_lines(b, p, "v ");
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *v = geo_poly_facet(p, f);
        proto_buf_puts(b, "f");
        for (uint32_t i = 0; i < n; i++)
            proto_buf_printf(b, " %u", v[i] + 1);
        proto_buf_puts(b, "\n");
    }
    return 0;
}
