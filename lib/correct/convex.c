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

#include "ascent.h"
#include "halfspace.h"
#include "plane.h"
#include "ptree.h"
#include "replanar.h"
#include "topo.h"
#include "vec.h"

/* The checks catch gross failures (a true facet lost, a plane fitted to
 * something else), not the scan's error: a result vertex may lie outside
 * the scan by this many noise bounds (the planes pass through the
 * hinges, which the noise moves either way) or half the largest roof or
 * deviation bound, whichever is more. */
#define OUTSIDE_FACTOR 3.0

/* A scan vertex may lie outside the result by the noise bound plus the
 * roof at it (geo_convex_roof_at) times this. */
#define ROOF_FACTOR 3.0

/* Facets narrower (twice the area over the perimeter) than NARROW noise
 * bounds are not resolved by the scan; up to NARROW_ROUNDS rounds. */
#define NARROW 20.0
#define NARROW_ROUNDS 3

/* A plane is needed when the intersection without it leaves some
 * silhouette of the scan by more than NEED_FACTOR noise scales (the
 * larger of the scan's surface noise and the hinges' scatter, at least
 * NEED_REL of the model's size): drop_unneeded. */
#define NEED_FACTOR 3.0
#define NEED_REL 1e-6
/* drop_unneeded's rounds, and the most neighbours of a facet it looks
 * at */
#define UNNEEDED_ROUNDS 3
#define RING_MAX 30

/* readmit: a dropped group comes back when its cut (beyond its own
 * roof) and the corner it cuts off from outside the scan both exceed the
 * noise (the support test's unit, drop_unneeded's margin) and one of
 * them by READMIT times. On the fixed suite 51 dropped groups pass; all
 * but three are taken out again by the narrow and unneeded tests, and
 * the three left add a facet each to their scans. The seven facets a
 * fancy's rounded end lost (test_convex) come back, their corners
 * 2.4–3.7 margins outside the scan. On fitted planes (the adjustment
 * declined) the corner alone must exceed READMIT margins: a heart's
 * dropped crown facets reached 10 µm, 2.4 margins. */
#define READMIT 2.0

/* The silhouettes a result may be clipped by (clip_to_scan): a few
 * corners' worth; beyond that the planes are wrong, not a corner. */
#define CLIP_ROUNDS 4
#define CLIP_MAX 8

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

static int cmp_area_asc(const void *a, const void *b, void *ctx)
{
    const double *ar = ctx;
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    if (ar[x] != ar[y])
        return ar[x] < ar[y] ? -1 : 1;
    return (x > y) - (x < y);
}

/* Removes the planes of cp marked by a NaN offset, with their
 * allowances; the groups' indices follow. 0 or -ENOMEM. */
static int remove_marked(geo_convex_planes *cp)
{
    uint32_t m = 0, *to = malloc(((size_t)cp->nplanes + 1) * sizeof *to);
    if (!to)
        return -ENOMEM;
    for (uint32_t i = 0; i < cp->nplanes; i++) {
        to[i] = GEO_NONE;
        if (isnan(cp->planes[i][3]))
            continue;
        memmove(cp->planes[m], cp->planes[i], sizeof cp->planes[0]);
        cp->allow[m] = cp->allow[i];
        to[i] = m++;
    }
    for (uint32_t g = 0; g < cp->ngroups; g++)
        if (cp->kept[g] != GEO_NONE && cp->kept[g] < cp->nplanes)
            cp->kept[g] = to[cp->kept[g]];
    free(to);
    cp->nplanes = m;
    return 0;
}

/* Would the stone reach farther than need outside the scan p without
 * facet f of q (plane pl)? The region beyond pl is bounded by the planes
 * of f's neighbours, so its vertices are among the meets of three of
 * those planes that satisfy them all; any silhouette plane of p more
 * than need below one of them says yes. A vertex that some farther
 * plane would cut off can only say yes wrongly (the plane is kept),
 * never no. ring: the neighbours' planes, k of them. */
static bool reaches_beyond(const geo_poly *p, const double pl[4],
                           const double (*ring)[4], uint32_t k, double tol,
                           double need, geo_plane_triples *tr, int *err)
{
    if (geo_plane_triples_set(tr, ring, k) < 0) {
        *err = -ENOMEM;
        return true;
    }
    uint32_t first = 0; /* the ring plane that last cut a meet off */
    for (uint32_t a = 0; a < k; a++)
        for (uint32_t b = a + 1; b < k; b++)
            for (uint32_t c = b + 1; c < k; c++) {
                double x[3];
                if (!geo_plane_triples_meet(tr, a, b, c, x) ||
                    geo_plane_eval(pl, x) <= 0)
                    continue;
                /* the planes in turn from the last one that cut: the
                 * same answer, found sooner */
                bool ok = true;
                for (uint32_t i = 0; i < k && ok; i++) {
                    uint32_t m = first + i < k ? first + i : first + i - k;
                    ok = geo_plane_eval(ring[m], x) <= tol;
                    if (!ok)
                        first = m;
                }
                for (uint32_t f = 0; ok && f < p->nfacets; f++)
                    if (geo_plane_eval(p->planes[f], x) > need)
                        return true;
            }
    return false;
}

/* The planes of facet f's neighbours in q and of a far box (q's box lo,
 * hi padded by pad), into ring (at most RING_MAX; more make the test
 * unsure: *ret_k = 0). */
static void ring_of(const geo_poly *q, const geo_topo *t, uint32_t f,
                    const double lo[3], const double hi[3], double pad,
                    uint32_t *mark, uint32_t stamp, double (*ring)[4],
                    uint32_t *ret_k)
{
    /* a box far around q closes the region where the neighbours do not
     * (the facet's plane then bounds the model alone): its corners lie
     * far outside the scan, so such a plane is always needed */
    uint32_t k = 0;
    for (int a = 0; a < 3; a++) {
        double n[3] = {0, 0, 0};
        n[a] = 1;
        ring[k][0] = n[0], ring[k][1] = n[1], ring[k][2] = n[2];
        ring[k++][3] = -(hi[a] + pad);
        ring[k][0] = -n[0], ring[k][1] = -n[1], ring[k][2] = -n[2];
        ring[k++][3] = lo[a] - pad;
    }
    mark[f] = stamp;
    for (uint32_t c = q->fstart[f]; c < q->fstart[f + 1]; c++) {
        uint32_t h = geo_topo_neighbor(t, c);
        if (h == GEO_NONE || mark[h] == stamp)
            continue;
        if (k == RING_MAX) {
            *ret_k = 0;
            return;
        }
        mark[h] = stamp;
        memcpy(ring[k++], q->planes[h], sizeof ring[0]);
    }
    *ret_k = k;
}

