/* merge_contour.c — the contour enclosing a group of facets (Palachev 2012, §2.4)
 * and the least-squares plane of that contour (§2.5).
 *
 * The walk follows the boundary edges of the group counter-clockwise seen
 * from outside: from a boundary edge a→b of a group facet it turns about b
 * through group facets until the next edge whose facet across is not in
 * the group. The paper finds that edge with its NF count (the next vertex
 * in one group facet only); that test fails where a contour edge joins two
 * vertices that each lie in two group facets (a fan of three slivers about
 * an interior vertex has such edges), so the facet across the edge decides
 * here instead — the same contour wherever the paper's walk succeeds.
 *
 * A group is merged only when it is simply connected (§2.1): one contour
 * loop that passes every vertex once and covers every boundary edge, and
 * Euler characteristic V − E + F = 1 (a disc). */
#include "merge_impl.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "plane.h"
#include "vec.h"

/* Is f marked as a member of the current group? */
static bool in_group(const geo_mw *w, uint32_t f)
{
    return f != GEO_NONE && w->fmark[f] == w->gen;
}

/* Adds the area, first and second moments of facet f's surface (fan of
 * triangles; for a triangle a, b, c of area A: ∫x = A·g with g the mean
 * of the corners, ∫x xᵀ = A/12 (a aᵀ + b bᵀ + c cᵀ + s sᵀ), s = a + b + c),
 * coordinates relative to w->mo. */
static void area_moments(geo_mw *w, uint32_t f)
{
    const geo_edit *e = w->e;
    uint32_t n = geo_edit_fn(e, f);
    const uint32_t *vs = geo_edit_fv(e, f);
    double a[3];
    geo_vsub(e->verts[vs[0]], w->mo, a);
    for (uint32_t i = 1; i + 1 < n; i++) {
        double b[3], c[3], ab[3], ac[3], x[3];
        geo_vsub(e->verts[vs[i]], w->mo, b);
        geo_vsub(e->verts[vs[i + 1]], w->mo, c);
        geo_vsub(b, a, ab);
        geo_vsub(c, a, ac);
        geo_vcross(ab, ac, x);
        geo_vadd(w->mn, x, w->mn);
        double A = 0.5 * geo_vlen(x), s[3];
        if (!(A > 0))
            continue;
        geo_vadd(a, b, s);
        geo_vadd(s, c, s);
        w->ma += A;
        for (int p = 0; p < 3; p++) {
            w->ms[p] += A * s[p] / 3.0;
            for (int q = p; q < 3; q++)
                w->mss[p][q] += A / 12.0 *
                                (a[p] * a[q] + b[p] * b[q] + c[p] * c[q] + s[p] * s[q]);
        }
    }
}

