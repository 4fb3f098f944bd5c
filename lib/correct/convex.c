/* convex.c — the convex path of the correction: the scan's convexity,
 * the intersection of the recovered planes and the checks on it
 * (convex.h). p is only read; the result is a new model. */
#include "convex.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "halfspace.h"
#include "topo.h"
#include "vec.h"

/* The checks catch gross failures (a true facet lost, a plane fitted to
 * something else), not the scan's error: a result vertex may lie outside
 * the scan by this many noise bounds (the planes pass through the
 * hinges, which the noise moves either way) or half the largest roof or
 * deviation bound, whichever is more. */
#define OUTSIDE_FACTOR 3.0

/* A scan vertex may lie outside the result by its group's allowance
 * (the noise bound and the roof) times this. */
#define ROOF_FACTOR 3.0

/* Facets narrower (twice the area over the perimeter) than NARROW noise
 * bounds are not resolved by the scan; up to NARROW_ROUNDS rounds. */
#define NARROW 20.0
#define NARROW_ROUNDS 3

/* The deepest local concavity of p: over every edge, how far the
 * neighbour facet's vertices rise above this facet's plane. */
static double concavity(const geo_poly *p, const geo_topo *t)
{
    double worst = 0;
    uint32_t nc = geo_poly_ncorners(p);
    for (uint32_t c = 0; c < nc; c++) {
        uint32_t h = geo_topo_neighbor(t, c);
        if (h == GEO_NONE)
            continue;
        const double *pl = p->planes[t->corner_facet[c]];
        uint32_t n = geo_poly_facet_size(p, h);
        const uint32_t *v = geo_poly_facet(p, h);
        for (uint32_t i = 0; i < n; i++) {
            double d = geo_plane_eval(pl, p->verts[v[i]]);
            if (d > worst)
                worst = d;
        }
    }
    return worst;
}

