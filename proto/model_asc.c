/* model_asc.c — GemCad .asc cutting designs (docs/formats-asc.md).
 *
 * A design is a list of tiers; each tier is one angle and one distance
 * and the gear indices of its facets. Facet plane: unit normal
 * (sin|A|·sin φ, sin|A|·cos φ, ±cos A) — φ the azimuth measured from +y
 * towards +x (clockwise seen from above), + for a crown facet (A > 0 or
 * +0), − for a pavilion facet (A < 0 or −0) — at distance DIST from the
 * origin along it. The gear "g N OFFSET" places the indices as GemCad
 * draws them in its top view: index OFFSET at the bottom (−y), indices
 * increasing counter-clockwise for N > 0, clockwise for N < 0; so
 * φ = 180° − 360°·(IDX − OFFSET)/N, and "g -96 48" puts 96 at the top
 * counting clockwise (φ = 3.75°·IDX). A zero angle with a
 * negative distance is GemCad's way of writing a culet. The stone is the
 * exact intersection of those half-spaces (lib/core/halfspace.h), so
 * vertices where many facets meet are single vertices.
 *
 * Reading is line-oriented; every error names the line ("line 7: angle
 * 200: must lie within −90..90"). Writing turns any convex model into a
 * design: the origin moves to the vertex centroid (so every distance is
 * positive, as GemCad expects) and an "H origin X Y Z" header records the
 * shift, which this reader undoes; facets of equal inclination and
 * distance share a tier; the gear is "g -96 48" (96 at the top, counting
 * clockwise) and an azimuth off its teeth is a fractional index. Numbers are written as the shortest decimals that
 * read back exactly, so a convex model round-trips to within rounding. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "halfspace.h"
#include "model_codec.h"

#define ASC_MAX_GEAR 10000
#define DEG (M_PI / 180.0)

typedef struct asc_tok {
    const char *s;
    size_t n;
} asc_tok;

typedef struct asc_reader {
    geo_err *err;
    uint32_t line;
    int32_t gear;   /* teeth; negative: indices counted clockwise */
    double offset;  /* the index at the bottom of the top view */
    bool have_origin;
    double origin[3];
    bool tier_open; /* an "a" record may continue on the next lines */
    double angle, dist;
    bool pavilion;
    uint32_t tier_count, tier_line; /* indices of the open tier, its line */
    /* the planes so far and the line of each */
    double (*pl)[4];
    uint32_t *pline;
    uint32_t n, cap;
    uint32_t max;
} asc_reader;

