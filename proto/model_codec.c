/* model_codec.c — the pieces every model codec shares: the output buffer,
 * exact (shortest round-trip) number printing (proto/decimal.h),
 * little-endian loads and
 * stores, limit checks, and finishing the planes of a read model.
 * Invariant of proto_buf: data[0..len) is valid, len ≤ cap; once failed
 * is set the buffer never changes again. */
#include "model_codec.h"
#include "polygon_triangulate.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "decimal.h"
#include "vec.h"

static bool buf_reserve(proto_buf *b, size_t n)
{
    if (b->failed)
        return false;
    if (n <= b->cap - b->len)
        return true;
    if (n > SIZE_MAX / 2 - b->len) {
        b->failed = true;
        return false;
    }
    size_t cap = b->cap ? b->cap : 4096;
    while (cap - b->len < n)
        cap *= 2;
    char *d = realloc(b->data, cap);
    if (!d) {
        b->failed = true;
        return false;
    }
    b->data = d;
    b->cap = cap;
    return true;
}

void proto_buf_append(proto_buf *b, const void *bytes, size_t n)
{
    if (n == 0 || !buf_reserve(b, n))
        return;
    memcpy(b->data + b->len, bytes, n);
    b->len += n;
}

void proto_buf_puts(proto_buf *b, const char *s)
{
    proto_buf_append(b, s, strlen(s));
}