static int decline(geo_convex_report *rep, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static int decline(geo_convex_report *rep, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(rep->reason, sizeof rep->reason, fmt, ap);
    va_end(ap);
    return 1;
}

/* Intersects the half-spaces of cp's planes into *q and *src (replacing
 * what they held): 0, -ENOMEM with err set, or 1 when they bound no
 * solid, with rep->reason "WHAT: why" (why cut to prec characters). */
static int intersect(const geo_convex_planes *cp, double tol,
                     const char *what, int prec, geo_poly **q,
                     uint32_t **src, geo_convex_report *rep, geo_err *err)
{
    geo_poly *q2 = NULL;
    uint32_t *src2 = NULL;
    enum geo_halfspace_status st;
    geo_err perr;
    int r = geo_halfspace_intersect(&cp->planes[0][0], cp->nplanes, tol, &q2,
                                    &src2, &st, &perr);
    if (r == -ENOMEM)
        return geo_err_set(err, r, "out of memory");
    if (r < 0)
        return decline(rep, "%s: %.*s", what, prec, perr.msg);
    geo_poly_free(*q);
    free(*src);
    *q = q2;
    *src = src2;
    return 0;
}

/* The checks of the result q (src: its facets' planes in cp) against
 * the scan p: planar, within the bounds the noise and the view step
 * allow. Counts cp's redundant planes. 0 when q passes, 1 when declined
 * (rep->reason says why), -ENOMEM. */
static int check_result(const geo_poly *p, const geo_poly *q,
                        const uint32_t *src, const geo_convex_planes *cp,
                        double max_dev, geo_convex_report *rep)
{
    /* a vertex where four planes nearly meet is contracted to one (the
     * kernel's short-edge contraction) and then lies off one of them by
     * up to the contraction length: a result the model's planarity
     * tolerance refuses is never given back as the correction */
    double np = geo_poly_max_nonplanarity(q), eps = geo_poly_eps(q);
    if (np > eps)
        return decline(rep, "the intersection is not planar: a vertex %.2g "
                       "mm off its facet's plane (tolerance %.2g mm)", np, eps);
    uint8_t *seen = calloc((size_t)cp->nplanes + 1, 1);
    if (!seen)
        return -ENOMEM;
    for (uint32_t f = 0; f < q->nfacets; f++)
        seen[src[f]] = 1;
    /* a kept plane that bounds nothing was redundant after all */
    rep->redundant = 0;
    for (uint32_t i = 0; i < cp->nplanes; i++)
        rep->redundant += !seen[i];
    free(seen);
    /* within the scan's bound: every result vertex no farther outside the
     * scan than the noise moves a hinge, every scan vertex no farther
     * outside the result than its group's roof allows */
    /* where many facets meet at shallow angles (a pavilion point, a
     * girdle corner) a plane's error of a noise moves the vertex by many:
     * the bound there is the merge's own deviation bound or the largest
     * roof, whichever is more */
    double roof_max = 0;
    for (uint32_t i = 0; i < cp->nplanes; i++)
        roof_max = fmax(roof_max, cp->allow[i]);
    double out = 0;
    double allow = OUTSIDE_FACTOR * fmax(fmax(cp->dev0, cp->hinge_noise),
                                         fmax(max_dev, roof_max) / 2);
    for (uint32_t v = 0; v < q->nverts; v++)
        for (uint32_t f = 0; f < p->nfacets; f++) {
            double d = geo_plane_eval(p->planes[f], q->verts[v]);
            if (d > out)
                out = d;
        }
    rep->bound = allow;
    rep->deviation = out;
    if (out > allow)
        return decline(rep, "the result reaches %.2g mm outside the scan "
                       "(bound %.2g mm)", out, allow);
    /* each scan vertex's distance outside the result (the largest of its
     * planes' values), once per vertex: its facets only differ in the
     * allowance */
    double *outside = malloc(((size_t)p->nverts + 1) * sizeof *outside);
    if (!outside)
        return -ENOMEM;
    for (uint32_t v = 0; v < p->nverts; v++) {
        double d = -INFINITY;
        for (uint32_t g = 0; g < q->nfacets; g++) {
            double e = geo_plane_eval(q->planes[g], p->verts[v]);
            if (e > d)
                d = e;
        }
        outside[v] = d;
    }
    double worst = 0, worst_allow = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t k = cp->kept[cp->group[f]];
        double a = k == GEO_NONE ? cp->dev0 + cp->cut_min : cp->allow[k];
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *fv = geo_poly_facet(p, f);
        for (uint32_t i = 0; i < n; i++) {
            double d = outside[fv[i]];
            if (d - ROOF_FACTOR * a > worst - worst_allow) {
                worst = d;
                worst_allow = ROOF_FACTOR * a;
            }
        }
    }
    free(outside);
    if (worst > worst_allow)
        return decline(rep, "the scan lies %.2g mm outside the result "
                       "(bound %.2g mm)", worst, worst_allow);
    if (worst > rep->deviation)
        rep->deviation = worst;
    if (worst_allow > rep->bound)
        rep->bound = worst_allow;
    return 0;
}

