/* merge_groups.c — finding the groups to merge automatically, and the
 * rounds of geo_merge_auto.
 *
 * A group grows from a seed facet (the largest facet not yet in a group)
 * by adding, one at a time, the neighbour (across an edge) whose normal is
 * closest to the group's plane, as long as (a) every member's normal stays
 * within max_angle of the plane, (b) every vertex of the members stays
 * within max_dev of it — on a scan, or within the roof the view step
 * leaves over a group that wide and that inclined, if that is more — and
 * (c) on a scan, the joining facet lies within the scan's own error of
 * the plane the group had before it (area RMS distance). The plane is
 * the least-squares plane of the members' distinct vertices, kept as
 * running moments (about the seed's first vertex, so the sums do not
 * cancel) and solved with the 3×3 eigen solver for every candidate. A
 * candidate that fails is not tried again for that group.
 *
 * Why (b) and (c): the vertices of one true facet's slivers stay within
 * the scan's error, a few µm, of one plane, and along every true edge the
 * scanner leaves bevels, narrow strips whose normals lie anywhere between
 * the two facets that meet there, so no angle separates slivers from true
 * facets (README "Automatic correction" has the measurements). But (b)
 * alone lets the refitted plane split the difference: two true facets
 * 2.8° apart and 0.16 mm wide deviate only ±2 µm from their common plane,
 * less than a single facet's scan vertices do. The joining facet's RMS
 * distance from the plane before it joined does not split anything: such
 * a neighbour lies 4.5 µm RMS off, a sliver of the same facet within its
 * noise plus the roof its view step leaves (step × extent). (c) uses the
 * surface noise measured on the scan itself (merge_scale.c). The roof in
 * (b): a sliver is a silhouette plane through one of the facet's true
 * edges, its normal up to half a view step in azimuth, so up to
 * step × sin(inclination) / 2 in tilt, off the facet's; two such planes
 * from opposite edges of a facet of width w meet in a ridge up to
 * w × step × sin(inclination) / 4 high (GEO_GROUP_ROOF_FACTOR), tens of
 * µm on a princess's pavilion at K = 100.
 * Cost per group O(c · (m + v)) for c candidates, m members, v vertices;
 * groups are small. */
#include "merge_impl.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "plane.h"
#include "vec.h"

typedef struct area_id {
    double area;
    uint32_t f;
} area_id;

static int cmp_area(const void *a, const void *b)
{
    const area_id *x = a, *y = b;
    if (x->area != y->area)
        return x->area > y->area ? -1 : 1;
    return (x->f > y->f) - (x->f < y->f);
}

typedef struct grower {
    geo_mw *w;
    geo_edit *e;
    const geo_group_crit *c;
    double lo[3], hi[3]; /* box of the members' vertices */
    double o[3];        /* origin of the moments */
    double s[3], ss[3][3];
    uint32_t cnt;
    double seedn[3];
    double plane[4];
    uint32_t *mem, nmem, capmem;
    uint32_t *vs, nvs, capvs;
    uint32_t *cand, ncand, capcand;
} grower;

/* Plane of the moments plus the extra points xs[0..nx), and (axis, may be
 * NULL) its middle axis of inertia; false when the points are collinear. */
static bool moments_plane(const grower *g, const double (*xs)[3], uint32_t nx,
                          double ret[4], double axis[3])
{
    double s[3], ss[3][3];
    memcpy(s, g->s, sizeof s);
    memcpy(ss, g->ss, sizeof ss);
    uint32_t cnt = g->cnt + nx;
    for (uint32_t i = 0; i < nx; i++) {
        double d[3];
        geo_vsub(xs[i], g->o, d);
        for (int a = 0; a < 3; a++) {
            s[a] += d[a];
            for (int b = a; b < 3; b++)
                ss[a][b] += d[a] * d[b];
        }
    }
    if (cnt < 3)
        return false;
    double mu[3], c[3][3];
    for (int a = 0; a < 3; a++)
        mu[a] = s[a] / cnt;
    for (int a = 0; a < 3; a++)
        for (int b = a; b < 3; b++)
            c[a][b] = ss[a][b] / cnt - mu[a] * mu[b];
    double val[3], vec[3][3];
    geo_sym3_eigen(c, val, vec);
    if (!(val[1] > 0))
        return false;
    double *n = vec[0];
    if (geo_vdot(n, g->seedn) < 0)
        geo_vscale(n, -1, n);
    double p[3];
    geo_vadd(mu, g->o, p);
    memcpy(ret, n, 3 * sizeof *n);
    ret[3] = -geo_vdot(n, p);
    if (axis)
        memcpy(axis, vec[1], 3 * sizeof *axis);
    return true;
}

