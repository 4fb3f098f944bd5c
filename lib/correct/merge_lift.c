/* merge_lift.c — lifting the contour points that lie below the merged
 * facet's plane (Palachev 2012, §2.6), so that the §3.4 cut can replace the
 * facet by its section.
 *
 * Notation of the paper (fig. 6): the main facet f has plane π (unit
 * normal n); its contour runs A_0 … A_{m−1} counter-clockwise seen from
 * outside; f_{−1} is the facet across the edge A_{i−1}A_i, f_{+1} across
 * A_iA_{i+1}, f_{−2} across A_{i−2}A_{i−1}, f_{+2} across A_{i+1}A_{i+2};
 * π_k is the plane of f_k. A_i moves along the line π_{−1} ∩ π_{+1} (it
 * stays in both facets). Its left neighbour A_{i−1} moves along
 * π_{−2} ∩ π_{−1}; the two paths meet at v_{−1} = π_{−2} ∩ π_{−1} ∩ π_{+1}.
 * If they meet below π the points join there; otherwise A_i goes to
 * π ∩ π_{−1} ∩ π_{+1} and A_{i−1} to v_{−2} = π ∩ π_{−2} ∩ π_{−1} (no join).
 * The right side is the mirror image. The lift d is the displacement's
 * component along n (the paper's (v − A_i, n)); the paper lifts the point
 * with the smallest d first (§2.6.2), to keep facets from crossing (§2.7).
 *
 * Departures from the paper's text, each marked where it is made:
 *  - the order (geo_lift_order): by default the event lowest along n goes
 *    first — a join at the height n·v of its meeting point, an arrival at
 *    the plane's height — instead of the smallest d; with the smallest d a
 *    point can pass the place where its neighbour's path meets the next
 *    neighbour's, and the facet between turns non-convex (statement 1
 *    fails; README counts the groups), while lowest-first processes that
 *    meeting before any move reaches it;
 *  - the main loop runs while any point is below π (the text says
 *    n_down > 1, which would leave one point below and make the cut fail);
 *  - "below" and "on" use the model's planarity tolerance: a point within
 *    geo_poly_eps of π lies on it (poly.h), so it is neither lifted nor
 *    duplicated by a vertex a rounding error away;
 *  - a meeting point behind A_i (n·(v − A_i) ≤ 0: the paths diverge as
 *    they rise) is not a join; the text would take a negative d;
 *  - in the no-join cases a neighbour on or above π stays where it is;
 *    the text moves it onto π along its edge, downwards when it is above,
 *    which runs past the edge's other end when that end is above π too
 *    and turns f_{∓2} non-convex (README gives the counts), while the cut
 *    finds the same section point without the move;
 *  - the right-hand branch of ПОДНЯТЬ_ВЕРШИНУ is the mirror image of the
 *    left one: the text tests СТЕПЕНЬ(A_{i−1}) where A_{i+1} is meant and
 *    writes "replace A_{i+1} in f by A_{i+1}" where v_{+1} is meant.
 * Three-plane intersections are solved for the offset from A_i and refined
 * once, so the new points lie on their planes to rounding even when the
 * planes meet at small angles. */
#include "merge_impl.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <string.h>

#include "predicates.h"
#include "vec.h"

/* Residuals r_k = −P_k(x) solved for δ with rows n_k (Cramer). */
static bool solve3(const double *p0, const double *p1, const double *p2,
                   const double x[3], double ret_delta[3])
{
    double c12[3], c20[3], c01[3];
    geo_vcross(p1, p2, c12);
    geo_vcross(p2, p0, c20);
    geo_vcross(p0, p1, c01);
    double det = geo_vdot(p0, c12);
    if (!(fabs(det) > 1e-12 * geo_vlen(p0) * geo_vlen(p1) * geo_vlen(p2)))
        return false;
    double r0 = -geo_plane_eval(p0, x), r1 = -geo_plane_eval(p1, x),
           r2 = -geo_plane_eval(p2, x);
    for (int k = 0; k < 3; k++)
        ret_delta[k] = (r0 * c12[k] + r1 * c20[k] + r2 * c01[k]) / det;
    return true;
}

