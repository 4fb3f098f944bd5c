/* poly.c — storage, construction, measures and compaction of geo_poly.
 * Invariant kept by every function here: fstart[0] = 0, fstart is
 * non-decreasing, planes has one entry per facet (or is NULL: implicit
 * planes, see poly.h, which only the readers make). */
#include "poly.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "plane.h"
#include "vec.h"

geo_poly *geo_poly_new(void)
{
    geo_poly *p = calloc(1, sizeof *p);
    if (!p)
        return NULL;
    p->fstart = calloc(1, sizeof *p->fstart);
    if (!p->fstart) {
        free(p);
        return NULL;
    }
    p->cap_facets = 0;
    /* the arrays are never NULL, even for an empty model, so that every
     * kernel may memcpy a whole (empty) array */
    if (geo_poly_reserve(p, 1, 1, 1) < 0)
        return geo_poly_free(p);
    return p;
}

geo_poly *geo_poly_free(geo_poly *p)
{
    if (!p)
        return NULL;
    free(p->verts);
    free(p->fstart);
    free(p->fidx);
    free(p->planes);
    free(p);
    return NULL;
}

void geo_poly_clear(geo_poly *p)
{
    p->nverts = 0;
    p->nfacets = 0;
    p->fstart[0] = 0;
}

static size_t grow_to(size_t cap, size_t need)
{
    size_t c = cap ? cap : 16;
    while (c < need)
        c = c + c / 2 + 16;
    return c;
}

int geo_poly_reserve(geo_poly *p, size_t nverts, size_t nfacets,
                     size_t ncorners)
{
    if (nverts > GEO_POLY_MAX_VERTS || nfacets > GEO_POLY_MAX_CORNERS ||
        ncorners > GEO_POLY_MAX_CORNERS)
        return -ERANGE;
    if (nverts > p->cap_verts) {
        size_t c = grow_to(p->cap_verts, nverts);
        void *v = realloc(p->verts, c * sizeof *p->verts);
        if (!v)
            return -ENOMEM;
        p->verts = v;
        p->cap_verts = (uint32_t)c;
    }
    if (nfacets > p->cap_facets) {
        size_t c = grow_to(p->cap_facets, nfacets);
        void *s = realloc(p->fstart, (c + 1) * sizeof *p->fstart);
        if (!s)
            return -ENOMEM;
        p->fstart = s;
        void *pl = realloc(p->planes, c * sizeof *p->planes);
        if (!pl)
            return -ENOMEM;
        p->planes = pl;
        p->cap_facets = (uint32_t)c;
    }
    if (ncorners > p->cap_idx) {
        size_t c = grow_to(p->cap_idx, ncorners);
        void *v = realloc(p->fidx, c * sizeof *p->fidx);
        if (!v)
            return -ENOMEM;
        p->fidx = v;
        p->cap_idx = (uint32_t)c;
    }
    return 0;
}

int64_t geo_poly_add_vertex(geo_poly *p, const double xyz[3])
{
    int r = geo_poly_reserve(p, (size_t)p->nverts + 1, 0, 0);
    if (r < 0)
        return r;
    memcpy(p->verts[p->nverts], xyz, sizeof p->verts[0]);
    return p->nverts++;
}

int64_t geo_poly_add_facet(geo_poly *p, const uint32_t *idx, uint32_t n)
{
    size_t nc = geo_poly_ncorners(p);
    int r = geo_poly_reserve(p, 0, (size_t)p->nfacets + 1, nc + n);
    if (r < 0)
        return r;
    if (n)
        memcpy(p->fidx + nc, idx, n * sizeof *idx);
    memset(p->planes[p->nfacets], 0, sizeof p->planes[0]);
    p->fstart[p->nfacets + 1] = (uint32_t)(nc + n);
    return p->nfacets++;
}

