/* replanar_least_norm.c — the least-norm schedule of replanar.h: steps of
 * least_norm.h on a region of rings around the fixed vertices that grows
 * until its outer ring hardly moves, the planes refitted after each step,
 * vertices left next to their start put back exactly. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "least_norm.h"
#include "replanar_run.h"
#include "vec.h"

/* Steps of least_norm.h are capped here: Gauss–Newton converges in a few
 * or not at all. */
#define LN_MAX_STEPS 50
/* Entries of one factor (12 bytes each: about 200 MB). */
#define LN_MAX_NNZ (UINT64_C(1) << 24)
/* Steps aimed at the least-norm point from the start; the later ones only
 * restore planarity nearest the current positions (Gauss–Newton on the
 * constraints alone, quadratic), instead of creeping on to the exact
 * least-norm point at a linear rate where slivers turn far. */
#define LN_FROM_START 2
/* The first region's rings, and the share of the largest move its outer
 * ring may keep before the region grows. */
#define LN_RINGS 4
#define LN_EDGE 1e-2
/* Steps of one region before it counts as stalled. */
#define LN_ATTEMPT_STEPS 12

/* Refits the planes of the facets with a vertex off its start or fixed
 * (the others keep their start planes exactly), activates them, and sets
 * r's step figures against the positions before the step (prev). */
static void ln_account(run *r, const double (*prev)[3])
{
    const geo_poly *p = r->p0;
    const uint8_t *fixflag = r->fit_all ? NULL : r->vflag;
    double delta = 0, s1 = 0;
    for (uint32_t v = 0; v < p->nverts; v++) {
        if (r->vflag[v] & V_FIXED)
            continue;
        double d[3];
        geo_vsub(r->x[v], prev[v], d);
        delta += geo_vdot(d, d);
        geo_vsub(r->x[v], rp_start_pos(r, v), d);
        s1 += geo_vdot(d, d);
    }
    for (uint32_t f = 0; f < p->nfacets; f++) {
        const uint32_t *fv = geo_poly_facet(p, f);
        uint32_t n = geo_poly_facet_size(p, f);
        bool off = false;
        for (uint32_t i = 0; i < n && !off; i++)
            off = (r->vflag[fv[i]] & V_FIXED) ||
                  memcmp(r->x[fv[i]], rp_start_pos(r, fv[i]),
                         sizeof r->x[0]) != 0;
        if (off) {
            rp_activate_facet(r, f);
            rp_fit_plane(p, r->x, fixflag, f, r->pl[f]);
        } else {
            memcpy(r->pl[f], p->planes[f], sizeof r->pl[f]);
        }
    }
    rp_plane_errors(r);
    r->delta = delta;
    r->s1 = s1;
}

/* The region of a least-norm solve: the facets within `rings` rings (by
 * shared vertices) of the seeds, which are the run's first active facets
 * (those of the fixed vertices and any not planar at the start). ring[f]
 * is the ring of facet f, or UINT32_MAX outside; hold[v] is set for the
 * fixed vertices and for every vertex of a facet of four or more vertices
 * outside the region, which must not move. Returns whether the region is
 * all the seeds' part of the model: no facet's neighbours were left out
 * for the ring limit (a model in several pieces never fills up). */
static bool ln_region(const run *r, uint32_t rings, uint32_t *ring,
                      uint32_t *queue, uint8_t *in, uint8_t *hold)
{
    const geo_poly *p = r->p0;
    const geo_replanar_prep *pr = r->prep;
    uint32_t head = 0, tail = 0;
    bool limited = false;
    for (uint32_t f = 0; f < p->nfacets; f++)
        ring[f] = UINT32_MAX;
    for (uint32_t i = 0; i < r->naf; i++) {
        ring[r->af[i]] = 0;
        queue[tail++] = r->af[i];
    }
    while (head < tail) {
        uint32_t f = queue[head++];
        if (ring[f] + 1 >= rings) {
            limited = true;
            continue;
        }
        const uint32_t *fv = geo_poly_facet(p, f);
        for (uint32_t i = 0, n = geo_poly_facet_size(p, f); i < n; i++)
            for (uint32_t j = pr->vstart[fv[i]]; j < pr->vstart[fv[i] + 1];
                 j++) {
                uint32_t g = pr->vfacets[j];
                if (ring[g] == UINT32_MAX) {
                    ring[g] = ring[f] + 1;
                    queue[tail++] = g;
                }
            }
    }
    for (uint32_t v = 0; v < p->nverts; v++)
        hold[v] = (r->vflag[v] & V_FIXED) != 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        in[f] = ring[f] != UINT32_MAX;
        if (in[f] || geo_poly_facet_size(p, f) <= 3)
            continue;
        const uint32_t *fv = geo_poly_facet(p, f);
        for (uint32_t i = 0, n = geo_poly_facet_size(p, f); i < n; i++)
            hold[fv[i]] = 1;
    }
    return !limited;
}

/* The largest move from the start of a free vertex of the region's outer
 * ring, and of any free vertex. */
static void ln_reach(const run *r, const uint32_t *ring, uint32_t rings,
                     double *ret_outer, double *ret_all)
{
    const geo_poly *p = r->p0;
    double outer = 0, all = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        if (ring[f] == UINT32_MAX)
            continue;
        const uint32_t *fv = geo_poly_facet(p, f);
        for (uint32_t i = 0, n = geo_poly_facet_size(p, f); i < n; i++) {
            if (r->vflag[fv[i]] & V_FIXED)
                continue;
            double d = geo_vdist(r->x[fv[i]], rp_start_pos(r, fv[i]));
            if (d > all)
                all = d;
            if (ring[f] + 1 == rings && d > outer)
                outer = d;
        }
    }
    *ret_outer = outer;
    *ret_all = all;
}

