/* classify.c — point vs plane in the four forms of "Tests of graphic elements", cross3, conv3
 * and facet convexity. Every decision is an exact sign from
 * lib/core/predicates.h; the value functions only measure. */
#include "classify.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>

#include "predicates.h"
#include "vec.h"

double geo_nf_implicit(const double plane[4], const double p[3])
{
    return geo_plane_eval(plane, p);
}

int geo_nf_implicit_sign(const double plane[4], const double p[3])
{
    return geo_plane_sign(plane, p);
}

double geo_nf_normal(const double p0[3], const double n[3], const double p[3])
{
    double d[3];
    geo_vsub(p, p0, d);
    return geo_vdot(n, d);
}

int geo_nf_normal_sign(const double p0[3], const double n[3],
                       const double p[3])
{
    return geo_normal_sign(p0, n, p);
}

double geo_nf3(const double a[3], const double b[3], const double c[3],
               const double p[3])
{
    double ba[3], cb[3], pa[3], n[3];
    geo_vsub(b, a, ba);
    geo_vsub(c, b, cb);
    geo_vsub(p, a, pa);
    geo_vcross(ba, cb, n);
    return geo_vdot(pa, n);
}

int geo_nf3_sign(const double a[3], const double b[3], const double c[3],
                 const double p[3])
{
    /* (b − a) × (c − b) = (b − a) × (c − a): the paper's nf3 is orient3d */
    return geo_orient3d(a, b, c, p);
}

static int dominant_axis(const double n[3])
{
    int ax = 0;
    for (int k = 1; k < 3; k++)
        if (fabs(n[k]) > fabs(n[ax]))
            ax = k;
    return ax;
}

/* Projected coordinates (u, v) of point x dropping axis ax, in the cyclic
 * order geo_orient2d_proj uses. */
static inline double proj_u(const double x[3], int ax)
{
    return x[(ax + 1) % 3];
}
static inline double proj_v(const double x[3], int ax)
{
    return x[(ax + 2) % 3];
}

static bool lex_less(const double a[3], const double b[3], int ax)
{
    double au = proj_u(a, ax), bu = proj_u(b, ax);
    if (au != bu)
        return au < bu;
    return proj_v(a, ax) < proj_v(b, ax);
}

void geo_facet_ref(const geo_poly *p, uint32_t f, uint32_t ret[3])
{
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *v = geo_poly_facet(p, f);
    double nv[3];
    geo_poly_facet_area_vector(p, f, nv);
    int ax = dominant_axis(nv);
    int want = (nv[ax] > 0) - (nv[ax] < 0);
    ret[0] = v[0];
    ret[1] = v[1 % n];
    ret[2] = v[2 % n];
    if (want == 0)
        return;
    uint32_t k = 0;
    for (uint32_t i = 1; i < n; i++)
        if (lex_less(p->verts[v[i]], p->verts[v[k]], ax))
            k = i;
    const double(*P)[3] = (const double(*)[3])p->verts;
    uint32_t a = v[(k + n - 1) % n], b = v[k], c = v[(k + 1) % n];
    if (geo_orient2d_proj(P[a], P[b], P[c], ax) == want) {
        ret[0] = a, ret[1] = b, ret[2] = c;
        return;
    }
    /* collinear neighbours (or a non-simple polygon): the largest corner
     * turning the polygon's way */
    double best = -1;
    for (uint32_t i = 0; i < n; i++) {
        a = v[(i + n - 1) % n], b = v[i], c = v[(i + 1) % n];
        if (geo_orient2d_proj(P[a], P[b], P[c], ax) != want)
            continue;
        double ab[3], ac[3], cr[3];
        geo_vsub(P[b], P[a], ab);
        geo_vsub(P[c], P[a], ac);
        geo_vcross(ab, ac, cr);
        double area = fabs(cr[ax]);
        if (area > best) {
            best = area;
            ret[0] = a, ret[1] = b, ret[2] = c;
        }
    }
}

double geo_nf_facet(const geo_poly *p, uint32_t f, const double q[3])
{
    uint32_t r[3];
    geo_facet_ref(p, f, r);
    return geo_nf3(p->verts[r[0]], p->verts[r[1]], p->verts[r[2]], q);
}

int geo_nf_facet_sign(const geo_poly *p, uint32_t f, const double q[3])
{
    uint32_t r[3];
    geo_facet_ref(p, f, r);
    return geo_orient3d(p->verts[r[0]], p->verts[r[1]], p->verts[r[2]], q);
}

bool geo_facet_is_planar_exact(const geo_poly *p, uint32_t f)
{
    uint32_t r[3];
    geo_facet_ref(p, f, r);
    const double *a = p->verts[r[0]], *b = p->verts[r[1]], *c = p->verts[r[2]];
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *v = geo_poly_facet(p, f);
    for (uint32_t i = 0; i < n; i++)
        if (geo_orient3d(a, b, c, p->verts[v[i]]) != 0)
            return false;
    return true;
}

void geo_plane_spec_facet(const geo_poly *p, uint32_t f, geo_plane_spec *ret)
{
    uint32_t r[3];
    geo_facet_ref(p, f, r);
    *ret = (geo_plane_spec){.form = GEO_PLANE_THREE_POINTS};
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            ret->pts[i][k] = p->verts[r[i]][k];
}