/* The common point of three planes, found as an offset from ref and
 * refined once. false when the normals are (nearly) dependent. */
static bool meet3(const double *p0, const double *p1, const double *p2,
                  const double ref[3], double ret[3])
{
    double d[3], x[3];
    if (!solve3(p0, p1, p2, ref, d))
        return false;
    geo_vadd(ref, d, x);
    if (solve3(p0, p1, p2, x, d))
        geo_vadd(x, d, x);
    for (int k = 0; k < 3; k++)
        if (!isfinite(x[k]))
            return false;
    memcpy(ret, x, sizeof x);
    return true;
}

/* One side (left: s = −1, right: s = +1) of the move of A_i. */
typedef struct side_plan {
    bool ok, join;
    double d;        /* the lift, along n */
    double h;        /* height of the event point along n: n·v */
    double v[3];     /* where A_i goes, or the joined point */
    double v2[3];    /* no join: where the neighbour goes */
    bool nb_on;      /* no join: the neighbour lies on or above π and
                        stays where it is */
} side_plan;

typedef struct lift_plan {
    uint32_t i;                        /* position of A_i in the contour */
    uint32_t a, am, ap, amm, app;      /* A_i, A_{i∓1}, A_{i∓2} */
    uint32_t fm2, fm1, fp1, fp2;       /* f_{−2}, f_{−1}, f_{+1}, f_{+2} */
    bool left;
    side_plan s;
} lift_plan;

static void plan_side(const geo_mw *w, const lift_plan *lp, int s,
                      const double pi[4], side_plan *ret)
{
    const geo_edit *e = w->e;
    const double *A = e->verts[lp->a];
    /* outer facet f_{±2}, near facet f_{±1}, far facet f_{∓1}; the
     * neighbour A_{i±1} */
    uint32_t fo = s < 0 ? lp->fm2 : lp->fp2;
    uint32_t fn = s < 0 ? lp->fm1 : lp->fp1;
    uint32_t nb = s < 0 ? lp->am : lp->ap;
    const double *po = e->planes[fo], *pm1 = e->planes[lp->fm1],
                 *pp1 = e->planes[lp->fp1], *pn = e->planes[fn];
    memset(ret, 0, sizeof *ret);
    /* A_i's path meets the neighbour's path at π_{±2} ∩ π_{−1} ∩ π_{+1};
     * the paper's parallel case (π_{−2} ∥ π_{+1}, resp. π_{−1} ∥ π_{+2})
     * is the one where meet3 finds no point; the outer facet being f_{∓1}
     * itself (a contour of three) is the same case */
    double x[3];
    uint32_t ff = s < 0 ? lp->fp1 : lp->fm1;
    if (fo != ff && meet3(po, pm1, pp1, A, x) &&
        geo_plane_eval(pi, x) <= w->eps) {
        double up[3];
        geo_vsub(x, A, up);
        double d = geo_vdot(up, pi);
        /* departure: a meeting point behind A_i is no join */
        if (d > 0) {
            ret->ok = ret->join = true;
            ret->d = d;
            ret->h = geo_vdot(x, pi);
            memcpy(ret->v, x, sizeof x);
            return;
        }
    }
    double t[3];
    if (!meet3(pi, pm1, pp1, A, t))
        return;
    double up[3];
    geo_vsub(t, A, up);
    ret->d = geo_vdot(up, pi);
    ret->h = geo_vdot(t, pi);
    if (!(ret->d > 0))
        return;
    memcpy(ret->v, t, sizeof t);
    const double *N = e->verts[nb];
    /* departure: a neighbour on or above π stays */
    if (geo_plane_eval(pi, N) >= -w->eps) {
        ret->nb_on = true;
        memcpy(ret->v2, N, sizeof ret->v2);
    } else if (!meet3(pi, po, pn, N, ret->v2)) {
        return;
    }
    ret->ok = true;
}