int geo_correct_convex(const geo_poly *p, uint32_t views, double noise,
                       double max_dev, enum geo_convex_fit fit,
                       const geo_ctx *ctx, geo_poly **ret,
                       geo_convex_report *report, geo_err *err)
{
    geo_convex_report local, *rep = report ? report : &local;
    memset(rep, 0, sizeof *rep);
    *ret = NULL;
    geo_topo *t = geo_topo_build(p, err);
    if (!t)
        return -ENOMEM;
    rep->concavity = concavity(p, t);
    geo_topo_free(t);
    if (rep->concavity > max_dev)
        return decline(rep, "not convex: a concavity %.2g mm deep (bound "
                       "%.2g mm)", rep->concavity, max_dev);
    if (geo_ctx_canceled(ctx))
        return geo_err_set(err, -ECANCELED, "correction canceled");
    geo_convex_planes cp;
    geo_err perr;
    int r = geo_convex_planes_find(p, views, noise, fit, &cp, &perr);
    if (r == -EINVAL)
        return decline(rep, "not a closed manifold");
    if (r < 0)
        return geo_err_set(err, r, "%s", perr.msg);
    rep->groups = cp.ngroups;
    rep->planes = cp.nplanes;
    rep->dropped = cp.dropped;
    geo_poly *q = NULL;
    uint32_t *src = NULL;
    double merge_tol = GEO_HALFSPACE_MERGE * geo_poly_size(p);
    r = intersect(&cp, merge_tol, "the recovered planes", 170, &q, &src, rep,
                  err);
    if (r != 0)
        goto done;
    /* a facet narrower than the scan can resolve (NARROW noise bounds)
     * is a bevel the support test let through at a corner where many
     * planes meet: its plane goes and the rest are intersected again */
    for (int round = 0; round < NARROW_ROUNDS; round++) {
        double wmin = NARROW * fmax(cp.dev0, cp.hinge_noise);
        uint32_t gone = 0;
        for (uint32_t f = 0; f < q->nfacets; f++) {
            uint32_t n = geo_poly_facet_size(q, f);
            const uint32_t *fv = geo_poly_facet(q, f);
            double per = 0;
            for (uint32_t i = 0; i < n; i++)
                per += geo_vdist(q->verts[fv[i]], q->verts[fv[(i + 1) % n]]);
            if (per > 0 && 2 * geo_poly_facet_area(q, f) / per < wmin) {
                cp.planes[src[f]][3] = NAN; /* marked */
                gone++;
            }
        }
        if (gone == 0)
            break;
        uint32_t m = 0;
        for (uint32_t i = 0; i < cp.nplanes; i++)
            if (!isnan(cp.planes[i][3]))
                memmove(cp.planes[m++], cp.planes[i], sizeof cp.planes[0]);
        cp.nplanes = m;
        rep->narrow += gone;
        r = intersect(&cp, merge_tol, "the recovered planes without the "
                      "narrow ones", 150, &q, &src, rep, err);
        if (r != 0)
            goto done;
    }
    if (fit == GEO_CONVEX_FIT_SILHOUETTE) {
        /* the adjusted planes replace the fitted ones only when their
         * intersection passes the checks: an adjustment that took a
         * wrong pair of vertices for a silhouette edge can move a plane
         * far, and the fitted planes are then the better answer */
        double (*fitted)[4] = malloc(((size_t)cp.nplanes + 1) * sizeof *fitted);
        if (!fitted) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            goto done;
        }
        memcpy(fitted, cp.planes, cp.nplanes * sizeof *fitted);
        double sc;
        double cluster = GEO_CONVEX_REFINE_CLUSTER *
                         fmax(cp.dev0, cp.hinge_noise);
        r = geo_convex_refine(p, q, src, cluster, cp.planes, cp.nplanes, &sc);
        geo_poly *qa = NULL;
        uint32_t *srca = NULL;
        if (r == 0) {
            geo_convex_report ra = *rep;
            r = intersect(&cp, merge_tol, "the adjusted planes", 170, &qa,
                          &srca, &ra, err);
            if (r == 0)
                r = check_result(p, qa, srca, &cp, max_dev, &ra);
            if (r == 0) {
                *rep = ra;
                geo_poly_free(q);
                free(src);
                q = qa;
                src = srca;
                qa = NULL;
                srca = NULL;
            }
        }
        geo_poly_free(qa);
        free(srca);
        if (r == -ENOMEM) {
            free(fitted);
            r = geo_err_set(err, r, "out of memory");
            goto done;
        }
        if (r != 0) {
            memcpy(cp.planes, fitted, cp.nplanes * sizeof *fitted);
            r = check_result(p, q, src, &cp, max_dev, rep);
        }
        free(fitted);
    } else {
        r = check_result(p, q, src, &cp, max_dev, rep);
    }
    if (r != 0) {
        if (r == -ENOMEM)
            r = geo_err_set(err, r, "out of memory");
        goto done;
    }
    *ret = q;
    q = NULL;
    r = 0;
done:
    geo_poly_free(q);
    free(src);
    geo_convex_planes_clear(&cp);
    return r;
}
