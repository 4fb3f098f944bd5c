/* model_off.c — Geomview's OFF, the text form geometry libraries ship
 * their test meshes in. A header keyword "[ST][C][N][4][n]OFF" (texture
 * coordinates, colours, normals, homogeneous coordinates, a dimension
 * line), then "NVertices NFaces [NEdges]" (on the keyword's line or the
 * next one), one vertex per line ("x y z" followed by whatever the
 * prefixes add: normals, colours, texture coordinates — ignored), and one
 * polygon per line ("n i0 ... i(n-1)" with 0-based indices, then an
 * optional colour: numbers, ignored). '#' starts a comment; blank lines
 * are skipped. 4OFF vertices carry a fourth coordinate w, divided out.
 * The binary form ("OFF BINARY") and dimensions other than 3 are refused
 * by name.
 *
 * The claimed counts are checked against the limits and against the
 * bytes present (a vertex or polygon line needs at least 6 bytes)
 * before anything is allocated for them. Errors name the line
 * ("line 12: facets[3].vertices[1]: index 9 out of range (8 vertices)").
 * OFF has no planes: they are computed by least squares. Writing emits
 * "OFF", the counts (edges as 0, as most writers do) and the shortest
 * exact decimals, so an OFF round trip keeps every coordinate. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model_codec.h"

/* What the header keyword announced. */
typedef struct off_header {
    bool homogeneous; /* 4OFF: x y z w */
    bool ndim;        /* nOFF: a dimension precedes the counts */
} off_header;

/* The next logical line: comments cut, blank lines skipped. False at the
 * end of the text. */
static bool next_line(proto_scan *s, const char **line, size_t *n,
                      uint32_t *ln)
{
    while (proto_scan_line(s, line, n)) {
        *ln = s->tok_line;
        const char *hash = memchr(*line, '#', *n);
        if (hash)
            *n = (size_t)(hash - *line);
        while (*n > 0 && ((*line)[*n - 1] == ' ' || (*line)[*n - 1] == '\t' ||
                          (*line)[*n - 1] == '\r'))
            (*n)--;
        if (*n > 0)
            return true;
    }
    return false;
}

/* Parses the keyword token; false when it is not one. */
static bool parse_keyword(const char *t, size_t n, off_header *h)
{
    size_t i = 0;
    memset(h, 0, sizeof *h);
    if (i + 2 <= n && memcmp(t + i, "ST", 2) == 0)
        i += 2;
    if (i < n && t[i] == 'C')
        i++;
    if (i < n && t[i] == 'N')
        i++;
    if (i < n && t[i] == '4') {
        h->homogeneous = true;
        i++;
    }
    if (i < n && t[i] == 'n') {
        h->ndim = true;
        i++;
    }
    return n - i == 3 && memcmp(t + i, "OFF", 3) == 0;
}

static int count_token(proto_scan *ls, uint32_t line, const char *what,
                       uint32_t *ret, geo_err *err)
{
    const char *t;
    size_t n;
    char shown[32];
    if (!proto_scan_token(ls, &t, &n))
        return geo_err_set(err, -EINVAL, "line %u: expected the %s", line,
                           what);
    int e = proto_parse_u32(t, n, ret);
    if (e < 0)
        return geo_err_set(err, -EINVAL, "line %u: %s: %s, found \"%s\"",
                           line, what,
                           e == -ERANGE ? "count out of range"
                                        : "expected a count",
                           proto_tok_show(t, n, shown));
    return 0;
}

/* The rest of a line must be numbers (colours, normals, texture
 * coordinates): garbage there is more likely a broken file than data. */
static int check_numbers(proto_scan *ls, uint32_t line, const char *place,
                         geo_err *err)
{
    const char *t;
    size_t n;
    while (proto_scan_token(ls, &t, &n)) {
        double d;
        char shown[32];
        if (proto_parse_double(t, n, &d) < 0)
            return geo_err_set(err, -EINVAL,
                               "line %u: %s: expected a number (colour, "
                               "normal or texture coordinate), found \"%s\"",
                               line, place, proto_tok_show(t, n, shown));
    }
    return 0;
}

static int read_vertex(proto_scan *ls, geo_poly *p, const off_header *h,
                       uint32_t line, geo_err *err)
{
    uint32_t i = p->nverts;
    int ncoords = h->homogeneous ? 4 : 3;
    double c[4];
    int e = proto_scan_coords(ls, line, i, ncoords, c, err);
    if (e < 0)
        return e;
    if (h->homogeneous) {
        if (!(c[3] != 0))
            return geo_err_set(err, -EINVAL,
                               "line %u: vertices[%u][3]: the homogeneous "
                               "coordinate w is zero", line, i);
        for (int k = 0; k < 3; k++)
            c[k] /= c[3];
    }
    for (int k = 0; k < 3; k++)
        p->verts[i][k] = c[k];
    char place[32];
    snprintf(place, sizeof place, "vertices[%u]", i);
    int r = check_numbers(ls, line, place, err);
    if (r < 0)
        return r;
    p->nverts++;
    return 0;
}