/* Fills lp for the point at position i; false when it cannot be lifted
 * (no facet across an edge, repeated neighbours, no path up). */
static bool plan_point(const geo_mw *w, uint32_t main, uint32_t i,
                       const double pi[4], lift_plan *lp)
{
    const geo_edit *e = w->e;
    uint32_t m = geo_edit_fn(e, main);
    const uint32_t *vs = geo_edit_fv(e, main);
    if (m < 3)
        return false;
    lp->i = i;
    lp->a = vs[i];
    lp->am = vs[(i + m - 1) % m];
    lp->ap = vs[(i + 1) % m];
    lp->amm = vs[(i + m - 2) % m];
    lp->app = vs[(i + 2) % m];
    lp->fm1 = geo_edit_across(e, main, lp->am, lp->a);
    lp->fp1 = geo_edit_across(e, main, lp->a, lp->ap);
    lp->fm2 = geo_edit_across(e, main, lp->amm, lp->am);
    lp->fp2 = geo_edit_across(e, main, lp->ap, lp->app);
    if (lp->fm1 == GEO_NONE || lp->fp1 == GEO_NONE || lp->fm2 == GEO_NONE ||
        lp->fp2 == GEO_NONE || lp->fm1 == lp->fp1)
        return false;
    side_plan l, r;
    plan_side(w, lp, -1, pi, &l);
    plan_side(w, lp, +1, pi, &r);
    /* the paper's choice: the left neighbour determines the move when
     * (d−1 ≤ d+1 and d−1 > 0) or (d−1 > 0 and d+1 ≤ 0) */
    if (l.ok && (!r.ok || l.d <= r.d)) {
        lp->left = true;
        lp->s = l;
    } else if (r.ok) {
        lp->left = false;
        lp->s = r;
    } else {
        return false;
    }
    /* a join that would leave fewer than three contour points, or one
     * whose neighbour facets repeat, cannot be done */
    if (lp->s.join && m < 4)
        return false;
    uint32_t fo = lp->left ? lp->fm2 : lp->fp2;
    if (fo == lp->fm1 || fo == lp->fp1 || fo == main)
        return false;
    return true;
}

/* Position helpers: insert v into f right after / right before vertex x. */
static int ins_after(geo_edit *e, uint32_t f, uint32_t x, uint32_t v)
{
    uint32_t p = geo_edit_find(e, f, x);
    if (p == GEO_NONE)
        return -EINVAL;
    return geo_edit_insert(e, f, p + 1, v);
}

static int ins_before(geo_edit *e, uint32_t f, uint32_t x, uint32_t v)
{
    uint32_t p = geo_edit_find(e, f, x);
    if (p == GEO_NONE)
        return -EINVAL;
    return geo_edit_insert(e, f, p, v);
}

static int del(geo_edit *e, uint32_t f, uint32_t x)
{
    uint32_t p = geo_edit_find(e, f, x);
    if (p == GEO_NONE)
        return -EINVAL;
    return geo_edit_remove(e, f, p);
}

static int repl(geo_edit *e, uint32_t f, uint32_t x, uint32_t v)
{
    uint32_t p = geo_edit_find(e, f, x);
    if (p == GEO_NONE)
        return -EINVAL;
    return geo_edit_replace(e, f, p, v);
}

/* The vertex of triangle f other than a and b. */
static uint32_t third_vertex(const geo_edit *e, uint32_t f, uint32_t a,
                             uint32_t b)
{
    const uint32_t *vs = geo_edit_fv(e, f);
    for (uint32_t i = 0; i < 3; i++)
        if (vs[i] != a && vs[i] != b)
            return vs[i];
    return GEO_NONE;
}

static int64_t newv(geo_edit *e, const double xyz[3])
{
    return geo_edit_add_vertex(e, xyz);
}