static void moments_add(grower *g, const double x[3])
{
    double d[3];
    geo_vsub(x, g->o, d);
    for (int a = 0; a < 3; a++) {
        g->s[a] += d[a];
        for (int b = a; b < 3; b++)
            g->ss[a][b] += d[a] * d[b];
    }
    g->cnt++;
}

void geo_mw_facet_moments(const geo_edit *e, uint32_t f, const double o[3],
                          double *a, double s[3], double ss[3][3])
{
    geo_fan_moments((const double(*)[3])e->verts, geo_edit_fv(e, f),
                    geo_edit_fn(e, f), o, a, s, ss);
}

/* Area RMS distance of facet f from plane pl. */
static double rms_from_plane(const geo_edit *e, uint32_t f, const double pl[4])
{
    double o[3], a = 0, s[3] = {0, 0, 0}, ss[3][3] = {{0}};
    memcpy(o, e->verts[geo_edit_fv(e, f)[0]], sizeof o);
    geo_mw_facet_moments(e, f, o, &a, s, ss);
    if (!(a > 0))
        return 0;
    /* d(x) = n·(x − o) + h with h = pl(o): ∫d² = nᵀSS n + 2h n·s + h² a */
    const double *n = pl;
    double h = geo_plane_eval(pl, o), q = 0;
    for (int k = 0; k < 3; k++)
        for (int l = 0; l < 3; l++)
            q += n[k] * n[l] * (k <= l ? ss[k][l] : ss[l][k]);
    double m = (q + 2 * h * geo_vdot(n, s)) / a + h * h;
    return sqrt(fmax(m, 0));
}

/* The deviation bound (b) for a group of plane pl whose extent along the
 * plane's middle axis of inertia is width: the roof the view step leaves
 * over a facet that wide rises by up to width × step × sin(inclination)
 * / 4, the inclination being the angle between pl and the horizontal
 * (the scanner turns the stone about z; README). */
static double dev_bound(const geo_group_crit *c, const double pl[4], double width)
{
    double sin_incl = sqrt(pl[0] * pl[0] + pl[1] * pl[1]);
    return fmax(c->max_dev, GEO_GROUP_ROOF_FACTOR * sin_incl * width * c->step);
}

/* Extent of the points vs[0..n) (vertex ids) and xs[0..nx) along axis. */
static double extent_along(const geo_edit *e, const uint32_t *vs, uint32_t n,
                           const double (*xs)[3], uint32_t nx,
                           const double axis[3])
{
    double lo = INFINITY, hi = -INFINITY;
    for (uint32_t i = 0; i < n; i++) {
        double t = geo_vdot(axis, e->verts[vs[i]]);
        geo_minmax(t, &lo, &hi);
    }
    for (uint32_t i = 0; i < nx; i++) {
        double t = geo_vdot(axis, xs[i]);
        geo_minmax(t, &lo, &hi);
    }
    return hi > lo ? hi - lo : 0;
}

/* Would facet f fit the group? On success the plane is returned in
 * ret_plane. */