/* Planes the scan does not need: a plane goes when, without it, the
 * intersection would still lie inside every silhouette of the scan p to
 * within need (mm, a few noise scales). A true facet's plane cuts off
 * a corner the silhouettes hold; a bevel strip that the noise left along
 * a true edge, or a second plane of one true facet, cuts off no more
 * than the noise. Smallest result facets first; a facet next to one that
 * goes waits for the next round, the intersection rebuilt between
 * rounds (UNNEEDED_ROUNDS). rep->unneeded counts them. 0, 1 (declined),
 * -ENOMEM. */
static int drop_unneeded(const geo_poly *p, geo_convex_planes *cp,
                         double need, double tol, geo_poly **q,
                         uint32_t **src, geo_convex_report *rep,
                         geo_err *err)
{
    int r = 0;
    geo_plane_triples tr = {0};
    for (int round = 0; round < UNNEEDED_ROUNDS; round++) {
        geo_poly *g = *q;
        uint32_t nf = g->nfacets, ngone = 0;
        geo_err perr;
        geo_topo *t = geo_topo_build(g, &perr);
        uint32_t *order = malloc(((size_t)nf + 1) * sizeof *order);
        uint32_t *mark = calloc((size_t)nf + 1, sizeof *mark);
        uint8_t *near = calloc((size_t)nf + 1, 1);
        double *area = malloc(((size_t)nf + 1) * sizeof *area);
        double (*ring)[4] = malloc(RING_MAX * sizeof *ring);
        if (!t || !order || !mark || !near || !area || !ring) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
        } else {
            for (uint32_t f = 0; f < nf; f++) {
                order[f] = f;
                area[f] = geo_poly_facet_area(g, f);
            }
            qsort_r(order, nf, sizeof *order, cmp_area_asc, area);
            double lo[3], hi[3];
            geo_poly_bbox(g, lo, hi);
            double pad = 10 * geo_poly_size(g);
            for (uint32_t i = 0; i < nf; i++) {
                uint32_t f = order[i], k;
                if (near[f])
                    continue;
                ring_of(g, t, f, lo, hi, pad, mark, i + 1, ring, &k);
                int terr = 0;
                if (k < 9 || reaches_beyond(p, g->planes[f],
                                            (const double(*)[4])ring, k,
                                            tol, need, &tr, &terr)) {
                    if (terr < 0) {
                        r = geo_err_set(err, terr, "out of memory");
                        break;
                    }
                    continue;
                }
                cp->planes[(*src)[f]][3] = NAN;
                ngone++;
                for (uint32_t c = g->fstart[f]; c < g->fstart[f + 1]; c++) {
                    uint32_t h = geo_topo_neighbor(t, c);
                    if (h != GEO_NONE)
                        near[h] = 1;
                }
            }
        }
        geo_topo_free(t);
        free(order), free(mark), free(near), free(area), free(ring);
        if (r < 0 || ngone == 0)
            break;
        if (remove_marked(cp) < 0) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            break;
        }
        rep->unneeded += ngone;
        r = intersect(cp, tol, "the planes the scan needs", 160, q, src, rep,
                      err);
        if (r != 0)
            break;
    }
    geo_plane_triples_free(&tr);
    return r;
}

/* *dst = a copy of src's planes, allowances, groups, spares and spans
 * (nf: the scan's facets; the area is not copied), with room for extra
 * more planes. 0 or -ENOMEM (dst zeroed). */
static int planes_copy_room(geo_convex_planes *dst,
                            const geo_convex_planes *src, uint32_t nf,
                            uint32_t extra)
{
    *dst = *src;
    dst->area = NULL;
    size_t np = (size_t)src->nplanes + extra + 1,
           ng = (size_t)src->ngroups + 1, ns = (size_t)src->nspare + 1;
    dst->planes = malloc(np * sizeof *dst->planes);
    dst->allow = malloc(np * sizeof *dst->allow);
    dst->kept = malloc(ng * sizeof *dst->kept);
    dst->group = malloc(((size_t)nf + 1) * sizeof *dst->group);
    dst->spare = malloc(ns * sizeof *dst->spare);
    dst->span = malloc(ng * sizeof *dst->span);
    if (!dst->planes || !dst->allow || !dst->kept || !dst->group ||
        !dst->spare || !dst->span) {
        geo_convex_planes_clear(dst);
        return -ENOMEM;
    }
    memcpy(dst->planes, src->planes, src->nplanes * sizeof *dst->planes);
    memcpy(dst->allow, src->allow, src->nplanes * sizeof *dst->allow);
    memcpy(dst->kept, src->kept, src->ngroups * sizeof *dst->kept);
    memcpy(dst->group, src->group, nf * sizeof *dst->group);
    memcpy(dst->spare, src->spare, src->nspare * sizeof *dst->spare);
    memcpy(dst->span, src->span, src->ngroups * sizeof *dst->span);
    return 0;
}

static int planes_copy(geo_convex_planes *dst, const geo_convex_planes *src,
                       uint32_t nf)
{
    return planes_copy_room(dst, src, nf, 0);
}

/* How far a result vertex may lie outside the scan (check_result). */
static double outside_allow(const geo_convex_planes *cp, double max_dev)
{
    double roof_max = 0;
    for (uint32_t i = 0; i < cp->nplanes; i++)
        roof_max = fmax(roof_max, cp->allow[i]);
    return OUTSIDE_FACTOR * fmax(fmax(cp->dev0, cp->hinge_noise),
                                 fmax(max_dev, roof_max) / 2);
}

/* The highest value of every plane of p at a vertex of the convex q, by
 * ascent along q's edges: a linear function has no local maximum on a
 * convex polytope but its highest vertex, and consecutive scan facets
 * are mostly neighbours, so each plane's ascent starts at the previous
 * plane's top and takes a few steps. q's vertices lie on its planes to
 * the planarity tolerance, so a top is the highest within about that.
 * 0 with *ret; 1 when q's edges do not join all its vertices or one is
 * not finite; -ENOMEM. */