/* ПОДНЯТЬ_ВЕРШИНУ (Palachev 2012, §2.6.3) for one side: lp->left, the
 * left branch (the neighbour N = A_{i−1} determines the move), or the
 * right branch, its mirror image (i−1 ↔ i+1, i−2 ↔ i+2, f_{−k} ↔ f_{+k},
 * after ↔ before; the paper's text of this branch has the typos named at
 * the top, this follows the symmetry). In the names below fN2 is f_{∓2}
 * (beyond N), fN1 f_{∓1} (between A_i and N), fO1 f_{±1} (the other side);
 * fwd inserts on N's side of a vertex, back on the other. The paper's
 * eight cases: join with A_i and N of degree > 3, only A_i, only N, or
 * neither (f_{∓1} a triangle squeezed out, or N taking A_i's place); no
 * join with both, only A_i, only N, or neither of degree > 3. Where the
 * two branches anchor an insertion at different ends of an edge, both are
 * kept as they were (the same polygon, its vertex list rotated).
 * Returns 0 or a negative errno; -EINVAL means an edit position was not
 * found (the neighbourhood is not what the plan saw). */
static int apply_side(geo_edit *e, uint32_t f, const lift_plan *lp,
                      uint32_t *ret_new)
{
    bool left = lp->left;
    uint32_t A = lp->a, N = left ? lp->am : lp->ap;
    uint32_t fN2 = left ? lp->fm2 : lp->fp2, fN1 = left ? lp->fm1 : lp->fp1,
             fO1 = left ? lp->fp1 : lp->fm1;
    int (*fwd)(geo_edit *, uint32_t, uint32_t, uint32_t) =
        left ? ins_after : ins_before;
    int (*back)(geo_edit *, uint32_t, uint32_t, uint32_t) =
        left ? ins_before : ins_after;
    assert(A != N && fN1 != fO1 && fN1 != f && fO1 != f);
    bool hiA = geo_edit_vn(e, A) > 3, hiN = geo_edit_vn(e, N) > 3;
    const side_plan *s = &lp->s;
    int r = 0;
    if (s->join) {
        if (hiA && hiN) {
            int64_t V = newv(e, s->v);
            if (V < 0)
                return (int)V;
            (*ret_new)++;
            uint32_t n = (uint32_t)V;
            if ((r = fwd(e, fN2, N, n)) || (r = fwd(e, fN1, A, n)) ||
                (r = back(e, fO1, A, n)) || (r = del(e, f, A)) ||
                (r = repl(e, f, N, n)))
                return r;
        } else if (hiA) {
            if ((r = geo_edit_move_vertex(e, N, s->v)) ||
                (r = back(e, fO1, A, N)) || (r = del(e, f, A)))
                return r;
        } else if (hiN) {
            if ((r = geo_edit_move_vertex(e, A, s->v)) ||
                (r = fwd(e, fN2, N, A)) || (r = del(e, f, N)))
                return r;
        } else if (geo_edit_fn(e, fN1) == 3) {
            /* departure: f_{∓1} is the triangle A_i N X, so the paths meet
             * at X itself and f_{∓1} is squeezed out whole: A_i and N
             * become X (the text would leave f_{∓1} with two vertices) */
            uint32_t X = third_vertex(e, fN1, A, N);
            if ((r = geo_edit_kill_facet(e, fN1)) || (r = del(e, fN2, N)) ||
                (r = del(e, fO1, A)) || (r = del(e, f, A)) ||
                (r = repl(e, f, N, X)))
                return r;
        } else {
            if ((r = geo_edit_move_vertex(e, N, s->v)) || (r = del(e, f, A)) ||
                (r = del(e, fN1, A)) || (r = repl(e, fO1, A, N)))
                return r;
        }
        return 0;
    }
    /* no join; a neighbour already on π counts as one of degree 3 that
     * does not move (departure, see the top) */
    if (s->nb_on)
        hiN = false;
    if (hiA && hiN) {
        /* v1 on π ∩ π_{−1} ∩ π_{+1} (A_i's), v2 on N's path */
        int64_t V1, V2;
        if (left) {
            V2 = newv(e, s->v2);
            V1 = V2 < 0 ? V2 : newv(e, s->v);
        } else {
            V1 = newv(e, s->v);
            V2 = V1 < 0 ? V1 : newv(e, s->v2);
        }
        if (V1 < 0 || V2 < 0)
            return (int)(V1 < 0 ? V1 : V2);
        *ret_new += 2;
        uint32_t v1 = (uint32_t)V1, v2 = (uint32_t)V2;
        /* f_{∓1} gets A_i v1 v2 N in its order; the left branch works from
         * N's side, the right from the other, as the paper writes them */
        if (left) {
            if ((r = fwd(e, fN2, N, v2)) || (r = ins_after(e, fN1, A, v1)) ||
                (r = ins_after(e, fN1, v1, v2)) || (r = back(e, fO1, A, v1)) ||
                (r = repl(e, f, N, v2)) || (r = repl(e, f, A, v1)))
                return r;
        } else {
            if ((r = back(e, fO1, A, v1)) || (r = ins_after(e, fN1, N, v2)) ||
                (r = ins_after(e, fN1, v2, v1)) || (r = fwd(e, fN2, N, v2)) ||
                (r = repl(e, f, A, v1)) || (r = repl(e, f, N, v2)))
                return r;
        }
    } else if (hiA) {
        int64_t V = newv(e, s->v);
        if (V < 0)
            return (int)V;
        (*ret_new)++;
        uint32_t v1 = (uint32_t)V;
        if ((!s->nb_on && (r = geo_edit_move_vertex(e, N, s->v2))) ||
            (r = fwd(e, fN1, A, v1)) || (r = back(e, fO1, A, v1)) ||
            (r = repl(e, f, A, v1)))
            return r;
    } else if (hiN) {
        int64_t V = newv(e, s->v2);
        if (V < 0)
            return (int)V;
        (*ret_new)++;
        uint32_t v2 = (uint32_t)V;
        /* v2 goes between A_i and N in f_{∓1} */
        if ((r = geo_edit_move_vertex(e, A, s->v)))
            return r;
        if (left ? (r = fwd(e, fN2, N, v2)) || (r = ins_after(e, fN1, A, v2))
                 : (r = ins_after(e, fN1, N, v2)) || (r = fwd(e, fN2, N, v2)))
            return r;
        if ((r = repl(e, f, N, v2)))
            return r;
    } else {
        if ((!s->nb_on && (r = geo_edit_move_vertex(e, N, s->v2))) ||
            (r = geo_edit_move_vertex(e, A, s->v)))
            return r;
    }
    return 0;
}