void proto_buf_printf(proto_buf *b, const char *fmt, ...)
{
    char small[256];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(small, sizeof small, fmt, ap);
    va_end(ap);
    if (n < 0) {
        b->failed = true;
        return;
    }
    if ((size_t)n < sizeof small) {
        proto_buf_append(b, small, (size_t)n);
        return;
    }
    if (!buf_reserve(b, (size_t)n + 1))
        return;
    va_start(ap, fmt);
    vsnprintf(b->data + b->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    b->len += (size_t)n;
}

void proto_buf_double(proto_buf *b, double x)
{
    if (!buf_reserve(b, PROTO_DECIMAL_MAX))
        return;
    b->len += proto_decimal_format(b->data + b->len, x);
}

void proto_buf_u32(proto_buf *b, uint32_t v)
{
    if (!buf_reserve(b, 10))
        return;
    char tmp[10];
    int n = 0;
    do {
        tmp[n++] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    for (int i = 0; i < n; i++)
        b->data[b->len + (size_t)i] = tmp[n - 1 - i];
    b->len += (size_t)n;
}

unsigned char *proto_buf_grow(proto_buf *b, size_t n)
{
    if (!buf_reserve(b, n))
        return NULL;
    unsigned char *at = (unsigned char *)b->data + b->len;
    b->len += n;
    return at;
}

void proto_buf_u16le(proto_buf *b, uint16_t v)
{
    unsigned char s[2] = {(unsigned char)v, (unsigned char)(v >> 8)};
    proto_buf_append(b, s, 2);
}

void proto_buf_u32le(proto_buf *b, uint32_t v)
{
    unsigned char s[4];
    for (int i = 0; i < 4; i++)
        s[i] = (unsigned char)(v >> (8 * i));
    proto_buf_append(b, s, 4);
}

void proto_buf_f32le(proto_buf *b, float v)
{
    uint32_t u;
    memcpy(&u, &v, 4);
    proto_buf_u32le(b, u);
}

void proto_buf_f64le(proto_buf *b, double v)
{
    uint64_t u;
    memcpy(&u, &v, 8);
    unsigned char s[8];
    for (int i = 0; i < 8; i++)
        s[i] = (unsigned char)(u >> (8 * i));
    proto_buf_append(b, s, 8);
}

void proto_scan_init(proto_scan *s, const void *data, size_t len,
                     bool hash_comments)
{
    s->p = data;
    s->end = s->p + len;
    s->line = 1;
    s->tok_line = 1;
    s->hash_comments = hash_comments;
}

static bool is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' ||
           c == '\f';
}

bool proto_scan_token(proto_scan *s, const char **ret, size_t *ret_len)
{
    for (;;) {
        while (s->p < s->end && is_space(*s->p)) {
            if (*s->p == '\n')
                s->line++;
            s->p++;
        }
        if (s->p < s->end && s->hash_comments && *s->p == '#') {
            while (s->p < s->end && *s->p != '\n')
                s->p++;
            continue;
        }
        break;
    }
    if (s->p == s->end)
        return false;
    const char *t = s->p;
    while (s->p < s->end && !is_space(*s->p) &&
           !(s->hash_comments && *s->p == '#'))
        s->p++;
    *ret = t;
    *ret_len = (size_t)(s->p - t);
    s->tok_line = s->line;
    return true;
}

bool proto_scan_line(proto_scan *s, const char **ret, size_t *ret_len)
{
    if (s->p == s->end)
        return false;
    const char *a = s->p;
    const char *nl = memchr(a, '\n', (size_t)(s->end - a));
    const char *b = nl ? nl : s->end;
    s->p = nl ? nl + 1 : s->end;
    s->tok_line = s->line;
    if (nl)
        s->line++;
    while (a < b && is_space(*a))
        a++;
    while (b > a && is_space(b[-1]))
        b--;
    *ret = a;
    *ret_len = (size_t)(b - a);
    return true;
}

int proto_parse_double(const char *tok, size_t len, double *ret)
{
    /* A number in JSON's grammar (what every writer prints, most tokens)
     * goes through the exact conversion of the JSON reader, which gives
     * strtod's double without its multi-precision path (half the time of
     * reading an OBJ was strtod); an integer keeps the sign of a zero as
     * strtod does. Anything else — a leading '+' or '.', a trailing '.',
     * leading zeros, more than 19 digits of an integer, an overflow — is
     * strtod's to accept or refuse, as before. */
    size_t end;
    bool is_int;
    int64_t integer;
    double r;
    if (proto_json_number(tok, len, 0, &end, &is_int, &integer, &r) &&
        end == len) {
        *ret = !is_int                           ? r
               : integer == 0 && tok[0] == '-' ? -0.0
                                                : (double)integer;
        return 0;
    }
    /* strtod needs a terminated string; longer tokens are no numbers a
     * writer would produce (the longest %.17g form has 24 bytes) */
    char buf[64];
    if (len == 0 || len >= sizeof buf)
        return -EINVAL;
    memcpy(buf, tok, len);
    buf[len] = '\0';
    char c = buf[0] == '-' || buf[0] == '+' ? buf[1] : buf[0];
    /* only decimal digits or '.': no "nan", "inf", hex floats */
    if (!((c >= '0' && c <= '9') || c == '.'))
        return -EINVAL;
    for (size_t i = 0; i < len; i++)
        if (buf[i] == 'x' || buf[i] == 'X')
            return -EINVAL;
    char *endp;
    errno = 0;
    double d = strtod(buf, &endp);
    if (endp != buf + len)
        return -EINVAL;
    if (!isfinite(d))
        return -ERANGE;
    *ret = d;
    return 0;
}

int proto_parse_u32(const char *tok, size_t len, uint32_t *ret)
{
    if (len == 0)
        return -EINVAL;
    uint64_t v = 0;
    for (size_t i = 0; i < len; i++) {
        if (tok[i] < '0' || tok[i] > '9')
            return -EINVAL;
        v = v * 10 + (uint64_t)(tok[i] - '0');
        if (v > UINT32_MAX)
            return -ERANGE;
    }
    *ret = (uint32_t)v;
    return 0;
}

int proto_parse_i64(const char *tok, size_t len, int64_t *ret)
{
    bool neg = len > 0 && tok[0] == '-';
    size_t i = neg || (len > 0 && tok[0] == '+') ? 1 : 0;
    if (i == len)
        return -EINVAL;
    int64_t v = 0;
    for (; i < len; i++) {
        if (tok[i] < '0' || tok[i] > '9')
            return -EINVAL;
        if (v > ((int64_t)1 << 62) / 10)
            return -ERANGE;
        v = v * 10 + (tok[i] - '0');
    }
    *ret = neg ? -v : v;
    return 0;
}

int proto_scan_coords(proto_scan *ls, uint32_t line, uint32_t i, int n,
                      double *c, geo_err *err)
{
    for (int k = 0; k < n; k++) {
        const char *t;
        size_t len;
        char shown[32];
        if (!proto_scan_token(ls, &t, &len))
            return geo_err_set(err, -EINVAL,
                               "line %u: vertices[%u]: expected %d numbers",
                               line, i, n);
        int e = proto_parse_double(t, len, &c[k]);
        if (e < 0)
            return geo_err_set(err, -EINVAL,
                               "line %u: vertices[%u][%d]: %s, found \"%s\"",
                               line, i, k,
                               e == -ERANGE ? "number out of range"
                                            : "expected a number",
                               proto_tok_show(t, len, shown));
    }
    return 0;
}

const char *proto_tok_show(const char *tok, size_t len, char *out)
{
    size_t n = len > 24 ? 24 : len;
    for (size_t i = 0; i < n; i++) {
        unsigned char c = (unsigned char)tok[i];
        out[i] = c >= 0x20 && c < 0x7f ? (char)c : '?';
    }
    if (len > n) {
        memcpy(out + n, "...", 3);
        n += 3;
    }
    out[n] = '\0';
    return out;
}

int proto_check_limits(const proto_limits *lim, uint64_t nverts,
                       uint64_t nfacets, uint64_t ncorners, geo_err *err)
{
    uint64_t max_v = lim->max_vertices, max_c = lim->max_corners;
    if (max_v > GEO_POLY_MAX_VERTS)
        max_v = GEO_POLY_MAX_VERTS;
    if (max_c > GEO_POLY_MAX_CORNERS)
        max_c = GEO_POLY_MAX_CORNERS;
    if (nverts > max_v)
        return geo_err_set(err, -ERANGE,
                           "vertices: %llu exceed the limit of %llu",
                           (unsigned long long)nverts,
                           (unsigned long long)max_v);
    if (nfacets > lim->max_facets)
        return geo_err_set(err, -ERANGE, "facets: %llu exceed the limit of %u",
                           (unsigned long long)nfacets, lim->max_facets);
    if (ncorners > max_c)
        return geo_err_set(err, -ERANGE,
                           "facets: %llu vertex indices in all exceed the "
                           "limit of %llu",
                           (unsigned long long)ncorners,
                           (unsigned long long)max_c);
    return 0;
}

static void note_mismatch(proto_read_report *rep, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static void note_mismatch(proto_read_report *rep, const char *fmt, ...)
{
    if (rep->plane_mismatches++ == 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(rep->first, sizeof rep->first, fmt, ap);
        va_end(ap);
    }
}

/* Normalises plane in place; false for a zero or non-finite normal. The
 * largest component is divided out first so that squaring cannot
 * overflow. */
static bool normalise_plane(double plane[4])
{
    double m = fmax(fabs(plane[0]), fmax(fabs(plane[1]), fabs(plane[2])));
    if (!(m > 0) || !isfinite(m) || !isfinite(plane[3]))
        return false;
    /* a plane already unit within rounding (as every writer here emits)
     * is kept bit for bit, so that write/read cycles are exact */
    if (m > 0.5 && m <= 1) {
        double n2 = geo_vdot(plane, plane);
        if (fabs(n2 - 1) <= 4 * DBL_EPSILON)
            return true;
    }
    double q[4];
    for (int k = 0; k < 4; k++)
        q[k] = plane[k] / m;
    double n = geo_vlen(q);
    if (!isfinite(q[3] / n))
        return false;
    for (int k = 0; k < 4; k++)
        plane[k] = q[k] / n;
    return true;
}

/* A least-squares plane for facet f; a zero component is stored as +0
 * so that files written later do not show "-0.0" for computed planes.
 * False when the fit overflows. */
static bool fit_plane(geo_poly *p, uint32_t f)
{
    geo_poly_facet_fit_plane(p, f, GEO_PLANE_UNWEIGHTED, p->planes[f]);
    bool finite = true;
    for (int k = 0; k < 4; k++) {
        p->planes[f][k] += 0.0;
        finite = finite && isfinite(p->planes[f][k]);
    }
    return finite;
}

static int fit_failed(uint32_t f, geo_err *err)
{
    return geo_err_set(err, -ERANGE,
                       "facets[%u].plane: no finite plane fits the "
                       "vertices (coordinates too large)", f);
}

/* -ERANGE unless every coordinate is within ±PROTO_MAX_COORD and the
 * model, if it has any extent, is at least PROTO_MIN_EXTENT across: the
 * exact predicates multiply three coordinate differences, which must
 * neither overflow nor fall into the subnormal range. */
static int check_coordinates(const geo_poly *p, geo_err *err)
{
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    if (p->nverts > 0)
        for (int k = 0; k < 3; k++)
            lo[k] = hi[k] = p->verts[0][k];
    for (uint32_t v = 0; v < p->nverts; v++)
        for (int k = 0; k < 3; k++) {
            double x = p->verts[v][k];
            if (!(fabs(x) <= PROTO_MAX_COORD))
                return geo_err_set(err, -ERANGE,
                                   "vertices[%u][%d]: %g mm is beyond the "
                                   "±%g mm a model may span", v, k, x,
                                   PROTO_MAX_COORD);
            /* x is finite: comparisons, not fmin/fmax's calls */
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
    double extent = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    if (extent > 0 && extent < PROTO_MIN_EXTENT)
        return geo_err_set(err, -ERANGE,
                           "the model is %g mm across, below the %g mm "
                           "the exact predicates can resolve (wrong "
                           "units?)", extent, PROTO_MIN_EXTENT);
    return 0;
}

/* Whether every facet of p is a triangle without a given plane. */
static bool triangles_without_planes(const geo_poly *p, const bool *given)
{
    for (uint32_t f = 0; f < p->nfacets; f++)
        if (geo_poly_facet_size(p, f) != 3 || (given && given[f]))
            return false;
    return true;
}

int proto_finish_planes(geo_poly *p, const bool *given,
                        const proto_limits *lim, proto_read_report *rep,
                        geo_err *err)
{
    int r = check_coordinates(p, err);
    if (r < 0)
        return r;
    /* A triangle's plane is always finite here, so dropping the planes
     * skips no failure: its coordinates are within ±1e9, so the Newell
     * vector's components are below 8e18 and its squared length below
     * 2e38; a squared length that underflows to zero gives the zero
     * plane, and a subnormal one a root within a few units of the true
     * length, so the unit normal's components stay below 2 and the
     * offset below 6e9. */
    if (lim && lim->implicit_planes && triangles_without_planes(p, given)) {
        rep->worst_facet = UINT32_MAX;
        free(p->planes);
        p->planes = NULL;
        return 0;
    }
    rep->worst_facet = UINT32_MAX;
    double eps = geo_poly_eps(p);
    for (uint32_t f = 0; f < p->nfacets; f++) {
        double *pl = p->planes[f];
        if (!given || !given[f]) {
            if (!fit_plane(p, f))
                return fit_failed(f, err);
            continue;
        }
        rep->planes_given++;
        if (!normalise_plane(pl)) {
            note_mismatch(rep, "facets[%u].plane: zero normal; recomputed "
                               "by least squares", f);
            if (!fit_plane(p, f))
                return fit_failed(f, err);
            continue;
        }
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *v = geo_poly_facet(p, f);
        double worst = 0;
        uint32_t worst_i = 0;
        for (uint32_t i = 0; i < n; i++) {
            double d = fabs(geo_plane_eval(pl, p->verts[v[i]]));
            if (!(d <= worst)) {
                worst = d;
                worst_i = i;
            }
        }
        if (worst > rep->worst_deviation) {
            rep->worst_deviation = worst;
            rep->worst_facet = f;
        }
        double area[3];
        geo_poly_facet_area_vector(p, f, area);
        if (!(worst <= eps))
            note_mismatch(rep, "facets[%u].plane: vertex %u (facets[%u]."
                               "vertices[%u]) lies %.3g mm off the plane "
                               "(tolerance %.3g mm)",
                          f, v[worst_i], f, worst_i, worst, eps);
        else if (geo_vdot(area, pl) < 0)
            note_mismatch(rep, "facets[%u].plane: the normal points against "
                               "the vertex order (inward)", f);
    }
    return 0;
}

geo_poly *proto_poly_alloc(uint64_t nv, uint64_t nf, uint64_t nc,
                           bool **ret_given, geo_err *err)
{
    geo_poly *p = geo_poly_new();
    bool *given = ret_given ? calloc(nf ? nf : 1, sizeof *given) : NULL;
    if (!p || (ret_given && !given) || geo_poly_reserve(p, nv, nf, nc) < 0) {
        free(given);
        geo_err_set(err, -ENOMEM, "out of memory");
        return geo_poly_free(p);
    }
    if (ret_given)
        *ret_given = given;
    return p;
}

geo_poly *proto_read_done(geo_poly *p, bool *given, const proto_limits *lim,
                          proto_read_report *rep, geo_err *err)
{
    int r = proto_finish_planes(p, given, lim, rep, err);
    free(given);
    return r < 0 ? geo_poly_free(p) : p;
}

void proto_buf_vertex_lines(proto_buf *b, const geo_poly *p,
                            const char *prefix)
{
    for (uint32_t i = 0; i < p->nverts; i++) {
        proto_buf_puts(b, prefix);
        for (int k = 0; k < 3; k++) {
            if (k)
                proto_buf_puts(b, " ");
            proto_buf_double(b, p->verts[i][k]);
        }
        proto_buf_puts(b, "\n");
    }
}

int proto_each_triangle(const geo_poly *p,
                        void (*emit)(const geo_poly *p, uint32_t f,
                                     const uint32_t *q, void *arg),
                        void *arg, geo_err *err)
{
    uint32_t maxn = 3;
    for (uint32_t f = 0; f < p->nfacets; f++)
        if (geo_poly_facet_size(p, f) > maxn)
            maxn = geo_poly_facet_size(p, f);
    uint32_t (*tris)[3] = malloc((size_t)(maxn - 2) * sizeof *tris);
    if (!tris)
        return geo_err_set(err, -ENOMEM, "out of memory");
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        if (geo_polygon_triangulate(&p->verts[0][0], geo_poly_facet(p, f), n,
                                    tris) < 0) {
            free(tris);
            return geo_err_set(err, -ENOMEM, "out of memory");
        }
        for (uint32_t k = 0; k + 2 < n; k++)
            emit(p, f, tris[k], arg);
    }
    free(tris);
    return 0;
}