double geo_plane_spec_value(const geo_plane_spec *pl, const double q[3])
{
    switch (pl->form) {
    case GEO_PLANE_IMPLICIT:
        return geo_nf_implicit(pl->coef, q);
    case GEO_PLANE_POINT_NORMAL:
        return geo_nf_normal(pl->point, pl->normal, q);
    case GEO_PLANE_THREE_POINTS:
        break;
    }
    return geo_nf3(pl->pts[0], pl->pts[1], pl->pts[2], q);
}

int geo_plane_spec_sign(const geo_plane_spec *pl, const double q[3])
{
    switch (pl->form) {
    case GEO_PLANE_IMPLICIT:
        return geo_plane_sign(pl->coef, q);
    case GEO_PLANE_POINT_NORMAL:
        return geo_normal_sign(pl->point, pl->normal, q);
    case GEO_PLANE_THREE_POINTS:
        break;
    }
    return geo_orient3d(pl->pts[0], pl->pts[1], pl->pts[2], q);
}

int geo_cross3(const geo_plane_spec *pl, const geo_poly *p)
{
    bool pos = false, neg = false, zero = false;
    for (uint32_t i = 0; i < p->nverts; i++) {
        int s = geo_plane_spec_sign(pl, p->verts[i]);
        pos |= s > 0;
        neg |= s < 0;
        zero |= s == 0;
        if (pos && neg)
            return 1;
    }
    return zero ? 0 : -1;
}

/* Facets between two progress reports / cancellation checks. */
enum { CONV3_STRIDE = 64 };

int geo_conv3(const geo_poly *p, const geo_ctx *ctx, geo_conv3_result *ret)
{
    geo_conv3_result r = {.convex = true};
    /* stamp[v] == f + 1 marks the vertices of facet f (skipped: j ∉ G_i) */
    uint32_t *stamp = calloc((size_t)p->nverts + 1, sizeof *stamp);
    if (!stamp)
        return -ENOMEM;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        if (f % CONV3_STRIDE == 0) {
            int rc = geo_ctx_progress(ctx, (double)f / p->nfacets);
            if (rc) {
                free(stamp);
                return rc;
            }
        }
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *fv = geo_poly_facet(p, f);
        for (uint32_t i = 0; i < n; i++)
            stamp[fv[i]] = f + 1;
        uint32_t ref[3];
        geo_facet_ref(p, f, ref);
        const double *a = p->verts[ref[0]], *b = p->verts[ref[1]],
                     *c = p->verts[ref[2]];
        bool l = false, rr = false; /* the paper's two flags */
        uint32_t va = 0, vb = 0;
        for (uint32_t j = 0; j < p->nverts && !(l && rr); j++) {
            if (stamp[j] == f + 1)
                continue;
            int s = geo_orient3d(a, b, c, p->verts[j]);
            if (s > 0 && !rr)
                rr = true, va = j;
            else if (s < 0 && !l)
                l = true, vb = j;
        }
        if (l && rr) {
            r.convex = false;
            r.facet = f;
            r.v_above = va;
            r.v_below = vb;
            break;
        }
        if (rr)
            r.nabove++;
    }
    free(stamp);
    int rc = geo_ctx_progress(ctx, 1.0);
    if (rc == 0)
        *ret = r;
    return rc;
}

bool geo_facet_is_convex(const geo_poly *p, uint32_t f)
{
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *v = geo_poly_facet(p, f);
    double nv[3];
    geo_poly_facet_area_vector(p, f, nv);
    int ax = dominant_axis(nv);
    int want = (nv[ax] > 0) - (nv[ax] < 0);
    if (want == 0)
        return false;
    const double(*P)[3] = (const double(*)[3])p->verts;
    bool strict = false;
    int changes[2] = {0, 0}, last[2] = {0, 0};
    for (uint32_t i = 0; i < n; i++) {
        const double *a = P[v[i]], *b = P[v[(i + 1) % n]],
                     *c = P[v[(i + 2) % n]];
        int s = geo_orient2d_proj(a, b, c, ax);
        if (s == -want)
            return false;
        if (s == 0) {
            /* straight: fine unless the boundary folds back on itself */
            double e1[3], e2[3];
            geo_vsub(b, a, e1);
            geo_vsub(c, b, e2);
            if (geo_vdot(e1, e2) < 0)
                return false;
        } else {
            strict = true;
        }
        for (int t = 0; t < 2; t++) {
            int k = (ax + 1 + t) % 3;
            /* the sign of a difference of doubles is exact */
            int d = (b[k] > a[k]) - (b[k] < a[k]);
            if (d == 0)
                continue;
            if (last[t] != 0 && d != last[t])
                changes[t]++;
            last[t] = d;
        }
    }
    /* the cycle closes: compare the first nonzero direction with the last */
    for (int t = 0; t < 2; t++) {
        int k = (ax + 1 + t) % 3, first = 0;
        for (uint32_t i = 0; i < n && first == 0; i++) {
            const double *a = P[v[i]], *b = P[v[(i + 1) % n]];
            first = (b[k] > a[k]) - (b[k] < a[k]);
        }
        if (first != 0 && last[t] != 0 && first != last[t])
            changes[t]++;
        if (changes[t] > 2)
            return false;
    }
    return strict;
}