static bool fits(grower *g, uint32_t f, double ret_plane[4])
{
    geo_edit *e = g->e;
    geo_mw *w = g->w;
    const geo_group_crit *c = g->c;
    uint32_t n = geo_edit_fn(e, f);
    const uint32_t *fv = geo_edit_fv(e, f);
    double extra[64][3];
    uint32_t nx = 0;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t v = fv[i];
        if (w->vmark[v] == w->gen)
            continue;
        if (nx == 64)
            return false;
        memcpy(extra[nx++], e->verts[v], sizeof extra[0]);
    }
    double lo[3], hi[3], d[3];
    memcpy(lo, g->lo, sizeof lo);
    memcpy(hi, g->hi, sizeof hi);
    for (uint32_t i = 0; i < nx; i++)
        for (int k = 0; k < 3; k++)
            geo_minmax(extra[i][k], &lo[k], &hi[k]);
    geo_vsub(hi, lo, d);
    double ext = geo_vlen(d);
    double pl[4], ax[3];
    if (!moments_plane(g, (const double(*)[3])extra, nx, pl, ax))
        return false;
    if (geo_vdot(e->planes[f], pl) < c->cosmax)
        return false;
    for (uint32_t i = 0; i < g->nmem; i++)
        if (geo_vdot(e->planes[g->mem[i]], pl) < c->cosmax)
            return false;
    /* the roof grows with the width, which the box's diagonal bounds
     * (the margin covers rounding): only a group whose roof could pass
     * max_dev needs its extent along the axis, O(its vertices) */
    double mdev = c->max_dev;
    if (dev_bound(c, pl, ext * (1 + 1e-9)) > c->max_dev)
        mdev = dev_bound(c, pl, extent_along(e, g->vs, g->nvs,
                                             (const double(*)[3])extra, nx,
                                             ax));
    for (uint32_t i = 0; i < nx; i++)
        if (fabs(geo_plane_eval(pl, extra[i])) > mdev)
            return false;
    for (uint32_t i = 0; i < g->nvs; i++)
        if (fabs(geo_plane_eval(pl, e->verts[g->vs[i]])) > mdev)
            return false;
    if (c->noise > 0) {
        double tol = GEO_GROUP_RMS_FACTOR * c->noise +
                     GEO_GROUP_STEP_FACTOR * ext * c->step;
        if (rms_from_plane(e, f, g->plane) > tol)
            return false;
    }
    memcpy(ret_plane, pl, sizeof pl);
    return true;
}

static int add_member(grower *g, uint32_t f, uint8_t *taken)
{
    geo_edit *e = g->e;
    geo_mw *w = g->w;
    if (geo_mw_grow(&g->mem, &g->capmem, (size_t)g->nmem + 1) < 0)
        return -ENOMEM;
    g->mem[g->nmem++] = f;
    taken[f] = 1;
    w->fmark[f] = w->gen;
    uint32_t n = geo_edit_fn(e, f);
    for (uint32_t i = 0; i < n; i++) {
        uint32_t v = geo_edit_fv(e, f)[i];
        if (w->vmark[v] == w->gen)
            continue;
        w->vmark[v] = w->gen;
        if (geo_mw_grow(&g->vs, &g->capvs, (size_t)g->nvs + 1) < 0)
            return -ENOMEM;
        g->vs[g->nvs++] = v;
        moments_add(g, e->verts[v]);
        for (int k = 0; k < 3; k++) {
            g->lo[k] = fmin(g->lo[k], e->verts[v][k]);
            g->hi[k] = fmax(g->hi[k], e->verts[v][k]);
        }
    }
    /* its neighbours become candidates, each once per group: the stamp
     * marks a facet that was a candidate (or member) of this group, so a
     * facet of 60,000 edges adds its neighbours in linear time */
    for (uint32_t i = 0; i < n; i++) {
        const uint32_t *fv = geo_edit_fv(e, f);
        uint32_t a = fv[i], b = fv[i + 1 < n ? i + 1 : 0];
        uint32_t h = geo_edit_across(e, f, a, b);
        if (h == GEO_NONE || taken[h] || w->fmark[h] == w->gen)
            continue;
        if (geo_mw_grow(&g->cand, &g->capcand, (size_t)g->ncand + 1) < 0)
            return -ENOMEM;
        w->fmark[h] = w->gen;
        g->cand[g->ncand++] = h;
    }
    return 0;
}