static int reach_by_ascent(const geo_poly *p, const geo_poly *q, double *ret)
{
    uint32_t nv = q->nverts, nc = geo_poly_ncorners(q);
    uint32_t *start = calloc((size_t)nv + 2, sizeof *start);
    uint32_t *adj = malloc(((size_t)nc + 1) * sizeof *adj);
    uint8_t *seen = calloc((size_t)nv + 1, 1);
    uint32_t *order = malloc(((size_t)nv + 1) * sizeof *order);
    if (!start || !adj || !seen || !order) {
        free(start), free(adj), free(seen), free(order);
        return -ENOMEM;
    }
    /* each facet edge from its corner's vertex to the next */
    for (int pass = 0; pass < 2; pass++) {
        for (uint32_t f = 0; f < q->nfacets; f++) {
            uint32_t n = geo_poly_facet_size(q, f);
            const uint32_t *fv = geo_poly_facet(q, f);
            for (uint32_t i = 0, prev = n ? fv[n - 1] : 0; i < n;
                 prev = fv[i++]) {
                if (pass == 0)
                    start[prev + 2]++;
                else
                    adj[start[prev + 1]++] = fv[i];
            }
        }
        if (pass == 0)
            for (uint32_t v = 0; v < nv; v++)
                start[v + 2] += start[v + 1];
    }
    /* every vertex reached from the first, breadth first, and finite */
    uint32_t ns = 0;
    for (uint32_t v = 0; v < nv; v++)
        if (!isfinite(q->verts[v][0] + q->verts[v][1] + q->verts[v][2]))
            nv = 0;
    if (nv > 0) {
        seen[0] = 1;
        order[ns++] = 0;
    }
    for (uint32_t i = 0; i < ns; i++)
        for (uint32_t a = start[order[i]]; a < start[order[i] + 1]; a++)
            if (!seen[adj[a]]) {
                seen[adj[a]] = 1;
                order[ns++] = adj[a];
            }
    free(seen), free(order);
    if (nv == 0 || ns < nv) {
        free(start), free(adj);
        return 1;
    }
    double out = 0, h;
    uint32_t top = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        const double *pl = p->planes[f];
        top = geo_ascent_top(start, adj, (const double(*)[3])q->verts, pl,
                             top, &h);
        double s = geo_plane_eval(pl, q->verts[top]);
        if (s > out)
            out = s;
    }
    free(start), free(adj);
    *ret = out;
    return 0;
}

/* How far the result q (convex: an intersection of half-spaces) reaches
 * outside the scan p: the largest value of a scan facet's plane at a
 * vertex of q, by ascent; when q's edges do not join its vertices, by
 * the tree of its vertices (every pair when memory is short for it). */
static double reach_outside(const geo_poly *p, const geo_poly *q)
{
    double out = 0;
    if (reach_by_ascent(p, q, &out) == 0)
        return out;
    const double(*x)[3] = (const double(*)[3])q->verts;
    const double(*pl)[4] = (const double(*)[4])p->planes;
    geo_ptree *t = NULL;
    out = 0;
    if (geo_ptree_build(x, q->nverts, &t) == 0 &&
        geo_ptree_reach(t, x, pl, p->nfacets, &out) == 0) {
        geo_ptree_free(t);
        return out;
    }
    geo_ptree_free(t);
    for (uint32_t v = 0; v < q->nverts; v++)
        for (uint32_t f = 0; f < p->nfacets; f++) {
            double d = geo_plane_eval(pl[f], x[v]);
            if (d > out)
                out = d;
        }
    return out;
}

/* Where the result q reaches outside the scan p beyond outside_allow,
 * the silhouettes it crosses are measured bounds of the stone: their
 * planes join cp's (as the stone lies inside every silhouette) and the
 * half-spaces are intersected again, up to CLIP_ROUNDS rounds, at most
 * CLIP_MAX planes in all. Only the corner beyond the silhouette goes
 * (a bevel the scan itself holds), not the whole recovered stone, as a
 * fallback to the merge would. rep->clipped counts the planes added.
 * 0, 1 (declined: the intersection failed), -ENOMEM. */
static int clip_to_scan(const geo_poly *p, geo_convex_planes *cp,
                        double max_dev, double tol, geo_poly **q,
                        uint32_t **src, geo_convex_report *rep, geo_err *err)
{
    double allow = outside_allow(cp, max_dev);
    uint8_t *added = NULL;
    for (int round = 0; round < CLIP_ROUNDS; round++) {
        uint32_t nadd = 0, *add = NULL;
        for (uint32_t f = 0; f < p->nfacets; f++) {
            if (added && added[f])
                continue;
            bool out = false;
            for (uint32_t v = 0; v < (*q)->nverts && !out; v++)
                out = geo_plane_eval(p->planes[f], (*q)->verts[v]) > allow;
            if (!out)
                continue;
            uint32_t *a2 = realloc(add, ((size_t)nadd + 1) * sizeof *add);
            if (!a2) {
                free(add), free(added);
                return geo_err_set(err, -ENOMEM, "out of memory");
            }
            add = a2;
            add[nadd++] = f;
        }
        if (nadd == 0 || rep->clipped + nadd > CLIP_MAX) {
            free(add);
            break;
        }
        if (!added)
            added = calloc((size_t)p->nfacets + 1, 1);
        uint32_t n = cp->nplanes;
        double (*pl)[4] = realloc(cp->planes, ((size_t)n + nadd) * sizeof *pl);
        if (pl)
            cp->planes = pl;
        double *al = pl ? realloc(cp->allow, ((size_t)n + nadd) * sizeof *al)
                        : NULL;
        if (al)
            cp->allow = al;
        if (!added || !pl || !al) {
            free(add), free(added);
            return geo_err_set(err, -ENOMEM, "out of memory");
        }
        for (uint32_t i = 0; i < nadd; i++) {
            memcpy(cp->planes[n + i], p->planes[add[i]], sizeof cp->planes[0]);
            cp->allow[n + i] = cp->dev0;
            added[add[i]] = 1;
        }
        cp->nplanes = n + nadd;
        rep->clipped += nadd;
        free(add);
        int r = intersect(cp, tol, "the planes clipped by the silhouettes",
                          150, q, src, rep, err);
        if (r != 0) {
            free(added);
            return r;
        }
    }
    free(added);
    return 0;
}

/* The checks of the result q (src: its facets' planes in cp) against
 * the scan p: planar, within the bounds the noise and the view step
 * allow. Counts cp's redundant planes. 0 when q passes, 1 when declined
 * (rep->reason says why), -ENOMEM. */