int geo_poly_assign(geo_poly *dst, const geo_poly *src)
{
    uint32_t nc = geo_poly_ncorners(src);
    int r = geo_poly_reserve(dst, src->nverts, src->nfacets, nc);
    if (r < 0)
        return r;
    if (src->nverts)
        memcpy(dst->verts, src->verts, src->nverts * sizeof *src->verts);
    memcpy(dst->fstart, src->fstart, (src->nfacets + 1) * sizeof *src->fstart);
    if (nc)
        memcpy(dst->fidx, src->fidx, nc * sizeof *src->fidx);
    if (src->nfacets && src->planes)
        memcpy(dst->planes, src->planes, src->nfacets * sizeof *src->planes);
    for (uint32_t f = 0; !src->planes && f < src->nfacets; f++)
        geo_poly_facet_plane(src, f, dst->planes[f]); /* made explicit */
    dst->nverts = src->nverts;
    dst->nfacets = src->nfacets;
    return 0;
}

geo_poly *geo_poly_copy(const geo_poly *p)
{
    geo_poly *q = geo_poly_new();
    if (!q)
        return NULL;
    if (geo_poly_assign(q, p) < 0)
        return geo_poly_free(q);
    return q;
}

int geo_poly_validate_indices(const geo_poly *p, geo_err *err)
{
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *v = geo_poly_facet(p, f);
        if (n < 3)
            return geo_err_set(err, -EINVAL,
                               "facets[%u].vertices: %u vertices, a facet "
                               "needs at least 3", f, n);
        for (uint32_t i = 0; i < n; i++) {
            if (v[i] >= p->nverts)
                return geo_err_set(err, -EINVAL,
                                   "facets[%u].vertices[%u]: index %u out of "
                                   "range (%u vertices)", f, i, v[i],
                                   p->nverts);
            uint32_t j = (i + 1) % n;
            if (v[i] == v[j])
                return geo_err_set(err, -EINVAL,
                                   "facets[%u].vertices[%u]: index %u "
                                   "repeated consecutively", f, j, v[i]);
        }
    }
    return 0;
}

geo_poly *geo_poly_from_arrays(uint32_t nv, const double *xyz, uint32_t nf,
                               const uint32_t *fstart, const uint32_t *fidx,
                               const double *planes, geo_err *err)
{
    if (fstart[0] != 0) {
        geo_err_set(err, -EINVAL, "facets: offsets must start at 0");
        return NULL;
    }
    for (uint32_t f = 0; f < nf; f++)
        if (fstart[f + 1] < fstart[f]) {
            geo_err_set(err, -EINVAL, "facets[%u]: decreasing offset", f);
            return NULL;
        }
    geo_poly *p = geo_poly_new();
    if (!p || geo_poly_reserve(p, nv, nf, fstart[nf]) < 0) {
        geo_err_set(err, -ENOMEM, "out of memory");
        return geo_poly_free(p);
    }
    for (uint32_t i = 0; i < 3 * nv; i++)
        if (!isfinite(xyz[i])) {
            geo_err_set(err, -EINVAL, "vertices[%u][%u]: not a finite number",
                        i / 3, i % 3);
            return geo_poly_free(p);
        }
    if (nv)
        memcpy(p->verts, xyz, (size_t)nv * sizeof *p->verts);
    memcpy(p->fstart, fstart, ((size_t)nf + 1) * sizeof *fstart);
    if (fstart[nf])
        memcpy(p->fidx, fidx, (size_t)fstart[nf] * sizeof *fidx);
    p->nverts = nv;
    p->nfacets = nf;
    if (geo_poly_validate_indices(p, err) < 0)
        return geo_poly_free(p);
    if (planes && nf)
        memcpy(p->planes, planes, (size_t)nf * sizeof *p->planes);
    else
        geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    return p;
}

void geo_poly_facet_area_vector(const geo_poly *p, uint32_t f, double ret[3])
{
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *v = geo_poly_facet(p, f);
    double s[3] = {0, 0, 0};
    if (n == 0) {
        memcpy(ret, s, sizeof s);
        return;
    }
    /* relative to the first vertex: less cancellation far from origin */
    const double *o = p->verts[v[0]];
    for (uint32_t i = 1; i + 1 < n; i++) {
        double a[3], b[3], c[3];
        geo_vsub(p->verts[v[i]], o, a);
        geo_vsub(p->verts[v[i + 1]], o, b);
        geo_vcross(a, b, c);
        geo_vadd(s, c, s);
    }
    memcpy(ret, s, sizeof s);
}

double geo_poly_facet_area(const geo_poly *p, uint32_t f)
{
    double a[3];
    geo_poly_facet_area_vector(p, f, a);
    return 0.5 * geo_vlen(a);
}