int geo_mw_find_groups(geo_mw *w, const geo_group_crit *c, const geo_ctx *ctx,
                       uint32_t **ret_start, uint32_t **ret_facets,
                       uint32_t *ret_n)
{
    uint64_t work = 0; /* candidate visits since the last cancel check */
    geo_edit *e = w->e;
    uint32_t nf = e->nfacets, nlive = 0;
    area_id *order = malloc(((size_t)nf + 1) * sizeof *order);
    uint8_t *taken = calloc((size_t)nf + 1, 1);
    uint32_t *start = malloc(sizeof *start), *facets = NULL;
    uint32_t ng = 0, nfl = 0, capstart = 1, capfacets = 0;
    grower g;
    memset(&g, 0, sizeof g);
    g.w = w;
    g.e = e;
    g.c = c;
    int r = 0;
    if (!order || !taken || !start)
        goto oom;
    for (uint32_t f = 0; f < nf; f++) {
        if (!e->falive[f])
            continue;
        double a[3];
        geo_edit_area_vector(e, f, a);
        order[nlive].area = geo_vlen(a);
        order[nlive++].f = f;
    }
    qsort(order, nlive, sizeof *order, cmp_area);
    start[0] = 0;
    for (uint32_t k = 0; k < nlive; k++) {
        uint32_t seed = order[k].f;
        if (taken[seed])
            continue;
        if (geo_mw_stamp(w) < 0)
            goto oom;
        g.nmem = g.nvs = g.ncand = g.cnt = 0;
        memset(g.s, 0, sizeof g.s);
        memset(g.ss, 0, sizeof g.ss);
        memcpy(g.o, e->verts[geo_edit_fv(e, seed)[0]], sizeof g.o);
        memcpy(g.seedn, e->planes[seed], sizeof g.seedn);
        for (int a = 0; a < 3; a++) {
            g.lo[a] = INFINITY;
            g.hi[a] = -INFINITY;
        }
        if (add_member(&g, seed, taken) < 0)
            goto oom;
        memcpy(g.plane, e->planes[seed], sizeof g.plane);
        for (;;) {
            work += g.ncand + 1;
            if (work >= (1u << 20)) {
                work = 0;
                if (geo_ctx_canceled(ctx)) {
                    r = -ECANCELED;
                    goto done;
                }
            }
            /* the candidate closest in normal to the plane */
            uint32_t bi = GEO_NONE;
            double bd = -2;
            for (uint32_t j = 0; j < g.ncand; j++) {
                uint32_t h = g.cand[j];
                double d = geo_vdot(e->planes[h], g.plane);
                if (d > bd || (d == bd && h < g.cand[bi])) {
                    bd = d;
                    bi = j;
                }
            }
            if (bi == GEO_NONE)
                break;
            uint32_t h = g.cand[bi];
            g.cand[bi] = g.cand[--g.ncand];
            if (taken[h])
                continue;
            double pl[4];
            if (bd < c->cosmax || !fits(&g, h, pl)) {
                continue; /* rejected; its stamp keeps it out */
            }
            if (add_member(&g, h, taken) < 0)
                goto oom;
            memcpy(g.plane, pl, sizeof pl);
        }
        if (g.nmem < 2)
            continue;
        if (geo_mw_grow(&start, &capstart, (size_t)ng + 2) < 0 ||
            geo_mw_grow(&facets, &capfacets, (size_t)nfl + g.nmem) < 0)
            goto oom;
        memcpy(facets + nfl, g.mem, g.nmem * sizeof *facets);
        nfl += g.nmem;
        start[++ng] = nfl;
    }
    *ret_start = start;
    *ret_facets = facets;
    *ret_n = ng;
    start = facets = NULL;
    goto done;
oom:
    r = -ENOMEM;
done:
    free(order), free(taken), free(start), free(facets);
    free(g.mem), free(g.vs), free(g.cand);
    return r;
}