static int check_result(const geo_poly *p, const geo_poly *q,
                        const uint32_t *src, const geo_convex_planes *cp,
                        double max_dev, geo_convex_report *rep,
                        uint32_t *ret_cutting)
{
    if (ret_cutting)
        *ret_cutting = GEO_NONE;
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
    double out = reach_outside(p, q), allow = outside_allow(cp, max_dev);
    rep->bound = allow;
    rep->deviation = out;
    if (out > allow)
        return decline(rep, "the result reaches %.2g mm outside the scan "
                       "(bound %.2g mm)", out, allow);
    /* how far a scan vertex may lie outside a result plane: by the noise
     * bound and the roof the view step leaves over its own facets' groups
     * at that vertex — the least of them — or over that plane's group,
     * whichever is more: a vertex near an edge lies on the slivers of
     * either facet, and the slivers of the plane's own facet rise above
     * it. The roof is the one at the vertex (geo_convex_roof_at): high
     * in the middle of a long facet, nothing where its slivers touch it,
     * so a plane pushed in at a stone's corner shows there */
    double *own = malloc(((size_t)p->nverts + 1) * sizeof *own);
    if (!own)
        return -ENOMEM;
    for (uint32_t v = 0; v < p->nverts; v++)
        own[v] = INFINITY;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t g = cp->group[f], k = cp->kept[g];
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *fv = geo_poly_facet(p, f);
        for (uint32_t i = 0; i < n; i++) {
            const double *x = p->verts[fv[i]];
            double roof = k == GEO_NONE
                              ? cp->cut_min
                              : geo_convex_roof_at(cp, g, cp->planes[k], x);
            double a = cp->dev0 + roof;
            own[fv[i]] = fmin(own[fv[i]], a);
        }
    }
    /* the group of each plane (none for a silhouette clip_to_scan added) */
    uint32_t *pg = malloc(((size_t)cp->nplanes + 1) * sizeof *pg);
    if (!pg) {
        free(own);
        return -ENOMEM;
    }
    for (uint32_t i = 0; i < cp->nplanes; i++)
        pg[i] = GEO_NONE;
    for (uint32_t g = 0; g < cp->ngroups; g++)
        if (cp->kept[g] < cp->nplanes)
            pg[cp->kept[g]] = g;
    /* the pair (scan vertex, result plane) farthest beyond its bound,
     * the first in vertex order (then plane order) among equals; a plane
     * is tested only at the vertices that may lie above its bound (the
     * bound is at least the noise bound) */
    geo_ptree *t = NULL;
    uint32_t *near = malloc(((size_t)p->nverts + 1) * sizeof *near);
    if (!near || geo_ptree_build((const double(*)[3])p->verts, p->nverts,
                                 &t) < 0) {
        free(own), free(pg), free(near);
        return -ENOMEM;
    }
    double worst = 0, worst_allow = 0, margin = 0;
    uint32_t wv = 0, wg = 0;
    for (uint32_t g = 0; g < q->nfacets; g++) {
        double lift = ROOF_FACTOR * cp->dev0 + margin;
        uint32_t nn = geo_ptree_above(t, q->planes[g],
                                      lift - 1e-9 * (1 + fabs(lift)), near);
        uint32_t k = src[g];
        for (uint32_t i = 0; i < nn; i++) {
            uint32_t v = near[i];
            double ov = own[v];
            if (ov == INFINITY)
                continue;
            double e = geo_plane_eval(q->planes[g], p->verts[v]);
            double ag = cp->dev0;
            if (pg[k] != GEO_NONE)
                ag += geo_convex_roof_at(cp, pg[k], cp->planes[k],
                                         p->verts[v]);
            double a = ag > ov ? ag : ov;
            double m = e - ROOF_FACTOR * a;
            if (m > margin ||
                (m == margin && m > 0 && (v < wv || (v == wv && g < wg)))) {
                worst = e;
                worst_allow = ROOF_FACTOR * a;
                margin = worst - worst_allow;
                wv = v, wg = g;
            }
        }
    }
    geo_ptree_free(t);
    free(near);
    free(own);
    free(pg);
    if (worst > worst_allow && ret_cutting)
        *ret_cutting = src[wg];
    if (worst > worst_allow)
        return decline(rep, "the scan lies %.2g mm outside the result "
                       "(bound %.2g mm)", worst, worst_allow);
    if (worst > rep->deviation)
        rep->deviation = worst;
    if (worst_allow > rep->bound)
        rep->bound = worst_allow;
    return 0;
}

/* Where four or more planes nearly meet, the half-space kernel contracts
 * a short edge and the merged vertex lies off one of the planes by up to
 * the contraction length (1e-9 mm here and there, above the model's
 * planarity tolerance): the vertices are moved as little as can be until
 * every facet is planar (lib/replanar, least-norm), each by about that
 * much. A run that does not get there leaves q to the planarity check.
 * 0, or -ENOMEM. */
static int planarize(geo_poly *q, geo_err *err)
{
    if (geo_poly_max_nonplanarity(q) <= geo_poly_eps(q))
        return 0;
    geo_replanar_opts o;
    geo_replanar_opts_default(&o, GEO_REPLANAR_LEAST_NORM);
    o.check = false; /* the result's checks follow */
    geo_replanar_result res;
    geo_err perr;
    int r = geo_replanarize(q, NULL, 0, GEO_REPLANAR_LEAST_NORM, &o, NULL,
                            NULL, &res, &perr);
    if (r == -ENOMEM)
        return geo_err_set(err, r, "out of memory");
    return 0;
}

/* The last steps on the intersection q of cp's planes: the planes the
 * scan does not need go, the silhouettes q crosses clip it, and the
 * result is checked. 0 (passed), 1 (declined), -ENOMEM. */
static int finish(const geo_poly *p, geo_convex_planes *cp, double max_dev,
                  double need, double tol, geo_poly **q, uint32_t **src,
                  geo_convex_report *rep, uint32_t *ret_cutting, geo_err *err)
{
    int r = drop_unneeded(p, cp, need, tol, q, src, rep, err);
    if (r == 0)
        r = planarize(*q, err);
    if (r == 0)
        r = check_result(p, *q, *src, cp, max_dev, rep, ret_cutting);
    if (r == 1 && rep->deviation > outside_allow(cp, max_dev)) {
        /* declined for reaching outside the scan: clipped, checked again */
        r = clip_to_scan(p, cp, max_dev, tol, q, src, rep, err);
        if (r == 0 && rep->clipped > 0) {
            rep->reason[0] = 0;
            r = planarize(*q, err);
            if (r == 0)
                r = check_result(p, *q, *src, cp, max_dev, rep, ret_cutting);
        } else if (r == 0) {
            r = 1;
        }
    }
    return r;
}