static int read_face(proto_scan *ls, geo_poly *p, const proto_limits *lim,
                     uint32_t line, geo_err *err)
{
    uint32_t f = p->nfacets;
    size_t nc = geo_poly_ncorners(p);
    uint32_t count;
    char what[48];
    snprintf(what, sizeof what, "facets[%u]: vertex count", f);
    int r = count_token(ls, line, what, &count, err);
    if (r < 0)
        return r;
    if (count < 3)
        return geo_err_set(err, -EINVAL,
                           "line %u: facets[%u]: %u vertices, a facet needs "
                           "at least 3", line, f, count);
    if (proto_check_limits(lim, 0, 0, (uint64_t)nc + count, err) < 0) {
        char where[32];
        snprintf(where, sizeof where, "line %u", line);
        geo_err_prefix(err, where);
        return -ERANGE;
    }
    /* a polygon line holds at least 2 bytes per index */
    if ((size_t)count > (size_t)(ls->end - ls->p) / 2 + 1)
        return geo_err_set(err, -EINVAL,
                           "line %u: facets[%u]: %u vertices announced, the "
                           "line holds fewer", line, f, count);
    if (geo_poly_reserve(p, 0, (size_t)f + 1, nc + count) < 0)
        return geo_err_set(err, -ENOMEM, "out of memory");
    uint32_t *dst = p->fidx + nc;
    for (uint32_t k = 0; k < count; k++) {
        const char *t;
        size_t n;
        char shown[32];
        uint32_t v;
        if (!proto_scan_token(ls, &t, &n))
            return geo_err_set(err, -EINVAL,
                               "line %u: facets[%u]: %u vertices announced, "
                               "%u given", line, f, count, k);
        if (proto_parse_u32(t, n, &v) < 0)
            return geo_err_set(err, -EINVAL,
                               "line %u: facets[%u].vertices[%u]: expected a "
                               "vertex index, found \"%s\"", line, f, k,
                               proto_tok_show(t, n, shown));
        if (v >= p->nverts)
            return geo_err_set(err, -EINVAL,
                               "line %u: facets[%u].vertices[%u]: index %u "
                               "out of range (%u vertices, 0-based)", line, f,
                               k, v, p->nverts);
        if (k > 0 && v == dst[k - 1])
            return geo_err_set(err, -EINVAL,
                               "line %u: facets[%u].vertices[%u]: index %u "
                               "repeated consecutively", line, f, k, v);
        dst[k] = v;
    }
    if (dst[0] == dst[count - 1])
        return geo_err_set(err, -EINVAL,
                           "line %u: facets[%u].vertices[0]: index %u "
                           "repeated consecutively", line, f, dst[0]);
    char place[48];
    snprintf(place, sizeof place, "facets[%u].colour", f);
    r = check_numbers(ls, line, place, err);
    if (r < 0)
        return r;
    p->fstart[f + 1] = (uint32_t)(nc + count);
    p->nfacets = f + 1;
    return 0;
}

/* ls continues on the current header line when tokens are left on it,
 * else on the next logical line. */
static int header_more(proto_scan *s, proto_scan *ls, uint32_t *ln,
                       const char *what, geo_err *err)
{
    while (ls->p < ls->end && (*ls->p == ' ' || *ls->p == '\t'))
        ls->p++;
    if (ls->p < ls->end)
        return 0;
    const char *line;
    size_t n;
    if (!next_line(s, &line, &n, ln))
        return geo_err_set(err, -EINVAL, "line %u: the file ends, expected "
                                         "the %s", s->line, what);
    proto_scan_init(ls, line, n, false);
    return 0;
}