static int fail(asc_reader *r, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static int fail(asc_reader *r, const char *fmt, ...)
{
    char msg[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return geo_err_set(r->err, -EINVAL, "line %u: %s", r->line, msg);
}

static bool tok_is(asc_tok t, const char *word)
{
    return t.n == strlen(word) && memcmp(t.s, word, t.n) == 0;
}

/* Splits a line into at most max blank-separated tokens (out NULL: only
 * counts them). */
static uint32_t split(const char *s, size_t n, asc_tok *out, uint32_t max)
{
    uint32_t k = 0;
    size_t i = 0;
    while (i < n && k < max) {
        while (i < n && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r'))
            i++;
        if (i == n)
            break;
        size_t j = i;
        while (j < n && s[j] != ' ' && s[j] != '\t' && s[j] != '\r')
            j++;
        if (out)
            out[k].s = s + i, out[k].n = j - i;
        k++;
        i = j;
    }
    return k;
}

static int number(asc_reader *r, asc_tok t, const char *what, double *ret)
{
    char shown[32];
    int e = proto_parse_double(t.s, t.n, ret);
    if (e < 0)
        return fail(r, "%s: expected a number, found \"%s\"", what,
                    proto_tok_show(t.s, t.n, shown));
    return 0;
}

/* sin and cos of x degrees with the circle's symmetries exact: exact at
 * multiples of 90°, sin = cos at 45°, and each quadrant a sign change or
 * a swap of the first octant's values, so mirror-symmetric facets of a
 * design get exactly mirrored normals. */
static void sincos_deg(double x, double *ret_s, double *ret_c)
{
    double r = fmod(x, 360.0);
    if (r < 0)
        r += 360.0;
    int q = (int)(r / 90.0);
    if (q > 3)
        q = 3;
    double t = r - 90.0 * q, st, ct;
    if (t == 45.0)
        st = ct = sqrt(0.5);
    else if (t < 45.0)
        st = sin(t * DEG), ct = cos(t * DEG);
    else
        st = cos((90.0 - t) * DEG), ct = sin((90.0 - t) * DEG);
    switch (q) {
    case 0: *ret_s = st, *ret_c = ct; break;
    case 1: *ret_s = ct, *ret_c = -st; break;
    case 2: *ret_s = -st, *ret_c = -ct; break;
    default: *ret_s = -ct, *ret_c = st; break;
    }
}

static int add_plane(asc_reader *r, double idx)
{
    if (r->n == r->max)
        return fail(r, "more than %u facets (the limit)", r->max);
    if (r->n == r->cap) {
        uint32_t cap = r->cap ? 2 * r->cap : 64;
        void *a = realloc(r->pl, (size_t)cap * sizeof *r->pl);
        if (!a)
            return geo_err_set(r->err, -ENOMEM, "out of memory");
        r->pl = a;
        void *b = realloc(r->pline, (size_t)cap * sizeof *r->pline);
        if (!b)
            return geo_err_set(r->err, -ENOMEM, "out of memory");
        r->pline = b;
        r->cap = cap;
    }
    double sp, cp, sa, ca;
    sincos_deg(180.0 - 360.0 * (idx - r->offset) / r->gear, &sp, &cp);
    sincos_deg(fabs(r->angle), &sa, &ca);
    double *q = r->pl[r->n];
    q[0] = sa * sp;
    q[1] = sa * cp;
    q[2] = r->pavilion ? -ca : ca;
    q[3] = -r->dist;
    r->pline[r->n++] = r->line;
    return 0;
}

/* The rest of an "a" record (on its own line or a continuation line):
 * indices, "n NAME" and "G text". */
static int tier_items(asc_reader *r, const asc_tok *t, uint32_t nt)
{
    char shown[32];
    for (uint32_t i = 0; i < nt; i++) {
        if (tok_is(t[i], "G"))
            return 0; /* instructions for the cutter run to the line's end */
        if (tok_is(t[i], "n")) {
            if (i + 1 == nt)
                return fail(r, "\"n\" without a facet name");
            i++;
            continue;
        }
        double idx;
        if (proto_parse_double(t[i].s, t[i].n, &idx) < 0)
            return fail(r, "tier: expected an index, \"n NAME\" or \"G "
                           "text\", found \"%s\"",
                        proto_tok_show(t[i].s, t[i].n, shown));
        if (fabs(idx) > 1e6)
            return fail(r, "index %g out of range", idx);
        int e = add_plane(r, idx);
        if (e < 0)
            return e;
        r->tier_count++;
    }
    return 0;
}

/* A tier ends at the next "a" record or at the end of the file; it must
 * have had an index. */
static int close_tier(asc_reader *r)
{
    if (!r->tier_open || r->tier_count > 0)
        return 0;
    uint32_t line = r->line;
    r->line = r->tier_line;
    fail(r, "tier: no index (truncated line?)");
    r->line = line;
    return -EINVAL;
}

static int record_gear(asc_reader *r, const asc_tok *t, uint32_t nt)
{
    /* "g 96 0.0", or the keyword glued to its value: "g96 0.0" */
    asc_tok teeth = {t[0].s + 1, t[0].n - 1}, off = {NULL, 0};
    uint32_t next = 1;
    if (teeth.n == 0) {
        if (nt < 2)
            return fail(r, "gear: expected the number of teeth");
        teeth = t[1];
        next = 2;
    }
    if (nt > next)
        off = t[next];
    double g;
    int e = number(r, teeth, "gear", &g);
    if (e < 0)
        return e;
    if (g == 0 || g != floor(g) || fabs(g) > ASC_MAX_GEAR)
        return fail(r, "gear %g: must be a whole number of teeth, 1..%d",
                    g, ASC_MAX_GEAR);
    r->gear = (int32_t)g;
    r->offset = 0.0;
    if (off.s && (e = number(r, off, "gear offset", &r->offset)) < 0)
        return e;
    if (!(fabs(r->offset) <= abs(r->gear)))
        return fail(r, "gear offset %g: must be an index within -%d..%d",
                    r->offset, abs(r->gear), abs(r->gear));
    return 0;
}

static int record_tier(asc_reader *r, const asc_tok *t, uint32_t nt)
{
    int e = close_tier(r);
    if (e < 0)
        return e;
    if (nt < 2)
        return fail(r, "tier: expected an angle");
    if (nt < 3)
        return fail(r, "tier: expected a distance after the angle");
    e = number(r, t[1], "tier angle", &r->angle);
    if (e < 0 || (e = number(r, t[2], "tier distance", &r->dist)) < 0)
        return e;
    if (!(fabs(r->angle) <= 90.0))
        return fail(r, "angle %g: must lie within -90..90 degrees",
                    r->angle);
    r->pavilion = signbit(r->angle);
    if (r->angle == 0.0 && r->dist < 0.0) { /* GemCad's culet */
        r->pavilion = true;
        r->dist = -r->dist;
    }
    r->tier_open = true;
    r->tier_count = 0;
    r->tier_line = r->line;
    return tier_items(r, t + 3, nt - 3);
}

static int record_origin(asc_reader *r, const asc_tok *t, uint32_t nt)
{
    /* "H origin X Y Z": written by this writer, undone on reading */
    if (nt != 5)
        return 0; /* another header that happens to start with "origin" */
    for (int k = 0; k < 3; k++)
        if (proto_parse_double(t[2 + k].s, t[2 + k].n, &r->origin[k]) < 0)
            return 0;
    r->have_origin = true;
    return 0;
}

static int read_record(asc_reader *r, const asc_tok *t, uint32_t nt);

static int read_line(asc_reader *r, const char *s, size_t n)
{
    asc_tok small[64], *t = small;
    const char *p = s;
    size_t left = n;
    if (left >= 3 && (unsigned char)p[0] == 0xef &&
        (unsigned char)p[1] == 0xbb && (unsigned char)p[2] == 0xbf)
        p += 3, left -= 3; /* a UTF-8 byte-order mark */
    uint32_t nt = split(p, left, NULL, UINT32_MAX);
    if (nt == 0)
        return 0;
    if (nt > 64 && !(t = malloc((size_t)nt * sizeof *t)))
        return geo_err_set(r->err, -ENOMEM, "out of memory");
    split(p, left, t, nt);
    int e = read_record(r, t, nt);
    if (t != small)
        free(t);
    return e;
}

static int read_record(asc_reader *r, const asc_tok *t, uint32_t nt)
{
    char c = t[0].s[0];
    if (c == ';' || c == '#' || (t[0].n >= 6 && !memcmp(t[0].s, "GemCad", 6)))
        return 0;
    if (tok_is(t[0], "H") || tok_is(t[0], "F") || tok_is(t[0], "I")) {
        if (tok_is(t[0], "H") && nt >= 2 && tok_is(t[1], "origin"))
            return record_origin(r, t, nt);
        return 0;
    }
    if (tok_is(t[0], "y")) {
        double s_fold;
        if (nt < 2)
            return fail(r, "symmetry: expected the fold");
        int e = number(r, t[1], "symmetry", &s_fold);
        if (e < 0)
            return e;
        if (s_fold < 1 || s_fold != floor(s_fold) || s_fold > ASC_MAX_GEAR)
            return fail(r, "symmetry %g: must be a whole number, 1..%d",
                        s_fold, ASC_MAX_GEAR);
        return 0;
    }
    if (t[0].s[0] == 'g' && (t[0].n == 1 || (t[0].s[1] >= '0' &&
                                              t[0].s[1] <= '9')))
        return record_gear(r, t, nt);
    if (tok_is(t[0], "a"))
        return record_tier(r, t, nt);
    if (tok_is(t[0], "G") && r->tier_open)
        return 0;
    if (r->tier_open) /* a continuation line of the open tier */
        return tier_items(r, t, nt);
    char shown[32];
    return fail(r, "unknown record \"%s\"",
                proto_tok_show(t[0].s, t[0].n, shown));
}

geo_poly *proto_asc_read(const void *data, size_t len,
                         const proto_limits *lim, proto_read_report *rep,
                         geo_err *err)
{
    asc_reader r = {.err = err, .gear = 96, .max = lim->max_facets};
    proto_scan s;
    proto_scan_init(&s, data, len, false);
    const char *ln;
    size_t n;
    int e = 0;
    uint32_t last = 1;
    while (e == 0 && proto_scan_line(&s, &ln, &n)) {
        r.line = last = s.tok_line;
        e = read_line(&r, ln, n);
    }
    if (e == 0)
        e = close_tier(&r);
    geo_poly *p = NULL;
    if (e == 0 && r.n == 0) {
        r.line = last;
        fail(&r, "no facets: a design needs \"a ANGLE DIST INDEX...\" "
                 "tiers");
        e = -EINVAL;
    }
    uint32_t *src = NULL;
    if (e == 0) {
        enum geo_halfspace_status st = GEO_HALFSPACE_OK;
        geo_err herr = {{0}};
        e = geo_halfspace_intersect(&r.pl[0][0], r.n, -1, &p, &src, &st, &herr);
        if (e == 0) {
            /* again contracting only edges below half the planarity
             * tolerance of the stone: merged vertices then lie on their
             * planes as every reader of the model checks */
            double tol = 0.5 * geo_poly_eps(p);
            p = geo_poly_free(p);
            free(src);
            src = NULL;
            e = geo_halfspace_intersect(&r.pl[0][0], r.n, tol, &p, &src, &st,
                                        &herr);
        }
        if (e == -EINVAL && st == GEO_HALFSPACE_EMPTY) {
            /* the kernel names the plane that emptied the region */
            unsigned idx = 0;
            sscanf(herr.msg, "the planes bound nothing: planes[%u]", &idx);
            r.line = idx < r.n ? r.pline[idx] : last;
            fail(&r, "the facets bound nothing: this facet leaves no "
                     "interior of those before it");
        } else if (e == -EINVAL) {
            uint32_t up = 0, down = 0;
            for (uint32_t i = 0; i < r.n; i++)
                up += r.pl[i][2] > 0, down += r.pl[i][2] < 0;
            r.line = last;
            fail(&r, "the facets do not bound a stone%s (%s)",
                 !up && !down ? ": no crown or pavilion facets"
                 : !up        ? ": no crown facets (a design in progress?)"
                 : !down      ? ": no pavilion facets (a design in progress?)"
                              : "",
                 herr.msg);
        } else if (e < 0) {
            geo_err_set(err, e, "%s", herr.msg);
        }
    }
    free(src);
    free(r.pl);
    free(r.pline);
    if (e < 0)
        return NULL;
    if (r.have_origin)
        for (uint32_t v = 0; v < p->nverts; v++)
            for (int k = 0; k < 3; k++)
                p->verts[v][k] += r.origin[k];
    if (r.have_origin)
        for (uint32_t f = 0; f < p->nfacets; f++)
            p->planes[f][3] -= p->planes[f][0] * r.origin[0] +
                               p->planes[f][1] * r.origin[1] +
                               p->planes[f][2] * r.origin[2];
    bool *given = calloc(p->nfacets ? p->nfacets : 1, sizeof *given);
    if (!given) {
        geo_err_set(err, -ENOMEM, "out of memory");
        return geo_poly_free(p);
    }
    for (uint32_t f = 0; f < p->nfacets; f++)
        given[f] = true; /* the design's planes, not fitted ones */
    if (proto_check_limits(lim, p->nverts, p->nfacets, geo_poly_ncorners(p),
                           err) < 0 ||
        proto_finish_planes(p, given, lim, rep, err) < 0) {
        free(given);
        return geo_poly_free(p);
    }
    free(given);
    return p;
}

/* A facet's design coordinates: signed angle from horizontal (−0 for a
 * culet), distance, azimuth in degrees [0, 360). */
typedef struct asc_facet {
    double angle, dist, index;
    uint32_t tier;
} asc_facet;

static void facet_design(const double q[4], const double o[3], uint32_t gear,
                         asc_facet *ret)
{
    double h = hypot(q[0], q[1]);
    double a = atan2(h, fabs(q[2])) / DEG;
    ret->angle = q[2] == 0 ? 90.0 : q[2] < 0 ? -a : a; /* a culet: −0 */
    ret->dist = -(q[3] + q[0] * o[0] + q[1] * o[1] + q[2] * o[2]);
    double az = h > 0 ? atan2(q[0], q[1]) / DEG : 0.0;
    if (az < 0)
        az += 360.0;
    double idx = az * gear / 360.0;
    double near = nearbyint(idx);
    if (fabs(idx - near) < 1e-9)
        idx = near;
    if (idx <= 0)
        idx += gear; /* GemCad writes the top index as N, not 0 */
    ret->index = idx;
}

static int tier_order(const asc_facet *a)
{
    if (a->angle < 0 || signbit(a->angle))
        return 0; /* pavilion first, as it is cut */
    return a->angle == 90.0 ? 1 : a->angle > 0 ? 2 : 3;
}

int proto_asc_write(const geo_poly *p, proto_buf *b, geo_err *err)
{
    const uint32_t gear = 96;
    double o[3] = {0, 0, 0};
    for (uint32_t v = 0; v < p->nverts; v++)
        for (int k = 0; k < 3; k++)
            o[k] += p->verts[v][k] / p->nverts;
    asc_facet *f = malloc((size_t)(p->nfacets ? p->nfacets : 1) * sizeof *f);
    uint32_t *first = malloc((size_t)(p->nfacets ? p->nfacets : 1) *
                             sizeof *first);
    if (!f || !first) {
        free(f);
        free(first);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    uint32_t ntier = 0;
    for (uint32_t i = 0; i < p->nfacets; i++) {
        const double *q = p->planes[i];
        double len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        if (!(fabs(len - 1.0) < 1e-9)) {
            free(f);
            free(first);
            return geo_err_set(err, -EINVAL, "facets[%u].plane: not a unit "
                               "normal (a degenerate facet)", i);
        }
        facet_design(q, o, gear, &f[i]);
        if (!(f[i].dist > 0)) {
            free(f);
            free(first);
            return geo_err_set(err, -EINVAL, "facets[%u]: the model is not "
                               "convex (its plane passes at or beyond the "
                               "vertex centroid)", i);
        }
        /* a tier: facets of the same angle and distance to 1e-9 */
        uint32_t t = 0;
        for (; t < ntier; t++) {
            const asc_facet *g = &f[first[t]];
            if (signbit(g->angle) == signbit(f[i].angle) &&
                fabs(g->angle - f[i].angle) <= 1e-9 &&
                fabs(g->dist - f[i].dist) <= 1e-9 * (1 + g->dist))
                break;
        }
        if (t == ntier)
            first[ntier++] = i;
        f[i].tier = t;
    }
    /* 96 at the top counting clockwise: the index is φ · 96 / 360 */
    proto_buf_puts(b, "GemCad 5.0\r\ng -");
    proto_buf_u32(b, gear);
    proto_buf_puts(b, " ");
    proto_buf_u32(b, gear / 2);
    proto_buf_puts(b, "\r\ny 1 n\r\nI 1.54\r\nH facet convert: ");
    proto_buf_u32(b, p->nfacets);
    proto_buf_puts(b, " facets in ");
    proto_buf_u32(b, ntier);
    proto_buf_puts(b, " tiers\r\nH origin ");
    for (int k = 0; k < 3; k++) {
        proto_buf_double(b, o[k]);
        proto_buf_puts(b, k < 2 ? " " : "\r\n");
    }
    uint32_t count[4] = {0, 0, 0, 0};
    for (int order = 0; order < 4; order++)
        for (uint32_t t = 0; t < ntier; t++) {
            const asc_facet *g = &f[first[t]];
            if (tier_order(g) != order)
                continue;
            proto_buf_puts(b, "a ");
            if (g->angle == 0 && signbit(g->angle))
                proto_buf_puts(b, "-0");
            else
                proto_buf_double(b, g->angle);
            proto_buf_puts(b, " ");
            proto_buf_double(b, g->dist);
            bool named = false;
            for (uint32_t i = first[t]; i < p->nfacets; i++) {
                if (f[i].tier != t)
                    continue;
                proto_buf_puts(b, " ");
                proto_buf_double(b, f[i].index);
                if (!named) {
                    static const char tag[4] = {'P', 'G', 'C', 'T'};
                    proto_buf_printf(b, " n %c%u", tag[order],
                                     ++count[order]);
                    named = true;
                }
            }
            proto_buf_puts(b, "\r\n");
        }
    free(f);
    free(first);
    return 0;
}

int proto_model_scale_to_width(geo_poly *p, double width_mm, geo_err *err)
{
    if (!(width_mm > 0) || !isfinite(width_mm))
        return geo_err_set(err, -EINVAL, "width %g mm: must be positive",
                           width_mm);
    /* the largest caliper width of the outline seen along z is the
     * largest distance between two vertices projected on z = 0 */
    double w2 = 0;
    for (uint32_t i = 0; i < p->nverts; i++)
        for (uint32_t j = i + 1; j < p->nverts; j++) {
            double dx = p->verts[i][0] - p->verts[j][0];
            double dy = p->verts[i][1] - p->verts[j][1];
            w2 = fmax(w2, dx * dx + dy * dy);
        }
    if (!(w2 > 0))
        return geo_err_set(err, -EINVAL, "the model has no width across z");
    double s = width_mm / sqrt(w2);
    for (uint32_t v = 0; v < p->nverts; v++)
        for (int k = 0; k < 3; k++)
            p->verts[v][k] *= s;
    for (uint32_t f = 0; f < p->nfacets; f++)
        p->planes[f][3] *= s;
    return 0;
}
