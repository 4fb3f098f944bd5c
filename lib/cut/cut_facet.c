/* cut_facet.c — the per-facet stages of the plane cut (Palachev 2012, §3), the
 * one implementation behind geo_cut (lib/cut/cut.c) and the merge's local
 * §3.4 cut (lib/correct/merge_cut.c).
 *
 * For one facet crossing the plane π:
 *  1. the boundary nodes: its vertices and, after each crossed edge, the
 *     caller's vertex for that crossing, with the kept/removed type of the
 *     boundary between nodes (an edge lying in π borders the kept side
 *     when it runs against e, the facet's inside then being below l);
 *  2. the events on l = facet ∩ π, kept sorted along e by binary-search
 *     insertion with the exact comparison geo_plane_crossing_cmp: ENTRY
 *     (the facet's inside begins along l), EXIT (it ends), PASS (a reflex
 *     on-plane vertex inside a segment of l); a convex on-plane vertex
 *     touching l from one side is the paper's "hanging" vertex and is not
 *     listed; a reflex one touching from the kept side is an EXIT and an
 *     ENTRY at once (DOUBLE); convexity is an exact 2D orientation
 *     (geo_orient2d_proj);
 *  3. the paper's direction sweep, which checks the pattern and pairs
 *     each EXIT with the ENTRY opening its segment;
 *  4. the kept pieces by the paper's two cycles: along the boundary while
 *     it stays on the kept side (cycle B), then along l from an EXIT back
 *     to its ENTRY (cycle A); each segment of l walked by cycle A is,
 *     reversed, an edge of the section.
 *
 * Invariants: the sides are the caller's and are never recomputed here;
 * a crossed edge's point is the caller's vertex, so the pieces of the two
 * facets of an edge and the section use the same ids along it; a pattern
 * along l that no simple planar facet has is refused, never repaired. */
#include "cut_facet.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "predicates.h"
#include "vec.h"

enum ev_type { EV_ENTRY, EV_EXIT, EV_DOUBLE, EV_PASS };
enum seg_type { SEG_KEPT, SEG_REMOVED };

int geo_cutf_dominant_axis(const double v[3])
{
    int k = 0;
    for (int j = 1; j < 3; j++)
        if (fabs(v[j]) > fabs(v[k]))
            k = j;
    return k;
}

#define U_ROUND 0x1.0p-53

/* Σ|plane[k]·x[k]| + |plane[3]|: the scale of plane(x)'s rounding. */
static double plane_mag(const double plane[4], const double x[3])
{
    return fabs(plane[0] * x[0]) + fabs(plane[1] * x[1]) +
           fabs(plane[2] * x[2]) + fabs(plane[3]);
}

/* The bound: the plane values carry the normalisation's rounding and
 * their own (≤ 8u·magnitude each), which moves the parameter by at most
 * twice their sum over |f0 − f1| less that sum, plus the rounding of the
 * interpolation; the whole edge when that sum is not smaller. */
double geo_cutf_crossing_point(const double plane[4], const double a[3],
                               const double b[3], double ret[3])
{
    double fa = geo_plane_eval(plane, a), fb = geo_plane_eval(plane, b);
    const double *p0 = a, *p1 = b;
    double f0 = fa, f1 = fb;
    if (fabs(fb) < fabs(fa) || (fabs(fb) == fabs(fa) && memcmp(b, a, 24) < 0)) {
        p0 = b, p1 = a, f0 = fb, f1 = fa;
    }
    double t = f0 / (f0 - f1);
    if (!(t >= 0.0))
        t = 0.0;
    if (t > 0.5)
        t = 0.5;
    for (int j = 0; j < 3; j++) {
        double x = p0[j] + t * (p1[j] - p0[j]);
        double lo = fmin(a[j], b[j]), hi = fmax(a[j], b[j]);
        ret[j] = fmin(fmax(x, lo), hi);
    }
    double e = 8 * U_ROUND * (plane_mag(plane, p0) + plane_mag(plane, p1));
    double den = fabs(f0 - f1) - e;
    double dt = den > 0 ? 2 * e / den + 4 * U_ROUND : 1.0;
    double err = 0;
    for (int j = 0; j < 3; j++) {
        double ej = dt * fabs(p1[j] - p0[j]) +
                    4 * U_ROUND * (fabs(p0[j]) + fabs(p1[j]));
        err = fmax(err, ej);
    }
    return err * (1 + 16 * U_ROUND);
}

int geo_cutf_push_section(geo_cutf *k, uint32_t a, uint32_t b)
{
    if (geo_grow((void **)&k->sec, &k->capsec, k->nsec + 1, sizeof *k->sec) < 0)
        return -ENOMEM;
    k->sec[k->nsec][0] = a;
    k->sec[k->nsec][1] = b;
    k->nsec++;
    return 0;
}

static int refuse(geo_cutf *k, const char *why)
{
    k->why = why;
    return -EINVAL;
}