/* Intersects cp without the planes marked in gone (NaN offsets): 0 with
 * *ret_q, *ret_src and *ret_cp (a copy) when the intersection exists and
 * reaches no farther outside the scan p than allow; 1 when not (nothing
 * returned); -ENOMEM. */
static int without(const geo_poly *p, const geo_convex_planes *cp,
                   const uint8_t *gone, double allow, double tol,
                   geo_convex_planes *ret_cp, geo_poly **ret_q,
                   uint32_t **ret_src)
{
    geo_convex_planes t;
    if (planes_copy(&t, cp, p->nfacets) < 0)
        return -ENOMEM;
    for (uint32_t i = 0; i < cp->nplanes; i++)
        if (gone[i])
            t.planes[i][3] = NAN;
    if (remove_marked(&t) < 0) {
        geo_convex_planes_clear(&t);
        return -ENOMEM;
    }
    geo_poly *q = NULL;
    uint32_t *src = NULL;
    enum geo_halfspace_status st;
    geo_err perr;
    int r = geo_halfspace_intersect(&t.planes[0][0], t.nplanes, tol, &q,
                                    &src, &st, &perr);
    if (r == -ENOMEM) {
        geo_convex_planes_clear(&t);
        return r;
    }
    if (r < 0 || reach_outside(p, q) > allow) {
        geo_poly_free(q);
        free(src);
        geo_convex_planes_clear(&t);
        return 1;
    }
    *ret_cp = t;
    *ret_q = q;
    *ret_src = src;
    return 0;
}

/* cp, q and src become t, qt and st (the old ones are released). */
static void adopt(geo_convex_planes *cp, geo_poly **q, uint32_t **src,
                  geo_convex_planes *t, geo_poly *qt, uint32_t *st)
{
    geo_convex_planes_clear(cp);
    *cp = *t;
    geo_poly_free(*q);
    free(*src);
    *q = qt;
    *src = st;
}

/* Marks in width[i] (else INFINITY) the planes of cp whose facet in q is
 * narrower (twice the area over the perimeter) than wmin; returns how
 * many. */
static uint32_t narrow_planes(const geo_convex_planes *cp, const geo_poly *q,
                              const uint32_t *src, double wmin, double *width)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < cp->nplanes; i++)
        width[i] = INFINITY;
    for (uint32_t f = 0; f < q->nfacets; f++) {
        uint32_t k = geo_poly_facet_size(q, f);
        const uint32_t *fv = geo_poly_facet(q, f);
        double per = 0;
        for (uint32_t i = 0; i < k; i++)
            per += geo_vdist(q->verts[fv[i]], q->verts[fv[(i + 1) % k]]);
        double w = per > 0 ? 2 * geo_poly_facet_area(q, f) / per : INFINITY;
        if (w < wmin && w < width[src[f]]) {
            n += width[src[f]] == INFINITY;
            width[src[f]] = w;
        }
    }
    return n;
}

/* Appends the planes marked in gone to cp's spares (their groups found
 * through kept, their roofs from their allowances), for the second look:
 * a true narrow facet (a small culet, where eight planes meet at a
 * point) may go here, on fitted planes whose roofs the bound allows.
 * 0 or -ENOMEM. */
static int spare_gone(geo_convex_planes *cp, const uint8_t *gone)
{
    uint32_t add = 0;
    for (uint32_t i = 0; i < cp->nplanes; i++)
        add += gone[i];
    geo_convex_spare *sp = realloc(
        cp->spare, ((size_t)cp->nspare + add + 1) * sizeof *sp);
    if (!sp)
        return -ENOMEM;
    cp->spare = sp;
    for (uint32_t g = 0; g < cp->ngroups; g++) {
        uint32_t i = cp->kept[g];
        if (i == GEO_NONE || i >= cp->nplanes || !gone[i])
            continue;
        geo_convex_spare *e = &cp->spare[cp->nspare++];
        memcpy(e->plane, cp->planes[i], sizeof e->plane);
        e->allow = cp->allow[i];
        e->roof = fmax(0, cp->allow[i] - cp->dev0);
        e->group = g;
    }
    return 0;
}

/* without, the planes it removes kept as spares in the result. */
static int without_spared(const geo_poly *p, geo_convex_planes *cp,
                          const uint8_t *gone, double allow, double tol,
                          geo_convex_planes *ret_cp, geo_poly **ret_q,
                          uint32_t **ret_src)
{
    uint32_t before = cp->nspare;
    if (spare_gone(cp, gone) < 0)
        return -ENOMEM;
    int r = without(p, cp, gone, allow, tol, ret_cp, ret_q, ret_src);
    cp->nspare = before; /* the copy has them; cp is as it was */
    return r;
}

/* A facet narrower than the scan can resolve (NARROW noise bounds) is
 * usually a bevel the support test let through at a corner where many
 * planes meet: its plane goes and the rest are intersected again, up to
 * NARROW_ROUNDS rounds — but only where the stone without it still lies
 * within reach of the scan: reach mm outside it, or, when reach is 0, the
 * scan's bound (outside_allow, the check's own, which allows for fitted
 * planes' roofs). A true narrow facet (a step
 * cut's corner) is needed by the silhouettes: without it its neighbours'
 * planes meet beyond the scan, and the whole correction used to be
 * declined for it. A round's narrow planes go all at once when that
 * passes, else each alone, narrowest first; those that go are kept as
 * spares for readmit. 0 or -ENOMEM. */