/* Exact convexity of facet f's polygon in its dominant projection: every
 * corner turns with the plane's normal or is flat, not all flat. */
static bool facet_convex(const geo_edit *e, uint32_t f)
{
    const double *n = e->planes[f];
    int drop = 0;
    for (int k = 1; k < 3; k++)
        if (fabs(n[k]) > fabs(n[drop]))
            drop = k;
    int want = n[drop] > 0 ? 1 : -1, turns = 0;
    uint32_t m = geo_edit_fn(e, f);
    const uint32_t *vs = geo_edit_fv(e, f);
    for (uint32_t i = 0; i < m; i++) {
        int o = geo_orient2d_proj(e->verts[vs[(i + m - 1) % m]],
                                  e->verts[vs[i]], e->verts[vs[(i + 1) % m]],
                                  drop) * want;
        if (o < 0)
            return false;
        turns += o > 0;
    }
    return turns > 0;
}

/* Largest |plane(v)| over facet f's vertices. */
static double facet_dev(const geo_edit *e, uint32_t f)
{
    double worst = 0;
    const uint32_t *vs = geo_edit_fv(e, f);
    for (uint32_t i = 0; i < geo_edit_fn(e, f); i++)
        worst = fmax(worst, fabs(geo_plane_eval(e->planes[f], e->verts[vs[i]])));
    return worst;
}