/* Does the group still meet the criterion on the current model? Groups
 * of a round are found on the model the round started from; a group
 * merged earlier in the round may have lifted or cut the facets of a
 * later one, whose vertices can then lie far from any common plane. */
static int still_fits(geo_mw *w, const uint32_t *mem, uint32_t n,
                      const geo_group_crit *c, bool *ret)
{
    geo_edit *e = w->e;
    if (geo_mw_stamp(w) < 0)
        return -ENOMEM;
    grower g;
    memset(&g, 0, sizeof g);
    g.w = w;
    g.e = e;
    memcpy(g.o, e->verts[geo_edit_fv(e, mem[0])[0]], sizeof g.o);
    memcpy(g.seedn, e->planes[mem[0]], sizeof g.seedn);
    int r = 0;
    for (uint32_t i = 0; i < n && r == 0; i++) {
        uint32_t nv = geo_edit_fn(e, mem[i]);
        for (uint32_t j = 0; j < nv; j++) {
            uint32_t v = geo_edit_fv(e, mem[i])[j];
            if (w->vmark[v] == w->gen)
                continue;
            w->vmark[v] = w->gen;
            if (geo_mw_grow(&g.vs, &g.capvs, (size_t)g.nvs + 1) < 0) {
                r = -ENOMEM;
                break;
            }
            g.vs[g.nvs++] = v;
            moments_add(&g, e->verts[v]);
        }
    }
    double pl[4], ax[3];
    bool ok = r == 0 && moments_plane(&g, NULL, 0, pl, ax);
    for (uint32_t i = 0; ok && i < n; i++)
        ok = geo_vdot(e->planes[mem[i]], pl) >= c->cosmax;
    double mdev = ok ? dev_bound(c, pl, extent_along(e, g.vs, g.nvs, NULL, 0, ax)) : 0;
    for (uint32_t i = 0; ok && i < g.nvs; i++)
        ok = fabs(geo_plane_eval(pl, e->verts[g.vs[i]])) <= mdev;
    free(g.vs);
    *ret = ok;
    return r;
}

int geo_mw_auto_round(geo_mw *w, const geo_group_crit *c, const geo_ctx *ctx,
                      double frac0, double frac1, geo_merge_report *rep,
                      uint32_t *ret_merged, geo_err *err)
{
    uint32_t *start = NULL, *facets = NULL, ng = 0, merged = 0;
    w->ctx = ctx;
    int r = geo_mw_world_build(w, err);
    if (r < 0)
        return r;
    if ((r = geo_mw_find_groups(w, c, ctx, &start, &facets, &ng)) < 0)
        return geo_err_set(err, r, r == -ECANCELED ? "merge canceled"
                                                   : "out of memory");
    uint32_t *live = NULL, caplive = 0;
    for (uint32_t g = 0; g < ng; g++) {
        if ((g & 15) == 0 &&
            geo_ctx_progress(ctx, frac0 + (frac1 - frac0) * g / ng) < 0) {
            r = geo_err_set(err, -ECANCELED, "merge canceled");
            break;
        }
        /* members merged away by an earlier group of this round drop out */
        uint32_t n = 0;
        if (geo_mw_grow(&live, &caplive, (size_t)start[g + 1] - start[g] + 1) < 0) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            break;
        }
        for (uint32_t k = start[g]; k < start[g + 1]; k++)
            if (w->e->falive[facets[k]])
                live[n++] = facets[k];
        if (n < 2)
            continue;
        bool ok;
        if (still_fits(w, live, n, c, &ok) < 0) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            break;
        }
        if (!ok)
            continue; /* found again, as it now is, next round */
        geo_merge_group *gr;
        if (geo_merge_report_add(rep, live, n, &gr) < 0) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            break;
        }
        geo_err gerr;
        r = geo_mw_merge(w, live, n, gr, &gerr);
        if (r == 0)
            merged++;
        else if (r == -EINVAL)
            r = 0;
        else {
            geo_err_set(err, r, "%s", gerr.msg);
            break;
        }
    }
    free(live), free(start), free(facets);
    *ret_merged = merged;
    return r;
}