/* Reads the keyword and the counts; leaves s after the counts' line. */
static int read_header(proto_scan *s, off_header *h, uint32_t *nv,
                       uint32_t *nf, geo_err *err)
{
    const char *line, *t;
    size_t n, tn;
    uint32_t ln;
    char shown[32];
    if (!next_line(s, &line, &n, &ln))
        return geo_err_set(err, -EINVAL, "line %u: empty file, expected the "
                                         "OFF keyword", s->line);
    proto_scan ls;
    proto_scan_init(&ls, line, n, false);
    proto_scan_token(&ls, &t, &tn);
    if (!parse_keyword(t, tn, h))
        return geo_err_set(err, -EINVAL,
                           "line %u: expected the OFF keyword ([ST][C][N][4]"
                           "[n]OFF), found \"%s\"", ln,
                           proto_tok_show(t, tn, shown));
    proto_scan peek = ls;
    if (proto_scan_token(&peek, &t, &tn) && tn == 6 &&
        memcmp(t, "BINARY", 6) == 0)
        return geo_err_set(err, -EINVAL, "line %u: binary OFF is not "
                                         "supported (convert it to text)",
                           ln);
    int r;
    if (h->ndim) {
        uint32_t dim;
        r = header_more(s, &ls, &ln, "dimension", err);
        if (r == 0)
            r = count_token(&ls, ln, "dimension", &dim, err);
        if (r < 0)
            return r;
        if (dim != 3)
            return geo_err_set(err, -EINVAL,
                               "line %u: dimension %u: only 3-dimensional "
                               "OFF is supported", ln, dim);
    }
    r = header_more(s, &ls, &ln, "vertex and facet counts", err);
    if (r == 0)
        r = count_token(&ls, ln, "vertex count", nv, err);
    if (r == 0)
        r = count_token(&ls, ln, "facet count", nf, err);
    if (r < 0)
        return r;
    uint32_t ne;
    if (proto_scan_token(&ls, &t, &tn) && proto_parse_u32(t, tn, &ne) < 0)
        return geo_err_set(err, -EINVAL,
                           "line %u: edge count: expected a count, found "
                           "\"%s\"", ln, proto_tok_show(t, tn, shown));
    if (proto_scan_token(&ls, &t, &tn))
        return geo_err_set(err, -EINVAL,
                           "line %u: unexpected \"%s\" after the counts", ln,
                           proto_tok_show(t, tn, shown));
    return 0;
}

geo_poly *proto_off_read(const void *data, size_t len,
                         const proto_limits *lim, proto_read_report *rep,
                         geo_err *err)
{
    (void)rep;
    proto_scan s;
    proto_scan_init(&s, data, len, false);
    off_header h;
    uint32_t nv, nf;
    if (read_header(&s, &h, &nv, &nf, err) < 0)
        return NULL;
    if (proto_check_limits(lim, nv, nf, 0, err) < 0)
        return NULL;
    size_t left = (size_t)(s.end - s.p);
    if (((uint64_t)nv + nf) * 6 > (uint64_t)left + 1) {
        geo_err_set(err, -EINVAL,
                    "line %u: %u vertices and %u facets announced, the %zu "
                    "bytes left cannot hold them", s.tok_line, nv, nf, left);
        return NULL;
    }
    geo_poly *p = proto_poly_alloc(nv, nf, (uint64_t)nf * 3, NULL, err);
    if (!p)
        return NULL;
    const char *line;
    size_t n;
    uint32_t ln = s.tok_line;
    for (uint64_t k = 0; k < (uint64_t)nv + nf; k++) {
        if (!next_line(&s, &line, &n, &ln)) {
            if (k < nv)
                geo_err_set(err, -EINVAL,
                            "line %u: vertices[%u]: the file ends (%u "
                            "vertices announced)", s.line, p->nverts, nv);
            else
                geo_err_set(err, -EINVAL,
                            "line %u: facets[%u]: the file ends (%u facets "
                            "announced)", s.line, p->nfacets, nf);
            return geo_poly_free(p);
        }
        proto_scan ls;
        proto_scan_init(&ls, line, n, false);
        int e = k < nv ? read_vertex(&ls, p, &h, ln, err)
                       : read_face(&ls, p, lim, ln, err);
        if (e < 0)
            return geo_poly_free(p);
    }
    if (next_line(&s, &line, &n, &ln)) {
        char shown[32];
        geo_err_set(err, -EINVAL,
                    "line %u: unexpected \"%s\" after the last facet (%u "
                    "announced)", ln, proto_tok_show(line, n, shown), nf);
        return geo_poly_free(p);
    }
    return proto_read_done(p, NULL, lim, rep, err);
}

int proto_off_write(const geo_poly *p, proto_buf *b, geo_err *err)
{
    (void)err;
    proto_buf_printf(b, "OFF\n# %u vertices, %u facets (counter-clockwise "
                        "seen from outside), millimetres\n%u %u 0\n",
                     p->nverts, p->nfacets, p->nverts, p->nfacets);
    proto_buf_vertex_lines(b, p, "");
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *v = geo_poly_facet(p, f);
        proto_buf_u32(b, n);
        for (uint32_t i = 0; i < n; i++) {
            proto_buf_puts(b, " ");
            proto_buf_u32(b, v[i]);
        }
        proto_buf_puts(b, "\n");
    }
    return 0;
}