void geo_poly_facet_center(const geo_poly *p, uint32_t f, double ret[3])
{
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *v = geo_poly_facet(p, f);
    double c[3] = {0, 0, 0};
    for (uint32_t i = 0; i < n; i++)
        geo_vadd(c, p->verts[v[i]], c);
    geo_vscale(c, n ? 1.0 / n : 0.0, ret);
}

void geo_poly_facet_fit_plane(const geo_poly *p, uint32_t f,
                              enum geo_plane_weight weight, double ret[4])
{
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *v = geo_poly_facet(p, f);
    double area[3];
    geo_poly_facet_area_vector(p, f, area);
    if (n == 3) {
        /* three points lie exactly on one plane: the least-squares plane
         * (weighted or not) is the plane through them, whose normal is
         * their cross product, the Newell vector, and which passes
         * through their centroid, as the fit's does; no eigenproblem.
         * A zero cross product (collinear) gives the zero plane, as the
         * fallback below would. */
        double c[3];
        geo_poly_facet_center(p, f, c);
        if (geo_plane_from_point_normal(c, area, ret) < 0)
            memset(ret, 0, 4 * sizeof *ret);
        return;
    }

    enum { STACK = 64 };
    double pts_stack[STACK][3], w_stack[STACK];
    double (*pts)[3] = pts_stack;
    double *w = w_stack;
    if (n > STACK) {
        pts = malloc(n * sizeof *pts);
        w = malloc(n * sizeof *w);
    }
    int r = -EINVAL;
    if (pts && w) {
        for (uint32_t i = 0; i < n; i++) {
            memcpy(pts[i], p->verts[v[i]], sizeof pts[i]);
            if (weight == GEO_PLANE_EDGE_WEIGHTED) {
                const double *prev = p->verts[v[(i + n - 1) % n]];
                const double *next = p->verts[v[(i + 1) % n]];
                w[i] = 0.5 * (geo_vdist(prev, pts[i]) +
                              geo_vdist(next, pts[i]));
            }
        }
        r = geo_plane_fit(&pts[0][0],
                          weight == GEO_PLANE_EDGE_WEIGHTED ? w : NULL, n,
                          area, ret);
    }
    if (r < 0) {
        /* degenerate polygon: keep whatever direction Newell gives */
        double c[3];
        geo_poly_facet_center(p, f, c);
        if (geo_plane_from_point_normal(c, area, ret) < 0)
            memset(ret, 0, 4 * sizeof *ret);
    }
    if (pts != pts_stack)
        free(pts);
    if (w != w_stack)
        free(w);
}

void geo_poly_facet_plane(const geo_poly *p, uint32_t f, double ret[4])
{
    if (p->planes) {
        memcpy(ret, p->planes[f], 4 * sizeof *ret);
        return;
    }
    geo_poly_facet_fit_plane(p, f, GEO_PLANE_UNWEIGHTED, ret);
    for (int k = 0; k < 4; k++)
        ret[k] += 0.0; /* as proto_finish_planes stores it */
}

void geo_poly_compute_planes(geo_poly *p, enum geo_plane_weight weight)
{
    for (uint32_t f = 0; f < p->nfacets; f++)
        geo_poly_facet_fit_plane(p, f, weight, p->planes[f]);
}

void geo_poly_bbox(const geo_poly *p, double ret_lo[3], double ret_hi[3])
{
    if (p->nverts == 0) {
        for (int k = 0; k < 3; k++)
            ret_lo[k] = ret_hi[k] = 0;
        return;
    }
    for (int k = 0; k < 3; k++)
        ret_lo[k] = ret_hi[k] = p->verts[0][k];
    for (uint32_t i = 1; i < p->nverts; i++)
        for (int k = 0; k < 3; k++) {
            double x = p->verts[i][k];
            if (x < ret_lo[k])
                ret_lo[k] = x;
            if (x > ret_hi[k])
                ret_hi[k] = x;
        }
}

double geo_poly_size(const geo_poly *p)
{
    double lo[3], hi[3], d[3];
    geo_poly_bbox(p, lo, hi);
    geo_vsub(hi, lo, d);
    return geo_vlen(d);
}

double geo_eps_of_size(double size)
{
    return 1e-10 * (1.0 + size);
}