int geo_cutf_frame(geo_cutf *k, const double area[3])
{
    double e[3];
    geo_vcross(k->frame, area, e);
    if (!(geo_vlen(e) > 0.0))
        return refuse(k, "crosses the plane but is parallel to it");
    k->axis = geo_cutf_dominant_axis(e);
    k->esign = e[k->axis] > 0 ? 1 : -1;
    k->drop = geo_cutf_dominant_axis(area);
    k->osign = area[k->drop] > 0 ? 1 : -1;
    return 0;
}

/* Order of two points of l along e: −1, 0, +1. */
static int along(const geo_cutf *k, const double *a0, const double *a1,
                 const double *b0, const double *b1)
{
    return k->esign * geo_plane_crossing_cmp(k->plane, a0, a1, b0, b1, k->axis);
}

static int insert_event(geo_cutf *k, size_t *nev, const geo_cutf_event *e)
{
    if (geo_grow((void **)&k->ev, &k->capev, *nev + 1, sizeof *k->ev) < 0)
        return -ENOMEM;
    /* binary search for the first event after e along l (ties keep the
     * boundary order; a tie means the facet touches itself, which the
     * pattern check then reports) */
    size_t lo = 0, hi = *nev;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        const geo_cutf_event *m = &k->ev[mid];
        if (along(k, m->p0, m->p1, e->p0, e->p1) <= 0)
            lo = mid + 1;
        else
            hi = mid;
    }
    memmove(k->ev + lo + 1, k->ev + lo, (*nev - lo) * sizeof *k->ev);
    k->ev[lo] = *e;
    (*nev)++;
    return 0;
}

static int piece_push(geo_cutf *k, size_t *np, uint32_t v)
{
    if (geo_grow((void **)&k->piece, &k->cappiece, *np + 1, sizeof *k->piece) < 0)
        return -ENOMEM;
    k->piece[(*np)++] = v;
    return 0;
}