static int drop_narrow(const geo_poly *p, geo_convex_planes *cp,
                       double max_dev, double reach, double tol,
                       geo_poly **q, uint32_t **src, geo_convex_report *rep,
                       geo_err *err)
{
    uint8_t *gone = calloc((size_t)cp->nplanes + 1, 1);
    double *width = malloc(((size_t)cp->nplanes + 1) * sizeof *width);
    int r = gone && width ? 0 : -ENOMEM;
    for (int round = 0; round < NARROW_ROUNDS && r == 0; round++) {
        double wmin = NARROW * fmax(cp->dev0, cp->hinge_noise);
        uint32_t ncand = narrow_planes(cp, *q, *src, wmin, width);
        if (ncand == 0)
            break;
        double allow = reach > 0 ? reach : outside_allow(cp, max_dev);
        geo_convex_planes t;
        geo_poly *qt;
        uint32_t *st;
        for (uint32_t i = 0; i < cp->nplanes; i++)
            gone[i] = width[i] < INFINITY;
        r = without_spared(p, cp, gone, allow, tol, &t, &qt, &st);
        if (r == 0) {
            adopt(cp, q, src, &t, qt, st);
            rep->narrow += ncand;
            continue;
        }
        if (r < 0)
            break;
        uint32_t taken = 0;
        for (r = 0; r == 0 || r == 1;) {
            uint32_t best = GEO_NONE;
            for (uint32_t i = 0; i < cp->nplanes; i++)
                if (width[i] < INFINITY &&
                    (best == GEO_NONE || width[i] < width[best]))
                    best = i;
            if (best == GEO_NONE) {
                r = 0;
                break;
            }
            width[best] = INFINITY;
            memset(gone, 0, cp->nplanes);
            gone[best] = 1;
            r = without_spared(p, cp, gone, allow, tol, &t, &qt, &st);
            if (r != 0)
                continue;
            /* the planes past best move down by one */
            memmove(width + best, width + best + 1,
                    (cp->nplanes - best - 1) * sizeof *width);
            adopt(cp, q, src, &t, qt, st);
            taken++;
        }
        rep->narrow += taken;
        if (taken == 0)
            break;
    }
    free(gone);
    free(width);
    if (r < 0)
        return geo_err_set(err, r, "out of memory");
    return 0;
}

/* A plane's true normal lies within the cone of its slivers' normals
 * (each sliver is the facet turned about a hinge; convex_planes.c,
 * within_cone). An adjusted plane turned from its fitted normal by more
 * than the farthest of its group's scan facets, plus a view step and
 * TURN_MARGIN_DEG, was moved by a wrong pair of spanning vertices (a
 * heart's small crown facet at K = 400: 16.4° for a cone of 4.3°, the
 * stone then 16 µm outside the scan): it is held at its fitted place and
 * the others are adjusted again. The margin leaves the scan's error
 * alone: on the fixed suite no plane turns that far. */
#define TURN_MARGIN_DEG 3.0

/* The planes of ca (their fitted normals fit) that the adjustment turned
 * out of their slivers' cone, marked in out (which has the caller's
 * held planes already); how many were newly marked. */
static uint32_t turned_out(const geo_poly *p, const geo_convex_planes *ca,
                           const double (*fit)[4], double *cone,
                           uint8_t *out)
{
    for (uint32_t i = 0; i < ca->nplanes; i++)
        cone[i] = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t k = ca->kept[ca->group[f]];
        if (k < ca->nplanes)
            cone[k] = fmax(cone[k], geo_vangle(fit[k], p->planes[f]));
    }
    uint32_t n = 0;
    for (uint32_t i = 0; i < ca->nplanes; i++) {
        double lim = cone[i] + ca->step + TURN_MARGIN_DEG * M_PI / 180;
        if (!out[i] && geo_vangle(fit[i], ca->planes[i]) > lim) {
            out[i] = 1;
            n++;
        }
    }
    return n;
}

/* Adjusts ca's planes to the silhouettes from the estimate est (its
 * facets' planes src) and intersects them: 0 with *ret_q and *ret_src,
 * 1 when the adjustment fails or the planes bound no solid (rep->reason
 * says so), -ENOMEM. *need grows to the silhouettes' own noise when the
 * adjustment measured it. Planes turned out of their slivers' cone are
 * held and the adjustment repeated once (rep->turned). */