/* Which planned move goes first: the paper's smallest lift d, or the
 * event lowest along n (see merge.h, geo_lift_order). */
static bool earlier(enum geo_lift_order o, const side_plan *a,
                    const side_plan *b)
{
    if (o == GEO_LIFT_EVENT_HEIGHT && a->h != b->h)
        return a->h < b->h;
    return a->d < b->d;
}

int geo_mw_lift(geo_mw *w, uint32_t main, const double plane[4],
                geo_merge_group *rep, geo_err *err)
{
    geo_edit *e = w->e;
    uint32_t m0 = geo_edit_fn(e, main);
    /* each step puts a point on π or removes one: 2·m steps suffice */
    uint32_t guard = 4 * m0 + 16;
    for (uint32_t step = 0;; step++) {
        uint32_t m = geo_edit_fn(e, main);
        const uint32_t *vs = geo_edit_fv(e, main);
        uint32_t below = 0;
        lift_plan best, lp;
        bool have = false;
        for (uint32_t i = 0; i < m; i++) {
            /* departure: while any point is below (text: n_down > 1) */
            if (geo_plane_eval(plane, e->verts[vs[i]]) >= -w->eps)
                continue;
            below++;
            if (plan_point(w, main, i, plane, &lp) &&
                (!have || earlier(w->lift_order, &lp.s, &best.s))) {
                best = lp;
                have = true;
            }
            vs = geo_edit_fv(e, main);
        }
        if (below == 0)
            break;
        if (!have) {
            /* §2.7 statement 2: some point can always be lifted */
            w->statement_violations++;
            return geo_err_set(err, -EINVAL,
                               "no contour point below the plane can be lifted "
                               "(%u below; statement 2 of §2.7 fails here)",
                               below);
        }
        if (step >= guard)
            return geo_err_set(err, -EINVAL, "lifting does not end after %u "
                               "steps", step);
        uint32_t touched[4] = {best.fm2, best.fm1, best.fp1, best.fp2};
        bool convex[4];
        for (int k = 0; k < 4; k++)
            convex[k] = facet_convex(e, touched[k]);
        uint32_t made = 0;
        int r = apply_side(e, main, &best, &made);
        if (r == -ENOMEM)
            return geo_err_set(err, r, "out of memory");
        if (r < 0)
            return geo_err_set(err, r, "vertices[%u]: the neighbourhood of "
                               "the lifted point is not as expected", best.a);
        rep->lifts++;
        rep->joins += best.s.join;
        rep->new_vertices += made;
        /* §2.7 statement 1: no facet loses planarity and a convex facet
         * stays convex */
        for (int k = 0; k < 4; k++) {
            uint32_t f = touched[k];
            if (!e->falive[f])
                continue;
            double dev = facet_dev(e, f);
            bool cv = !convex[k] || facet_convex(e, f);
            if (dev > w->eps || !cv || geo_edit_fn(e, f) < 3) {
                w->statement_violations++;
                return geo_err_set(err, -EINVAL,
                                   "facets[%u]: %s after lifting vertex %u "
                                   "(statement 1 of §2.7 fails here)", f,
                                   geo_edit_fn(e, f) < 3 ? "degenerates"
                                   : dev > w->eps ? "is no longer planar"
                                                  : "is no longer convex",
                                   best.a);
            }
        }
    }
    /* §2.7 statement 3: every contour point on or above π, and the contour
     * not empty */
    uint32_t m = geo_edit_fn(e, main);
    if (m < 3) {
        w->statement_violations++;
        return geo_err_set(err, -EINVAL, "the contour lost all but %u points "
                           "(statement 3 of §2.7 fails here)", m);
    }
    return 0;
}