int geo_cutf_facet(geo_cutf *k, const double (*verts)[3], const uint32_t *vs,
                   const int8_t *side, const uint32_t *xv, uint32_t n)
{
    k->ninplane = 0;

    /* boundary nodes with the kept/removed type of the segments between */
    if (geo_grow((void **)&k->nodes, &k->capnodes, 2 * (size_t)n,
                      sizeof *k->nodes) < 0)
        return -ENOMEM;
    uint32_t nn = 0;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t j = i + 1 < n ? i + 1 : 0;
        int si = side[i], sj = side[j];
        geo_cutf_node *v = &k->nodes[nn++];
        v->i = i;
        v->vout = vs[i];
        v->crossing = 0;
        v->ev = -1;
        if (si * sj < 0) {
            v->out = si < 0 ? SEG_KEPT : SEG_REMOVED;
            geo_cutf_node *x = &k->nodes[nn++];
            x->i = i;
            x->vout = xv[i];
            x->crossing = 1;
            x->ev = -1;
            x->in = v->out;
            x->out = sj < 0 ? SEG_KEPT : SEG_REMOVED;
        } else if (si < 0 || sj < 0) {
            v->out = SEG_KEPT;
        } else if (si > 0 || sj > 0) {
            v->out = SEG_REMOVED;
        } else {
            int d = along(k, verts[vs[j]], NULL, verts[vs[i]], NULL);
            if (d == 0)
                return refuse(k, "an edge in the plane has zero length");
            v->out = d < 0 ? SEG_KEPT : SEG_REMOVED;
        }
    }
    for (uint32_t a = 0; a < nn; a++) {
        geo_cutf_node *v = &k->nodes[a];
        if (!v->crossing)
            v->in = k->nodes[a ? a - 1 : nn - 1].out;
    }

    /* events, sorted along l */
    size_t nev = 0;
    for (uint32_t a = 0; a < nn; a++) {
        geo_cutf_node *v = &k->nodes[a];
        geo_cutf_event ev = {0, a, NULL, NULL, -1};
        if (v->crossing) {
            uint32_t j = v->i + 1 < n ? v->i + 1 : 0;
            ev.p0 = verts[vs[v->i]];
            ev.p1 = verts[vs[j]];
        } else {
            if (side[v->i] != 0)
                continue;
            ev.p0 = verts[vs[v->i]];
        }
        if (v->in == SEG_REMOVED && v->out == SEG_KEPT) {
            ev.type = EV_ENTRY;
        } else if (v->in == SEG_KEPT && v->out == SEG_REMOVED) {
            ev.type = EV_EXIT;
        } else {
            /* a single on-plane vertex between two vertices of one side:
             * convex, it only touches l (hanging); reflex, l runs through
             * the facet on both of its sides */
            uint32_t ip = v->i ? v->i - 1 : n - 1, in = v->i + 1 < n ? v->i + 1 : 0;
            int sp = side[ip], sn = side[in];
            if (sp == 0 || sn == 0 || sp != sn)
                continue;
            int turn = k->osign * geo_orient2d_proj(verts[vs[ip]], verts[vs[v->i]],
                                                    verts[vs[in]], k->drop);
            if (turn >= 0)
                continue;
            ev.type = sp < 0 ? EV_DOUBLE : EV_PASS;
        }
        int r = insert_event(k, &nev, &ev);
        if (r < 0)
            return r;
    }

    /* the paper's direction sweep: outside, ENTRY opens a segment of l
     * inside the facet, PASS lies inside one, EXIT closes it, DOUBLE
     * closes one and opens the next */
    int32_t open = -1;
    for (size_t s = 0; s < nev; s++) {
        geo_cutf_event *ev = &k->ev[s];
        k->nodes[ev->node].ev = (int32_t)s;
        switch (ev->type) {
        case EV_ENTRY:
            if (open >= 0)
                return refuse(k, "two entries in a row along the section");
            open = (int32_t)s;
            break;
        case EV_PASS:
            if (open < 0)
                return refuse(k, "a reflex vertex outside the section");
            break;
        case EV_EXIT:
        case EV_DOUBLE:
            if (open < 0)
                return refuse(k, "an exit before any entry along the section");
            ev->partner = open;
            open = ev->type == EV_DOUBLE ? (int32_t)s : -1;
            break;
        }
    }
    if (open >= 0 || nev == 0)
        return refuse(k, "the section does not close");

    /* cycles B (boundary, kept side) and A (along l back to the entry) */
    if (geo_grow((void **)&k->used, &k->capused, nev, 1) < 0 ||
        geo_grow((void **)&k->pstart, &k->cappstart, 1, sizeof *k->pstart) < 0)
        return -ENOMEM;
    memset(k->used, 0, nev);
    k->pstart[0] = 0;
    size_t np = 0;
    uint32_t pieces = 0;
    size_t guard = 0, limit = 4 * ((size_t)nn + nev) + 16;
    for (size_t s0 = 0; s0 < nev; s0++) {
        const geo_cutf_event *start = &k->ev[s0];
        if ((start->type != EV_ENTRY && start->type != EV_DOUBLE) || k->used[s0])
            continue;
        size_t p0 = np;
        uint32_t cur = start->node;
        for (;;) {
            k->used[k->nodes[cur].ev] = 1;
            /* cycle B */
            uint32_t a = cur;
            for (;;) {
                if (++guard > limit)
                    return refuse(k, "the pieces do not close");
                if (piece_push(k, &np, k->nodes[a].vout) < 0)
                    return -ENOMEM;
                if (a != cur && k->nodes[a].ev >= 0) {
                    uint8_t ty = k->ev[k->nodes[a].ev].type;
                    if (ty == EV_EXIT || ty == EV_DOUBLE)
                        break;
                }
                const geo_cutf_node *na = &k->nodes[a];
                if (!na->crossing && na->out == SEG_KEPT && side[na->i] == 0 &&
                    side[na->i + 1 < n ? na->i + 1 : 0] == 0) {
                    if (geo_grow((void **)&k->inplane, &k->capinplane,
                                      k->ninplane + 1, sizeof *k->inplane) < 0)
                        return -ENOMEM;
                    k->inplane[k->ninplane++] = na->i;
                }
                a = a + 1 < nn ? a + 1 : 0;
                if (k->nodes[a].in != SEG_KEPT)
                    return refuse(k, "the kept boundary is interrupted");
            }
            /* cycle A: from the exit against e to its entry; the section
             * gets the same segment along e */
            int32_t x = k->nodes[a].ev, en = k->ev[x].partner;
            for (int32_t s = x; s > en; s--) {
                uint32_t hi = k->nodes[k->ev[s].node].vout;
                uint32_t lo = k->nodes[k->ev[s - 1].node].vout;
                if (geo_cutf_push_section(k, lo, hi) < 0)
                    return -ENOMEM;
                if (s - 1 > en && piece_push(k, &np, lo) < 0)
                    return -ENOMEM;
            }
            cur = k->ev[en].node;
            if (cur == start->node)
                break;
            if (k->used[en])
                return refuse(k, "an entry is reached twice");
        }
        if (np - p0 < 3)
            return refuse(k, "a piece with fewer than 3 vertices");
        pieces++;
        if (geo_grow((void **)&k->pstart, &k->cappstart, pieces + 1,
                          sizeof *k->pstart) < 0)
            return -ENOMEM;
        k->pstart[pieces] = (uint32_t)np;
    }
    for (size_t s = 0; s < nev; s++)
        if (!k->used[s] && (k->ev[s].type == EV_ENTRY || k->ev[s].type == EV_DOUBLE))
            return refuse(k, "an entry is not on any piece");
    return (int)pieces;
}

void geo_cutf_free(geo_cutf *k)
{
    free(k->sec), free(k->piece), free(k->pstart), free(k->inplane);
    free(k->nodes), free(k->ev), free(k->used);
}