static int adjust(const geo_poly *p, geo_convex_planes *ca,
                  const geo_poly *est, const uint32_t *est_src,
                  const uint8_t *held, double *need, double tol,
                  geo_poly **ret_q, uint32_t **ret_src,
                  geo_convex_report *rep, geo_err *err)
{
    double sc;
    double cluster = GEO_CONVEX_REFINE_CLUSTER *
                     fmax(ca->dev0, ca->hinge_noise);
    size_t np = (size_t)ca->nplanes + 1;
    double (*fit)[4] = malloc(np * sizeof *fit);
    double *cone = malloc(np * sizeof *cone);
    uint8_t *hold = calloc(np, 1);
    if (!fit || !cone || !hold) {
        free(fit), free(cone), free(hold);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    memcpy(fit, ca->planes, ca->nplanes * sizeof *fit);
    if (held)
        memcpy(hold, held, ca->nplanes);
    int r = geo_convex_refine(p, est, est_src, cluster, ca->planes,
                              ca->nplanes, held, &sc);
    uint32_t turned = r == 0 ? turned_out(p, ca, (const double(*)[4])fit,
                                          cone, hold)
                             : 0;
    if (turned) {
        memcpy(ca->planes, fit, ca->nplanes * sizeof *fit);
        r = geo_convex_refine(p, est, est_src, cluster, ca->planes,
                              ca->nplanes, hold, &sc);
        rep->turned += turned;
    }
    free(fit), free(cone), free(hold);
    if (r == -ENOMEM)
        return geo_err_set(err, r, "out of memory");
    if (r < 0)
        return 1;
    /* the silhouettes' own noise, when the adjustment measured it */
    *need = fmax(*need, NEED_FACTOR * sc);
    rep->silhouette_scale = fmax(rep->silhouette_scale, sc);
    return intersect(ca, tol, "the adjusted planes", 170, ret_q, ret_src, rep,
                     err);
}

/* The second look at the dropped groups (the end of step 6 on the
 * kernel's page), on the planes cp and their intersection q before it is
 * finished: the adjusted planes (adjusted), or the fitted ones when the
 * adjustment was declined. The support test drops a group whose cut is
 * within the noise and the roofs of its neighbours' fitted planes: a
 * bevel along a true edge, where two raised planes make even a strip on
 * the true edge cut that deep — but also a small true facet between
 * large ones, whose roofs hide it (the 50° pavilion facets at a fancy's
 * rounded end: 20 µm of roof beside cuts of 4–13 µm). The adjusted planes
 * have no roof: a dropped group comes back when its fitted plane cuts q
 * deeper than its own roof plus the support test's noise unit and the
 * corner it cuts off lies outside the scan by more than need (the
 * question drop_unneeded asks of every plane), one of the two by READMIT
 * times; all such at once, and so the planes step 5 took for narrow
 * bevels (a culet where eight planes meet can go there). They are
 * intersected with cp's (narrow facets dropped as in step 5, but against
 * three noise bounds: adjusted planes have no roof to allow for),
 * adjusted with them from there, and finished (unneeded planes,
 * planarity, the checks).
 *
 * On fitted planes the cut says little (the neighbours' roofs raise the
 * corner it cuts as much as a true facet would), so there a group that
 * cuts comes back on the reach alone — its corner READMIT times need
 * outside the scan, which the true stone, inside the scan to the noise,
 * cannot reach — and a narrow plane goes again only where the stone
 * without it stays within need of the scan (the fitted check's bound
 * allows the roofs: 10 µm on a heart, where its girdle's dropped corners
 * reached 10 µm); nothing is adjusted. Returns 0 when that stone passes
 * and a readmitted plane bounds a facet of it (cp, q, src and rep
 * replaced by the finished ones), 1 when nothing came back (all left as
 * they were, q still to be finished), -ENOMEM. */
static int readmit(const geo_poly *p, geo_convex_planes *cp, bool adjusted,
                   geo_poly **q, uint32_t **src, double max_dev, double need,
                   double tol, geo_convex_report *rep, geo_err *err)
{
    uint32_t n = 0;
    uint8_t *take = calloc((size_t)cp->nspare + 1, 1);
    if (!take)
        return geo_err_set(err, -ENOMEM, "out of memory");
    const geo_poly *g = *q;
    for (uint32_t i = 0; i < cp->nspare; i++) {
        /* how deep it cuts q beyond its roof, and how far outside the
         * scan the corner it cuts off lies (drop_unneeded's question;
         * asked only past the first test, and only as far as it matters) */
        double depth = -INFINITY, outside = -INFINITY;
        for (uint32_t v = 0; v < g->nverts; v++)
            depth = fmax(depth, geo_plane_eval(cp->spare[i].plane, g->verts[v]));
        double cut = depth - cp->spare[i].roof;
        if (!(cut > cp->cut_min))
            continue;
        for (uint32_t v = 0; v < g->nverts && outside <= READMIT * need;
             v++) {
            if (!(geo_plane_eval(cp->spare[i].plane, g->verts[v]) > 0))
                continue;
            for (uint32_t f = 0; f < p->nfacets; f++)
                outside = fmax(outside,
                               geo_plane_eval(p->planes[f], g->verts[v]));
        }
        /* both beyond the noise, one of them clearly: the support test's
         * no is overturned only on evidence well beyond it (on fitted
         * planes the reach alone, clearly: their roofs raise the cut) */
        take[i] = adjusted ? outside > need &&
                                 (cut > READMIT * cp->cut_min ||
                                  outside > READMIT * need)
                           : outside > READMIT * need;
        n += take[i];
    }
    geo_convex_planes cr;
    if (n == 0 || planes_copy_room(&cr, cp, p->nfacets, n) < 0) {
        free(take);
        return n == 0 ? 1 : geo_err_set(err, -ENOMEM, "out of memory");
    }
    uint32_t ns = 0;
    for (uint32_t i = 0; i < cp->nspare; i++) {
        const geo_convex_spare *e = &cp->spare[i];
        if (!take[i]) {
            cr.spare[ns++] = *e;
            continue;
        }
        cr.kept[e->group] = cr.nplanes;
        memcpy(cr.planes[cr.nplanes], e->plane, sizeof cr.planes[0]);
        cr.allow[cr.nplanes++] = e->allow;
    }
    cr.nspare = ns;
    free(take);
    geo_convex_report rr = *rep;
    geo_poly *qe = NULL, *qr = NULL;
    uint32_t *srce = NULL, *srcr = NULL;
    int r = intersect(&cr, tol, "the readmitted planes", 170, &qe, &srce,
                      &rr, err);
    if (r == 0)
        r = drop_narrow(p, &cr, max_dev,
                        adjusted ? OUTSIDE_FACTOR * fmax(cp->dev0,
                                                         cp->hinge_noise)
                                 : need,
                        tol, &qe, &srce, &rr, err);
    /* adjusted again with them: a readmitted plane is a fitted one, up
     * to its roof off, and its neighbours move with it */
    if (r == 0 && adjusted)
        r = adjust(p, &cr, qe, srce, NULL, &need, tol, &qr, &srcr, &rr, err);
    else if (r == 0) {
        qr = qe, srcr = srce;
        qe = NULL, srce = NULL;
    }
    if (r == 0)
        r = finish(p, &cr, max_dev, need, tol, &qr, &srcr, &rr, NULL, err);
    geo_poly_free(qe);
    free(srce);
    /* kept only where a readmitted plane still bounds a facet (the
     * narrow and unneeded tests may take them out again: the stone is
     * then the one before, not a second adjustment of it) */
    uint32_t kept = 0;
    for (uint32_t i = 0; r == 0 && i < cp->nspare; i++) {
        uint32_t at = cr.kept[cp->spare[i].group];
        bool bounds = false;
        for (uint32_t f = 0; at != GEO_NONE && f < qr->nfacets && !bounds;
             f++)
            bounds = srcr[f] == at;
        kept += bounds;
    }
    if (r == 0 && kept > 0) {
        rr.readmitted = kept;
        *rep = rr;
        adopt(cp, q, src, &cr, qr, srcr);
        return 0;
    }
    geo_poly_free(qr);
    free(srcr);
    geo_convex_planes_clear(&cr);
    return r < 0 ? r : 1;
}

/* The adjusted stone (planes *ca, intersection qa, srca, report *ra)
 * becomes the answer in place of cp, q, src and rep; *ca is left empty. */
static void take_adjusted(geo_convex_report *rep, const geo_convex_report *ra,
                          geo_convex_planes *cp, geo_poly **q, uint32_t **src,
                          geo_convex_planes *ca, geo_poly *qa, uint32_t *srca)
{
    *rep = *ra;
    rep->adjusted = true;
    adopt(cp, q, src, ca, qa, srca);
    memset(ca, 0, sizeof *ca);
}

/* When the adjusted stone is declined because the scan lies outside one
 * of its planes — the adjustment took a wrong pair of vertices for that
 * plane's silhouette edge and pushed it into the stone — the adjustment
 * runs again from the fitted planes cp (their intersection q, src) with
 * that plane held at its fitted place, so that its neighbours settle
 * around it, and the stone is finished; up to RESCUE_TRIES planes, each
 * held once and from then on. cutting: the plane of *ca the last check
 * found cut in (GEO_NONE when it declined for another reason). 0 with
 * *ca, *qa, *srca and *ra the passing stone, 1 when it still does not
 * pass, -ENOMEM. */
#define RESCUE_TRIES 4

static int rescue(const geo_poly *p, const geo_convex_planes *cp,
                  const geo_poly *q, const uint32_t *src,
                  geo_convex_planes *ca, uint32_t cutting, double max_dev,
                  double need, double tol, geo_poly **qa, uint32_t **srca,
                  const geo_convex_report *rep, geo_convex_report *ra,
                  geo_err *err)
{
    uint8_t *held = calloc((size_t)cp->nplanes + 1, 1);
    if (!held)
        return geo_err_set(err, -ENOMEM, "out of memory");
    int r = 1;
    for (int t = 0; r == 1 && t < RESCUE_TRIES && cutting != GEO_NONE; t++) {
        uint32_t g = 0;
        while (g < ca->ngroups && ca->kept[g] != cutting)
            g++;
        if (g == ca->ngroups || g >= cp->ngroups ||
            cp->kept[g] == GEO_NONE || held[cp->kept[g]])
            break;
        held[cp->kept[g]] = 1;
        geo_convex_planes_clear(ca);
        if (planes_copy(ca, cp, p->nfacets) < 0) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            break;
        }
        *ra = *rep;
        double nd = need;
        r = adjust(p, ca, q, src, held, &nd, tol, qa, srca, ra, err);
        ra->held = (uint32_t)t + 1;
        if (r == 0)
            r = finish(p, ca, max_dev, nd, tol, qa, srca, ra, &cutting, err);
    }
    free(held);
    return r;
}