double geo_poly_eps(const geo_poly *p)
{
    return geo_eps_of_size(geo_poly_size(p));
}

double geo_fan_volume6(double acc, const double (*x)[3], const uint32_t *v,
                       uint32_t n, const double o[3])
{
    if (n < 3)
        return acc;
    double a[3];
    geo_vsub(x[v[0]], o, a);
    for (uint32_t i = 1; i + 1 < n; i++) {
        double b[3], c[3], bc[3];
        geo_vsub(x[v[i]], o, b);
        geo_vsub(x[v[i + 1]], o, c);
        geo_vcross(b, c, bc);
        acc += geo_vdot(a, bc);
    }
    return acc;
}

double geo_poly_volume(const geo_poly *p)
{
    /* Σ over facets of (fan triangles) o·(a×b)/6, relative to the bbox
     * centre to keep the sum well conditioned */
    double lo[3], hi[3], o[3];
    geo_poly_bbox(p, lo, hi);
    geo_vadd(lo, hi, o);
    geo_vscale(o, 0.5, o);
    double vol = 0;
    for (uint32_t f = 0; f < p->nfacets; f++)
        vol = geo_fan_volume6(vol, (const double(*)[3])p->verts,
                              geo_poly_facet(p, f), geo_poly_facet_size(p, f),
                              o);
    return vol / 6.0;
}

double geo_poly_area(const geo_poly *p)
{
    double s = 0;
    for (uint32_t f = 0; f < p->nfacets; f++)
        s += geo_poly_facet_area(p, f);
    return s;
}

double geo_poly_max_nonplanarity(const geo_poly *p)
{
    double m = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *v = geo_poly_facet(p, f);
        double pl[4];
        geo_poly_facet_plane(p, f, pl);
        for (uint32_t i = 0; i < n; i++) {
            double d = fabs(geo_plane_eval(pl, p->verts[v[i]]));
            if (d > m)
                m = d;
        }
    }
    return m;
}

void geo_poly_flip_facet(geo_poly *p, uint32_t f)
{
    uint32_t *v = p->fidx + p->fstart[f];
    uint32_t n = geo_poly_facet_size(p, f);
    for (uint32_t i = 0, j = n - 1; i < j; i++, j--) {
        uint32_t t = v[i];
        v[i] = v[j];
        v[j] = t;
    }
    for (int k = 0; k < 4; k++)
        p->planes[f][k] = -p->planes[f][k];
}

int geo_poly_compact(geo_poly *p, const bool *keep_facet, uint32_t *ret_vmap,
                     uint32_t *ret_fmap)
{
    uint32_t *vmap = malloc(((size_t)p->nverts + 1) * sizeof *vmap);
    if (!vmap)
        return -ENOMEM;
    for (uint32_t i = 0; i < p->nverts; i++)
        vmap[i] = UINT32_MAX;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        if (keep_facet && !keep_facet[f])
            continue;
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *v = geo_poly_facet(p, f);
        for (uint32_t i = 0; i < n; i++)
            vmap[v[i]] = 0;
    }
    uint32_t nv = 0;
    for (uint32_t i = 0; i < p->nverts; i++)
        if (vmap[i] == 0) {
            vmap[i] = nv;
            if (nv != i)
                memcpy(p->verts[nv], p->verts[i], sizeof p->verts[0]);
            nv++;
        }
    uint32_t nf = 0, nc = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t start = p->fstart[f], n = p->fstart[f + 1] - start;
        bool keep = !keep_facet || keep_facet[f];
        if (ret_fmap)
            ret_fmap[f] = keep ? nf : UINT32_MAX;
        if (!keep)
            continue;
        for (uint32_t i = 0; i < n; i++)
            p->fidx[nc + i] = vmap[p->fidx[start + i]];
        if (nf != f)
            memcpy(p->planes[nf], p->planes[f], sizeof p->planes[0]);
        p->fstart[nf] = nc;
        nc += n;
        nf++;
        p->fstart[nf] = nc;
    }
    p->fstart[nf] = nc;
    if (ret_vmap)
        memcpy(ret_vmap, vmap, p->nverts * sizeof *vmap);
    p->nverts = nv;
    p->nfacets = nf;
    free(vmap);
    return 0;
}