int geo_mw_contour(geo_mw *w, const uint32_t *group, uint32_t n,
                   uint32_t *ret_main, uint32_t *ret_nverts,
                   geo_merge_group *rep, geo_err *err)
{
    geo_edit *e = w->e;
    if (n < 2)
        return geo_err_set(err, -EINVAL, "a group needs at least 2 facets");
    for (uint32_t i = 0; i < n; i++) {
        uint32_t f = group[i];
        if (f >= e->nfacets || !e->falive[f])
            return geo_err_set(err, -EINVAL, "facets[%u]: no such facet%s", f,
                               f < e->nfacets ? " (merged earlier)" : "");
        if (w->fmark[f] == w->gen)
            return geo_err_set(err, -EINVAL, "facets[%u]: listed twice", f);
        w->fmark[f] = w->gen;
    }

    /* boundary edges, distinct vertices, and a first boundary edge */
    uint32_t nb = 0, nv = 0, sum = 0, g0 = GEO_NONE, j0 = 0;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t f = group[i], m = geo_edit_fn(e, f);
        sum += m;
        for (uint32_t j = 0; j < m; j++) {
            const uint32_t *vs = geo_edit_fv(e, f);
            uint32_t a = vs[j], b = vs[j + 1 < m ? j + 1 : 0];
            uint32_t g = geo_edit_across(e, f, a, b);
            if (g == GEO_NONE)
                return geo_err_set(err, -EINVAL,
                                   "facets[%u]: edge %u-%u has no single "
                                   "facet across (model not closed)", f, a, b);
            if (!in_group(w, g)) {
                nb++;
                if (g0 == GEO_NONE) {
                    g0 = f;
                    j0 = j;
                }
            }
            if (w->vmark[a] != w->gen) {
                w->vmark[a] = w->gen;
                if (geo_mw_grow(&w->buf_c, &w->cap_c, (size_t)nv + 1) < 0)
                    return geo_err_set(err, -ENOMEM, "out of memory");
                w->buf_c[nv++] = a;
            }
        }
    }
    if (g0 == GEO_NONE)
        return geo_err_set(err, -EINVAL, "the group has no boundary (it is "
                           "the whole surface)");
    uint32_t ne = (sum + nb) / 2;
    if ((int64_t)nv - ne + n != 1)
        return geo_err_set(err, -EINVAL,
                           "the group is not simply connected (V-E+F = %lld)",
                           (long long)nv - ne + n);

    /* the walk; contour vertices are marked in vmark2 to catch a vertex
     * passed twice */
    if (geo_mw_grow(&w->buf_a, &w->cap_a, (size_t)nb + 1) < 0)
        return geo_err_set(err, -ENOMEM, "out of memory");
    uint32_t len = 0, g = g0, j = j0;
    for (;;) {
        uint32_t m = geo_edit_fn(e, g);
        const uint32_t *vs = geo_edit_fv(e, g);
        uint32_t a = vs[j];
        if (len == nb)
            return geo_err_set(err, -EINVAL, "the contour does not close");
        if (w->vmark2[a] == w->gen)
            return geo_err_set(err, -EINVAL,
                               "vertices[%u]: the contour passes this vertex "
                               "twice (the group is pinched there)", a);
        w->vmark2[a] = w->gen;
        w->buf_a[len++] = a;
        /* turn about b = the edge's end until a boundary edge leaves it */
        uint32_t b = vs[j + 1 < m ? j + 1 : 0];
        uint32_t h = g, pb = j + 1 < m ? j + 1 : 0, turns = 0;
        for (;;) {
            uint32_t hm = geo_edit_fn(e, h);
            const uint32_t *hv = geo_edit_fv(e, h);
            uint32_t c = hv[pb + 1 < hm ? pb + 1 : 0];
            uint32_t x = geo_edit_across(e, h, b, c);
            if (!in_group(w, x))
                break;
            h = x;
            pb = geo_edit_find(e, h, b);
            if (pb == GEO_NONE || ++turns > n)
                return geo_err_set(err, -EINVAL, "vertices[%u]: the group's "
                                   "facets do not form a fan here", b);
        }
        g = h;
        j = pb;
        if (g == g0 && j == j0)
            break;
    }
    if (len != nb)
        return geo_err_set(err, -EINVAL,
                           "the group has %u boundary edges but its contour "
                           "%u: more than one contour (a hole)", nb, len);
    rep->contour = len;

    /* area moments of the group's surface, for the area plane */
    memset(w->ms, 0, sizeof w->ms);
    memset(w->mss, 0, sizeof w->mss);
    memset(w->mn, 0, sizeof w->mn);
    w->ma = 0;
    memcpy(w->mo, e->verts[geo_edit_fv(e, group[0])[0]], sizeof w->mo);
    for (uint32_t i = 0; i < n; i++)
        area_moments(w, group[i]);

    /* the group becomes one facet on the contour */
    double nrm[4] = {0, 0, 0, 0};
    for (uint32_t i = 0; i < n; i++) {
        if (geo_edit_kill_facet(e, group[i]) < 0)
            return geo_err_set(err, -ENOMEM, "out of memory");
    }
    int64_t mf = geo_edit_add_facet(e, w->buf_a, len, nrm);
    if (mf < 0)
        return geo_err_set(err, (int)mf, "out of memory");
    uint32_t main = (uint32_t)mf;

    /* §2.4 step 8: hanging vertices (in two facets only). Departure: a
     * neighbour that is a triangle on three consecutive contour points
     * would keep two vertices; it is absorbed into the merged facet
     * instead (its third edge then borders the merged facet), which can
     * leave its other two vertices hanging in turn, hence the repeat. */
    uint32_t hung = 0;
    for (bool again = true; again;) {
        again = false;
        for (uint32_t i = 0; i < geo_edit_fn(e, main); i++) {
            uint32_t v = geo_edit_fv(e, main)[i];
            if (geo_edit_vn(e, v) != 2)
                continue;
            const uint32_t *l = geo_edit_vf(e, v);
            uint32_t other = l[0] == main ? l[1] : l[0];
            int r = 0;
            if (geo_edit_fn(e, other) == 3)
                r = geo_edit_kill_facet(e, other);
            else
                r = geo_edit_remove(e, other, geo_edit_find(e, other, v));
            if (r < 0 || geo_edit_remove(e, main, i) < 0)
                return geo_err_set(err, -ENOMEM, "out of memory");
            if (geo_edit_fn(e, main) < 3)
                return geo_err_set(err, -EINVAL, "the contour has fewer than "
                                   "3 vertices once hanging vertices are "
                                   "removed");
            hung++;
            again = true;
            break;
        }
    }
    rep->hanging = hung;
    *ret_main = main;
    *ret_nverts = nv;
    return 0;
}