int geo_correct_convex(const geo_poly *p, const geo_topo *t,
                       uint32_t views, double noise,
                       double max_dev, enum geo_convex_fit fit,
                       const geo_ctx *ctx, geo_poly **ret,
                       geo_convex_report *report, geo_err *err)
{
    geo_convex_report local, *rep = report ? report : &local;
    memset(rep, 0, sizeof *rep);
    *ret = NULL;
    geo_topo *own = NULL;
    if (!t && !(t = own = geo_topo_build(p, err)))
        return -ENOMEM;
    rep->concavity = concavity(p, t);
    if (rep->concavity > max_dev) {
        geo_topo_free(own);
        return decline(rep, "not convex: a concavity %.2g mm deep (bound "
                       "%.2g mm)", rep->concavity, max_dev);
    }
    if (geo_ctx_canceled(ctx)) {
        geo_topo_free(own);
        return geo_err_set(err, -ECANCELED, "correction canceled");
    }
    geo_convex_planes cp;
    geo_err perr;
    int r = geo_convex_planes_find_topo(p, t, views, noise, fit, ctx, &cp,
                                        &perr);
    geo_topo_free(own);
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
    double need = NEED_FACTOR * fmax(fmax(noise, cp.hinge_noise),
                                     NEED_REL * geo_poly_size(p));
    r = intersect(&cp, merge_tol, "the recovered planes", 170, &q, &src, rep,
                  err);
    if (r != 0)
        goto done;
    r = drop_narrow(p, &cp, max_dev, 0, merge_tol, &q, &src, rep, err);
    if (r != 0)
        goto done;
    if (fit == GEO_CONVEX_FIT_SILHOUETTE) {
        /* the adjusted planes replace the fitted ones only when their
         * intersection passes the checks: an adjustment that took a
         * wrong pair of vertices for a silhouette edge can move a plane
         * far, and the fitted planes are then the better answer */
        geo_convex_planes ca;
        double need0 = need;
        if (planes_copy(&ca, &cp, p->nfacets) < 0) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            goto done;
        }
        geo_poly *qa = NULL;
        uint32_t *srca = NULL, cutting = GEO_NONE;
        geo_convex_report ra = *rep;
        r = adjust(p, &ca, q, src, NULL, &need, merge_tol, &qa, &srca, &ra, err);
        if (r == 0) {
            r = readmit(p, &ca, true, &qa, &srca, max_dev, need, merge_tol,
                        &ra, err);
            if (r == 1)
                r = finish(p, &ca, max_dev, need, merge_tol, &qa, &srca, &ra,
                           &cutting, err);
        }
        bool rescued = false;
        if (r == 1) {
            r = rescue(p, &cp, q, src, &ca, cutting, max_dev, need0,
                       merge_tol, &qa, &srca, rep, &ra, err);
            rescued = r == 0;
        }
        if (r == 0 && !rescued) {
            take_adjusted(rep, &ra, &cp, &q, &src, &ca, qa, srca);
        } else if (r != 0) {
            geo_poly_free(qa);
            free(srca);
            qa = NULL, srca = NULL;
        }
        if (r == -ENOMEM) {
            geo_convex_planes_clear(&ca);
            r = geo_err_set(err, r, "out of memory");
            goto done;
        }
        /* declined: the fitted planes, with their own second look; a
         * rescued stone (some planes held) is taken instead only when
         * it is the simpler one: fewer facets than the fitted stone
         * needs to stay within the scan's bounds, or the fitted one
         * does not pass */
        if (r != 0 || rescued) {
            /* the noise the adjustment measured stands, whatever its
             * planes: the residuals' median, not one plane pushed in */
            rep->silhouette_scale =
                fmax(rep->silhouette_scale, ra.silhouette_scale);
            r = readmit(p, &cp, false, &q, &src, max_dev, need, merge_tol,
                        rep, err);
            if (r == 1)
                r = finish(p, &cp, max_dev, need, merge_tol, &q, &src, rep,
                           NULL, err);
            if (rescued && r >= 0 && (r == 1 || qa->nfacets < q->nfacets)) {
                take_adjusted(rep, &ra, &cp, &q, &src, &ca, qa, srca);
                r = 0;
            } else if (rescued) {
                geo_poly_free(qa);
                free(srca);
            }
        }
        geo_convex_planes_clear(&ca);
    } else {
        r = finish(p, &cp, max_dev, need, merge_tol, &q, &src, rep, NULL,
                   err);
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