/* Gauss–Newton steps of the least-norm problem until S2 < eps_final, on a
 * region around the fixed vertices that grows (rings ×2) until the move
 * has died out at its edge — below LN_EDGE of the largest move there —
 * or the region is everything. A region that stalls (its held edge bends
 * the facets across it) grows too. The rest of the model is held where
 * it is, so a local edit costs a local solve. A free vertex left within
 * eps_final / 100 of its start (rounding of a solve that reaches every
 * vertex of the region) is put back there, so the result differs from the
 * start only where the move reached. */
int rp_least_norm_run(run *r, const geo_replanar_opts *o,
                          const geo_ctx *ctx, geo_replanar_log *log,
                          uint32_t *ret_steps, bool *ret_converged,
                          int64_t *nsi, geo_replanar_result *ret,
                          geo_err *err)
{
    const geo_poly *p = r->p0;
    size_t nv = (size_t)p->nverts + 1, nf = (size_t)p->nfacets + 1;
    uint8_t *hold = malloc(nv), *in = malloc(nf);
    uint32_t *ring = malloc(nf * sizeof *ring),
             *queue = malloc(nf * sizeof *queue);
    if (!hold || !in || !ring || !queue) {
        free(hold);
        free(in);
        free(ring);
        free(queue);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    const uint8_t *fixflag = r->fit_all ? NULL : r->vflag;
    uint32_t budget = o->max_steps < LN_MAX_STEPS ? o->max_steps
                                                   : LN_MAX_STEPS;
    uint32_t stepno = 0, rings = LN_RINGS;
    bool converged = false;
    int rc = 0;
    for (;;) {
        bool whole = ln_region(r, rings, ring, queue, in, hold);
        /* every attempt starts from the start, the planes through the
         * fixed vertices first: the first linearisation is then about
         * planes the result can keep */
        for (uint32_t v = 0; v < p->nverts; v++)
            if (!(r->vflag[v] & V_FIXED))
                memcpy(r->x[v], rp_start_pos(r, v), sizeof r->x[v]);
        memcpy(r->pl, p->planes, (size_t)p->nfacets * sizeof *r->pl);
        for (uint32_t i = 0; i < r->naf; i++)
            rp_fit_plane(p, r->x, fixflag, r->af[i], r->pl[r->af[i]]);
        uint32_t worse = 0, first = stepno;
        double best = INFINITY;
        converged = false;
        while (stepno < budget && stepno - first < LN_ATTEMPT_STEPS) {
            rc = geo_ctx_progress(ctx, (double)stepno / budget);
            if (rc < 0) {
                geo_err_set(err, rc, "canceled");
                break;
            }
            memcpy(r->xn, r->x, (size_t)p->nverts * sizeof *r->x);
            rc = geo_least_norm_step(p, hold, in, (const double(*)[4])r->pl,
                                     r->x, stepno - first < LN_FROM_START,
                                     LN_MAX_NNZ, ctx);
            if (rc < 0) {
                if (rc == -ERANGE)
                    geo_err_set(err, rc, "least-norm: the region is too "
                                "large for one sparse factor (over %llu "
                                "entries); use the local-exp schedule",
                                (unsigned long long)LN_MAX_NNZ);
                else if (rc == -EDOM)
                    geo_err_set(err, rc, "least-norm: the planarity system "
                                "is singular (facets whose fixed vertices "
                                "are not coplanar?)");
                else
                    geo_err_set(err, rc, rc == -ECANCELED ? "canceled"
                                                          : "out of memory");
                break;
            }
            ln_account(r, (const double(*)[3])r->xn);
            if (o->count_selfint) {
                rc = rp_count_selfint(r, nsi);
                if (rc < 0) {
                    geo_err_set(err, rc, "out of memory");
                    break;
                }
                if (*nsi > 0 && ret->first_selfint_step < 0)
                    ret->first_selfint_step = stepno;
            }
            rc = rp_log_row(log, r, stepno, rings, stepno - first, o->eps_final,
                         0, o->count_selfint ? *nsi : -1);
            if (rc < 0) {
                geo_err_set(err, rc, "out of memory for the log");
                break;
            }
            stepno++;
            if (!isfinite(r->s2) || !isfinite(r->s1))
                break; /* diverged */
            if (r->s2 < o->eps_final) {
                converged = true;
                break;
            }
            /* Gauss–Newton that does not improve twice in a row is stuck */
            worse = r->s2 < best ? 0 : worse + 1;
            if (r->s2 < best)
                best = r->s2;
            if (worse == 2)
                break;
        }
        if (rc < 0 || whole || stepno >= budget)
            break;
        /* a region too tight for the move stalls (its held edge bends the
         * facets across it) or still moves at its edge: grow it */
        double outer, all;
        ln_reach(r, ring, rings, &outer, &all);
        if (converged && outer <= LN_EDGE * all)
            break;
        rings *= 2;
    }
    if (rc == 0 && converged) {
        double snap = o->eps_final / 100;
        memcpy(r->xn, r->x, (size_t)p->nverts * sizeof *r->x);
        for (uint32_t v = 0; v < p->nverts; v++)
            if (!(r->vflag[v] & V_FIXED) &&
                geo_vdist(r->x[v], rp_start_pos(r, v)) <= snap)
                memcpy(r->x[v], rp_start_pos(r, v), sizeof r->x[v]);
        /* the figures of the result as written (delta: the last step's) */
        double delta = r->delta;
        ln_account(r, (const double(*)[3])r->xn);
        r->delta = delta;
        converged = r->s2 < o->eps_final;
    }
    free(hold);
    free(in);
    free(ring);
    free(queue);
    *ret_steps = stepno;
    *ret_converged = converged;
    return rc;
}