/* The plane through the area centroid normal to the axis of least
 * inertia of the group's surface. */
static int area_plane(const geo_mw *w, double ret[4])
{
    if (!(w->ma > 0))
        return -EINVAL;
    double mu[3], c[3][3], val[3], vec[3][3];
    for (int p = 0; p < 3; p++)
        mu[p] = w->ms[p] / w->ma;
    for (int p = 0; p < 3; p++)
        for (int q = p; q < 3; q++)
            c[p][q] = w->mss[p][q] / w->ma - mu[p] * mu[q];
    geo_sym3_eigen(c, val, vec);
    if (!(val[1] > 0))
        return -EINVAL;
    double *nrm = vec[0], x[3];
    if (geo_vdot(nrm, w->mn) < 0)
        geo_vscale(nrm, -1, nrm);
    geo_vadd(mu, w->mo, x);
    memcpy(ret, nrm, 3 * sizeof *nrm);
    ret[3] = -geo_vdot(nrm, x);
    return 0;
}

int geo_mw_plane(geo_mw *w, uint32_t main, double ret_plane[4], geo_err *err)
{
    geo_edit *e = w->e;
    if (w->fixed_plane) {
        memcpy(ret_plane, w->fixed_plane, 4 * sizeof *ret_plane);
        return 0;
    }
    if (w->plane_mode == GEO_MERGE_PLANE_AREA) {
        if (area_plane(w, ret_plane) < 0)
            return geo_err_set(err, -EINVAL, "the group has no area: no plane");
        return 0;
    }
    uint32_t m = geo_edit_fn(e, main);
    const uint32_t *vs = geo_edit_fv(e, main);
    double(*pts)[3] = malloc((size_t)m * sizeof *pts);
    double *wt = malloc((size_t)m * sizeof *wt);
    if (!pts || !wt) {
        free(pts), free(wt);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    for (uint32_t i = 0; i < m; i++) {
        memcpy(pts[i], e->verts[vs[i]], sizeof pts[i]);
        const double *prev = e->verts[vs[i ? i - 1 : m - 1]];
        const double *next = e->verts[vs[i + 1 < m ? i + 1 : 0]];
        wt[i] = 0.5 * (geo_vdist(prev, pts[i]) + geo_vdist(next, pts[i]));
    }
    double area[3];
    geo_edit_area_vector(e, main, area);
    int r = geo_plane_fit(&pts[0][0],
                          w->plane_mode == GEO_MERGE_PLANE_CONTOUR_WEIGHTED ? wt
                                                                            : NULL,
                          m,
                          area, ret_plane);
    free(pts), free(wt);
    if (r < 0)
        return geo_err_set(err, -EINVAL, "the contour's points are collinear: "
                           "no plane");
    return 0;
}
