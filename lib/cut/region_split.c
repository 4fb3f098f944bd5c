/* region_split.c — splitting a planar region with holes into simple
 * polygons along diagonals (see region_split.h for the input model).
 *
 * Method, and why. A part that needs splitting (it has holes or visits a
 * point twice) is triangulated without new points and the triangles are
 * merged back into few simple pieces:
 *  1. each hole is joined to the part's ring by one bridge, in Eberly's
 *     order (holes by their greatest point, decreasing; the bridge leaves
 *     that point M towards +x), so a ring vertex visible from M always
 *     exists; candidates are tried nearest first and each is checked
 *     exactly (it leaves both corners inside their wedges and meets no
 *     edge of the ring or of a remaining hole), so the heuristic order
 *     never decides validity. The ring is then one weakly simple polygon
 *     (every bridge walked once each way);
 *  2. the ring is ear clipped. An ear must be a strictly convex corner
 *     whose closed triangle holds no other point; a second occurrence of
 *     one of the ear's own points (a bridge end, a touching point) is
 *     allowed when neither of its edges enters the triangle. Only
 *     non-convex corners and repeated points can spoil an ear of a weakly
 *     simple polygon (the point of the triangle farthest from the
 *     diagonal would otherwise be reflex), so only those are tested,
 *     found through a grid over the part;
 *  3. triangles are merged across diagonals and bridges: first by growing
 *     a piece from a triangle across its edges while the triangle added
 *     brings a point the piece does not have yet, then by joining two
 *     pieces across an edge when they share no other point. Both keep a
 *     piece a simple polygon by construction (a union of two simple
 *     polygons of a triangulation meeting in exactly one edge is simple),
 *     and both refuse to close a piece around a hole or a touching point,
 *     so the bridges come out as ordinary edges between two pieces.
 * Why not two bridges per hole directly: choosing the second bridges so
 * that every face becomes simple (several holes, holes touching the
 * outer loop or each other) needs the same case analysis the merge rule
 * settles by one local test; and why not convex pieces: a smooth hole of
 * n points would need about n pieces, while a simple-polygon merge gives
 * two for an annulus.
 *
 * Certainty: with per-point bounds (perr), every sign that makes geometry
 * comes from turn(), which answers only when the sign holds for every
 * position within the bounds and is UNSURE otherwise; ears, bridges and
 * wedges are accepted only on sure answers, a point leaves a triangle
 * only surely. A part for which this finds no bridge or ear is done again
 * on the positions alone (exact geo_orient2d), so the bounds never make a
 * split fail that the positions allow.
 *
 * Invariants: a ring occurrence's out-edge carries its slot (the
 * diagonal or bridge it is, or NONE for an edge of the input loops); each
 * slot ends with exactly two triangles, one on each side; points are
 * identified by index (distinct indices have distinct positions, checked
 * up front). */
#include "region_split.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "grow.h"
#include "predicates.h"
#include "uf.h"

#define NONE UINT32_MAX

typedef const double (*pts_t)[2];

static bool lex_less(const double *a, const double *b)
{
    return a[0] < b[0] || (a[0] == b[0] && a[1] < b[1]);
}

/* +1 inside, −1 outside, 0 on the loop. */
static int point_in_loop(pts_t P, const uint32_t *lp, uint32_t n,
                         const double *q)
{
    bool in = false;
    for (uint32_t j = 0; j < n; j++) {
        const double *a = P[lp[j]], *b = P[lp[j + 1 < n ? j + 1 : 0]];
        if (a[0] == q[0] && a[1] == q[1])
            return 0;
        bool ua = a[1] > q[1], ub = b[1] > q[1];
        if (ua != ub) {
            int o = geo_orient2d(a, b, q);
            if (o == 0)
                return 0;
            /* the crossing with the ray q → +x lies right of q */
            if ((o > 0) == ub)
                in = !in;
        } else if (a[1] == q[1] && b[1] == q[1] &&
                   (a[0] <= q[0]) != (b[0] < q[0])) {
            return 0;
        }
    }
    return in ? 1 : -1;
}

static double loop_area(pts_t P, const uint32_t *lp, uint32_t n)
{
    const double *o = P[lp[0]];
    double s = 0;
    for (uint32_t j = 1; j + 1 < n; j++) {
        const double *a = P[lp[j]], *b = P[lp[j + 1]];
        s += (a[0] - o[0]) * (b[1] - o[1]) - (b[0] - o[0]) * (a[1] - o[1]);
    }
    return 0.5 * s;
}

/* Orientation of a loop: exact at its lowest point when the loop passes
 * there once (a convex corner), else the sign of its area. */
static int loop_sign(pts_t P, const uint32_t *lp, uint32_t n, double area)
{
    uint32_t lo = 0, count = 1;
    for (uint32_t j = 1; j < n; j++) {
        if (lex_less(P[lp[j]], P[lp[lo]])) {
            lo = j;
            count = 1;
        } else if (lp[j] == lp[lo]) {
            count++;
        }
    }
    if (count == 1) {
        int s = geo_orient2d(P[lp[lo ? lo - 1 : n - 1]], P[lp[lo]],
                             P[lp[lo + 1 < n ? lo + 1 : 0]]);
        if (s)
            return s;
    }
    return area > 0 ? 1 : area < 0 ? -1 : 0;
}

/* ---- the splitter ------------------------------------------------------ */

typedef struct loopinfo {
    int sign;
    bool repeats;
    double area; /* absolute */
    double lo[2], hi[2];
    uint32_t owner; /* hole: its part's loop; part: its part number */
} loopinfo;

typedef struct splitter {
    pts_t P;
    const double *perr;     /* per point position bound, or NULL */
    bool sure;              /* decide for every position within perr */
    uint32_t npts;
    const uint32_t *ls, *li;
    uint32_t nloops;
    geo_err *err;
    geo_region_pieces *out;
    size_t capidx, capstart, cappart;
    uint32_t *stamp, epoch; /* per point marks */
    uint32_t *nxt;          /* per point: next point on a piece's boundary */
    uint32_t *cnt;          /* per point: occurrences in the ring */
    uint32_t *occ_at;       /* per point: an occurrence of it in the ring */
    double maxerr;          /* largest perr (0 without bounds) */
    loopinfo *info;
} splitter;

/* ---- signs ---------------------------------------------------------------
 *
 * turn(a, b, c) is the orientation of three points by index. In sure mode
 * it holds for every position of each point within its bound perr (so for
 * the exact crossing points behind the computed ones as much as for the
 * computed ones): +1, −1, or UNSURE when the bounds allow both signs or
 * zero. A repeated index gives 0 (exactly collinear). Without bounds, or
 * when all three are exact, it is geo_orient2d. Each use below reads
 * UNSURE the cautious way: an ear, a bridge or a wedge is accepted only
 * when every position allows it, a point is out of a triangle only when
 * every position puts it out. */

enum { UNSURE = 2 };

#define U_ROUND 0x1.0p-53

static int turn(const splitter *s, uint32_t ia, uint32_t ib, uint32_t ic)
{
    if (ia == ib || ib == ic || ia == ic)
        return 0;
    const double *a = s->P[ia], *b = s->P[ib], *c = s->P[ic];
    double ea = 0, eb = 0, ec = 0;
    if (s->sure && s->perr)
        ea = s->perr[ia], eb = s->perr[ib], ec = s->perr[ic];
    if (ea == 0 && eb == 0 && ec == 0)
        return geo_orient2d(a, b, c);
    double bx = b[0] - a[0], by = b[1] - a[1];
    double cx = c[0] - a[0], cy = c[1] - a[1];
    double l = bx * cy, r = by * cx, det = l - r;
    /* the rounding of det, and how far moving each point within its
     * bound (in both coordinates) can move the exact determinant */
    double bound = 8 * U_ROUND * (fabs(l) + fabs(r)) +
                   ea * (fabs(c[0] - b[0]) + fabs(c[1] - b[1])) +
                   eb * (fabs(cx) + fabs(cy)) + ec * (fabs(bx) + fabs(by)) +
                   2 * (ea * eb + eb * ec + ec * ea);
    bound *= 1 + 16 * U_ROUND;
    if (det > bound)
        return 1;
    if (det < -bound)
        return -1;
    return UNSURE;
}

/* r possibly strictly inside the angle at v turning counter-clockwise
 * from v→from to v→to (below π). */
static bool maybe_in_angle(const splitter *s, uint32_t v, uint32_t from,
                           uint32_t to, uint32_t r)
{
    int t1 = turn(s, v, from, r), t2 = turn(s, v, to, r);
    return (t1 == 1 || t1 == UNSURE) && (t2 == -1 || t2 == UNSURE);
}

/* q surely strictly inside the region's wedge at corner v of a boundary
 * running a → v → c (region on the left): counter-clockwise from v→c to
 * v→a. */
static bool in_wedge(const splitter *s, uint32_t a, uint32_t v, uint32_t c,
                     uint32_t q)
{
    int left_out = turn(s, v, c, q), left_in = turn(s, a, v, q);
    int corner = turn(s, a, v, c);
    if (corner == 1 || corner == UNSURE)
        return left_out == 1 && left_in == 1;
    return left_out == 1 || left_in == 1;
}

/* x, exactly collinear with segment mp, strictly between m and p. */
static bool strictly_between(const double *m, const double *p,
                             const double *x)
{
    int k = m[0] != p[0] ? 0 : 1;
    double lo = m[k] < p[k] ? m[k] : p[k], hi = m[k] < p[k] ? p[k] : m[k];
    return lo < x[k] && x[k] < hi;
}

/* Whether the closed segment xy may meet segment mp other than at one
 * common end point, or run along it (true when unsure). */
static bool blocks(const splitter *s, uint32_t m, uint32_t p, uint32_t x,
                   uint32_t y)
{
    const double *M = s->P[m], *Pp = s->P[p], *X = s->P[x], *Y = s->P[y];
    int o1 = turn(s, m, p, x), o2 = turn(s, m, p, y);
    if (o1 == UNSURE || o2 == UNSURE) {
        if (o1 != UNSURE && o1 != 0 && o1 == o2)
            return false;
        int o3 = turn(s, x, y, m), o4 = turn(s, x, y, p);
        return !(o3 != UNSURE && o3 != 0 && o3 == o4);
    }
    if (o1 == 0 && o2 == 0) {
        int k = M[0] != Pp[0] ? 0 : 1;
        double lo1 = M[k] < Pp[k] ? M[k] : Pp[k], hi1 = M[k] < Pp[k] ? Pp[k] : M[k];
        double lo2 = X[k] < Y[k] ? X[k] : Y[k], hi2 = X[k] < Y[k] ? Y[k] : X[k];
        /* meeting in one point, that point is an end of both */
        return !(hi2 <= lo1 || hi1 <= lo2);
    }
    if (o1 == 0)
        return x == m || x == p ? false : strictly_between(M, Pp, X);
    if (o2 == 0)
        return y == m || y == p ? false : strictly_between(M, Pp, Y);
    if (o1 == o2)
        return false;
    int o3 = turn(s, x, y, m), o4 = turn(s, x, y, p);
    /* o3 == 0: xy crosses the line mp at m itself, so m is on xy */
    return o3 == 0 || o4 == 0 || o3 != o4;
}

static uint32_t new_epoch(splitter *s)
{
    if (++s->epoch == 0) {
        memset(s->stamp, 0, (size_t)s->npts * sizeof *s->stamp);
        s->epoch = 1;
    }
    return s->epoch;
}

static int emit(splitter *s, const uint32_t *v, uint32_t n, uint32_t part)
{
    geo_region_pieces *o = s->out;
    size_t at = o->npieces ? o->start[o->npieces] : 0;
    if (geo_grow((void **)&o->idx, &s->capidx, at + n, sizeof *o->idx) < 0 ||
        geo_grow((void **)&o->part, &s->cappart, (size_t)o->npieces + 1,
             sizeof *o->part) < 0 ||
        geo_grow((void **)&o->start, &s->capstart, (size_t)o->npieces + 2,
             sizeof *o->start) < 0)
        return geo_err_set(s->err, -ENOMEM, "out of memory");
    memcpy(o->idx + at, v, (size_t)n * sizeof *v);
    o->start[o->npieces] = (uint32_t)at;
    o->part[o->npieces] = part;
    o->npieces++;
    o->start[o->npieces] = (uint32_t)(at + n);
    return 0;
}

/* ---- one part: ring, bridges, ears, merge ------------------------------- */

typedef struct ring {
    uint32_t n;                       /* occurrences */
    uint32_t *pt, *next, *prev, *eslot;
    int8_t *kind;                     /* turn at the occurrence */
    uint8_t *dup, *dead;
    uint32_t ntri, nslot;
    uint32_t (*tri)[3], (*tslot)[3];  /* slot of edge e: tri[e] → tri[e+1] */
    uint32_t (*slot)[2];
    uint8_t *slotn;
    bool overfull;
} ring;

static void ring_free(ring *r)
{
    free(r->pt), free(r->next), free(r->prev), free(r->eslot), free(r->kind);
    free(r->dup), free(r->dead), free(r->tri), free(r->tslot), free(r->slot);
    free(r->slotn);
}

static int ring_alloc(ring *r, uint32_t n)
{
    memset(r, 0, sizeof *r);
    size_t m = (size_t)n + 1;
    r->pt = malloc(m * sizeof *r->pt);
    r->next = malloc(m * sizeof *r->next);
    r->prev = malloc(m * sizeof *r->prev);
    r->eslot = malloc(m * sizeof *r->eslot);
    r->kind = malloc(m);
    r->dup = calloc(m, 1);
    r->dead = calloc(m, 1);
    r->tri = malloc(m * sizeof *r->tri);
    r->tslot = malloc(m * sizeof *r->tslot);
    r->slot = malloc(2 * m * sizeof *r->slot);
    r->slotn = calloc(2 * m, 1);
    if (!r->pt || !r->next || !r->prev || !r->eslot || !r->kind || !r->dup ||
        !r->dead || !r->tri || !r->tslot || !r->slot || !r->slotn)
        return -ENOMEM;
    return 0;
}

/* Records occurrence o of point q (the ring's per-point counts). */
static void note_occ(splitter *s, uint32_t o, uint32_t q)
{
    s->cnt[q]++;
    s->occ_at[q] = o;
}

static uint32_t new_slot(ring *r)
{
    return r->nslot++;
}

static void slot_add(ring *r, uint32_t s, uint32_t t)
{
    if (s == NONE)
        return;
    if (r->slotn[s] == 2) {
        r->overfull = true;
        return;
    }
    r->slot[s][r->slotn[s]++] = t;
}

typedef struct cand {
    double d2;
    uint32_t occ;
} cand;

/* Candidates come out nearest first from a binary min-heap: the first
 * one or two nearly always make the bridge, so the whole is not sorted. */
static void sift_down(cand *h, uint32_t n, uint32_t i)
{
    for (;;) {
        uint32_t l = 2 * i + 1, m = i;
        if (l < n && h[l].d2 < h[m].d2)
            m = l;
        if (l + 1 < n && h[l + 1].d2 < h[m].d2)
            m = l + 1;
        if (m == i)
            return;
        cand t = h[i];
        h[i] = h[m];
        h[m] = t;
        i = m;
    }
}

static cand heap_pop(cand *h, uint32_t *n)
{
    cand top = h[0];
    h[0] = h[--*n];
    sift_down(h, *n, 0);
    return top;
}

/* Segment xy's box misses the box lo–hi. */
static bool apart(const splitter *s, const double lo[2], const double hi[2],
                  uint32_t x, uint32_t y)
{
    const double *X = s->P[x], *Y = s->P[y];
    for (int c = 0; c < 2; c++)
        if (fmax(X[c], Y[c]) < lo[c] || fmin(X[c], Y[c]) > hi[c])
            return true;
    return false;
}

/* Is the bridge from ring occurrence j to point lp[k] of hole lp (n
 * points) valid: inside both wedges, meeting no edge of the ring or of
 * the holes still open (holes[first …] in hole order, this one
 * included)? */
static bool bridge_ok(const splitter *s, const ring *r, uint32_t j,
                      const uint32_t *lp, uint32_t n, uint32_t k,
                      const uint32_t *holes, uint32_t nholes, uint32_t first)
{
    uint32_t p = r->pt[j], m = lp[k];
    if (!in_wedge(s, r->pt[r->prev[j]], p, r->pt[r->next[j]], m) ||
        !in_wedge(s, lp[k ? k - 1 : n - 1], m, lp[k + 1 < n ? k + 1 : 0], p))
        return false;
    /* edges whose boxes stay apart from the bridge's, by more than the
     * bounds allow, cannot meet it */
    double lo[2], hi[2], e = 2 * s->maxerr;
    for (int c = 0; c < 2; c++) {
        lo[c] = fmin(s->P[m][c], s->P[p][c]) - e;
        hi[c] = fmax(s->P[m][c], s->P[p][c]) + e;
    }
    for (uint32_t i = 0; i < r->n; i++) {
        uint32_t x = r->pt[i], y = r->pt[r->next[i]];
        if (!apart(s, lo, hi, x, y) && blocks(s, m, p, x, y))
            return false;
    }
    for (uint32_t h = first; h < nholes; h++) {
        uint32_t l = holes[h], b = s->ls[l], en = s->ls[l + 1];
        for (uint32_t c = b; c < en; c++) {
            uint32_t x = s->li[c], y = s->li[c + 1 < en ? c + 1 : b];
            if (!apart(s, lo, hi, x, y) && blocks(s, m, p, x, y))
                return false;
        }
    }
    return true;
}

typedef struct hole_key {
    double x, y;
    uint32_t loop;
} hole_key;

static int cmp_hole_desc(const void *a, const void *b)
{
    const hole_key *p = a, *q = b;
    if (p->x != q->x)
        return p->x < q->x ? 1 : -1;
    if (p->y != q->y)
        return p->y < q->y ? 1 : -1;
    return (p->loop > q->loop) - (p->loop < q->loop);
}

/* A hole sharing a point with the ring, its corner there nested in the
 * ring's wedge (each one's edges strictly inside the other's region
 * wedge), is spliced in at that point without a bridge: 1 when done, 0
 * when the hole shares no point with the ring, or -EINVAL when it shares
 * several (the part would fall apart into pieces joined at points, which
 * one ring cannot hold) or one whose wedges do not nest. */
static int join_at_shared_point(splitter *s, ring *r, uint32_t l,
                                const uint32_t *lp, uint32_t n)
{
    uint32_t ep = new_epoch(s), shared = 0, j = 0;
    for (uint32_t k = 0; k < n; k++) {
        uint32_t q = lp[k];
        if (s->stamp[q] == ep)
            continue;
        s->stamp[q] = ep;
        shared += s->cnt[q];
        if (s->cnt[q])
            j = s->occ_at[q];
    }
    if (shared == 0)
        return 0;
    if (shared > 1)
        return geo_err_set(s->err, -EINVAL, "loop %u: a hole touching the "
                           "boundary of its part at more than one point (the "
                           "part falls apart; give each piece its own loop)", l);
    uint32_t a = r->pt[r->prev[j]], v = r->pt[j], c = r->pt[r->next[j]];
    for (uint32_t k = 0; k < n; k++) {
        if (lp[k] != v)
            continue;
        uint32_t hp = lp[k ? k - 1 : n - 1], hn = lp[k + 1 < n ? k + 1 : 0];
        if (!in_wedge(s, a, v, c, hp) || !in_wedge(s, a, v, c, hn) ||
            !in_wedge(s, hp, v, hn, a) || !in_wedge(s, hp, v, hn, c))
            continue;
        /* a → j → hole after k … before k → j' → c */
        uint32_t o = r->n, after = r->next[j];
        for (uint32_t i = 0; i + 1 < n; i++) {
            r->pt[o + i] = lp[(k + 1 + i) % n];
            r->eslot[o + i] = NONE;
            r->next[o + i] = o + i + 1;
            r->prev[o + i] = o + i - 1;
        }
        uint32_t j2 = o + n - 1;
        r->pt[j2] = lp[k];
        for (uint32_t i = 0; i < n; i++)
            note_occ(s, o + i, r->pt[o + i]);
        r->prev[j2] = o + n - 2;
        r->eslot[j2] = r->eslot[j];
        r->eslot[j] = NONE;
        r->next[j2] = after;
        r->prev[after] = j2;
        r->next[j] = o;
        r->prev[o] = j;
        r->n += n;
        return 1;
    }
    return geo_err_set(s->err, -EINVAL, "loop %u: a hole touching the "
                       "boundary of its part from outside it", l);
}

/* Joins hole h (holes[h]) to the ring: at a shared point, else by one
 * bridge. */
static int bridge_hole(splitter *s, ring *r, const uint32_t *holes,
                       uint32_t nholes, uint32_t h, cand *cands)
{
    pts_t P = s->P;
    uint32_t l = holes[h], b = s->ls[l], n = s->ls[l + 1] - b;
    const uint32_t *lp = s->li + b;
    int joined = join_at_shared_point(s, r, l, lp, n);
    if (joined)
        return joined < 0 ? joined : 0;
    uint32_t top = 0;
    for (uint32_t j = 1; j < n; j++)
        if (lex_less(P[lp[top]], P[lp[j]]))
            top = j;
    const double *m = P[lp[top]];
    uint32_t nc = 0;
    for (uint32_t j = 0; j < r->n; j++) {
        const double *q = P[r->pt[j]];
        if (q[0] > m[0]) {
            double dx = q[0] - m[0], dy = q[1] - m[1];
            cands[nc].d2 = dx * dx + dy * dy;
            cands[nc].occ = j;
            nc++;
        }
    }
    for (uint32_t i = nc / 2; i-- > 0;)
        sift_down(cands, nc, i);
    while (nc > 0) {
        uint32_t j = heap_pop(cands, &nc).occ;
        for (uint32_t k = 0; k < n; k++) {
            if (lp[k] != lp[top] ||
                !bridge_ok(s, r, j, lp, n, k, holes, nholes, h))
                continue;
            /* P(j) → M → hole … → M' → P' → the old successor of j */
            uint32_t o = r->n, sl = new_slot(r), after = r->next[j];
            for (uint32_t i = 0; i < n; i++) {
                r->pt[o + i] = lp[(k + i) % n];
                r->eslot[o + i] = NONE;
                r->next[o + i] = o + i + 1;
                r->prev[o + i] = o + i - 1;
            }
            uint32_t m2 = o + n, p2 = o + n + 1;
            r->pt[m2] = lp[k];
            r->pt[p2] = r->pt[j];
            r->eslot[m2] = sl;
            r->eslot[p2] = r->eslot[j];
            r->eslot[j] = sl;
            r->next[m2] = p2;
            r->prev[m2] = o + n - 1;
            r->next[p2] = after;
            r->prev[p2] = m2;
            r->prev[after] = p2;
            r->next[j] = o;
            r->prev[o] = j;
            for (uint32_t i = 0; i < n + 2; i++)
                note_occ(s, o + i, r->pt[o + i]);
            r->n += n + 2;
            return 0;
        }
    }
    return geo_err_set(s->err, -EINVAL,
                       "loop %u: no bridge from this hole to the outer "
                       "boundary (the boundary crosses itself)", l);
}

/* The occurrences that can spoil an ear (non-convex or repeated points),
 * bucketed in a uniform grid over the ring's box so that an ear test
 * visits only those near its triangle. */
typedef struct grid {
    double x0, y0, cw, ch;
    uint32_t nx, ny;
    uint32_t *start; /* nx·ny + 1 */
    uint32_t *occ;
} grid;

static uint32_t cell_of(double v, double v0, double w, uint32_t n)
{
    double c = floor((v - v0) / w);
    if (!(c >= 0))
        return 0;
    return c >= n ? n - 1 : (uint32_t)c;
}

static int grid_build(const splitter *s, const ring *r, const uint32_t *susp,
                      uint32_t nsusp, grid *g)
{
    memset(g, 0, sizeof *g);
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (uint32_t i = 0; i < r->n; i++)
        for (int k = 0; k < 2; k++) {
            double v = s->P[r->pt[i]][k];
            lo[k] = v < lo[k] ? v : lo[k];
            hi[k] = v > hi[k] ? v : hi[k];
        }
    double side = sqrt((double)nsusp / 2.0) + 1;
    g->nx = g->ny = side > 1024 ? 1024 : (uint32_t)side;
    g->x0 = lo[0];
    g->y0 = lo[1];
    g->cw = (hi[0] - lo[0]) / g->nx;
    g->ch = (hi[1] - lo[1]) / g->ny;
    if (!(g->cw > 0))
        g->cw = 1;
    if (!(g->ch > 0))
        g->ch = 1;
    size_t nc = (size_t)g->nx * g->ny;
    g->start = calloc(nc + 1, sizeof *g->start);
    g->occ = malloc(((size_t)nsusp + 1) * sizeof *g->occ);
    if (!g->start || !g->occ)
        return -ENOMEM;
    uint32_t *cellid = malloc(((size_t)nsusp + 1) * sizeof *cellid);
    if (!cellid)
        return -ENOMEM;
    for (uint32_t x = 0; x < nsusp; x++) {
        const double *q = s->P[r->pt[susp[x]]];
        cellid[x] = cell_of(q[1], g->y0, g->ch, g->ny) * g->nx +
                    cell_of(q[0], g->x0, g->cw, g->nx);
        g->start[cellid[x] + 1]++;
    }
    for (size_t c = 0; c < nc; c++)
        g->start[c + 1] += g->start[c];
    for (uint32_t x = 0; x < nsusp; x++)
        g->occ[g->start[cellid[x]]++] = susp[x];
    for (size_t c = nc; c-- > 0;)
        g->start[c + 1] = g->start[c];
    g->start[0] = 0;
    free(cellid);
    return 0;
}

static void grid_free(grid *g)
{
    free(g->start), free(g->occ);
}

/* Could occurrence j spoil the ear a, i, c (corner points pa, pb, pc)? */
static bool spoils(const splitter *s, const ring *r, uint32_t j, uint32_t pa,
                   uint32_t pb, uint32_t pc)
{
    uint32_t q = r->pt[j];
    if (q == pa || q == pb || q == pc) {
        /* another pass through a corner: its edges must not enter */
        uint32_t from = q == pa ? pb : q == pb ? pc : pa;
        uint32_t to = q == pa ? pc : q == pb ? pa : pb;
        return maybe_in_angle(s, q, from, to, r->pt[r->prev[j]]) ||
               maybe_in_angle(s, q, from, to, r->pt[r->next[j]]);
    }
    return turn(s, pa, pb, q) != -1 && turn(s, pb, pc, q) != -1 &&
           turn(s, pc, pa, q) != -1;
}

static bool is_ear(const splitter *s, const ring *r, uint32_t i,
                   const grid *g)
{
    if (r->kind[i] != 1)
        return false;
    pts_t P = s->P;
    uint32_t a = r->prev[i], c = r->next[i];
    uint32_t pa = r->pt[a], pb = r->pt[i], pc = r->pt[c];
    const uint32_t corner[3] = {pa, pb, pc};
    double lo[2], hi[2], slack = 0;
    for (int k = 0; k < 2; k++)
        lo[k] = hi[k] = P[pa][k];
    for (int q = 0; q < 3; q++) {
        for (int k = 0; k < 2; k++) {
            double x = P[corner[q]][k];
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
        if (s->sure && s->perr && s->perr[corner[q]] > slack)
            slack = s->perr[corner[q]];
    }
    double big = slack + (s->sure ? s->maxerr : 0);
    uint32_t cx0 = cell_of(lo[0] - big, g->x0, g->cw, g->nx);
    uint32_t cx1 = cell_of(hi[0] + big, g->x0, g->cw, g->nx);
    uint32_t cy0 = cell_of(lo[1] - big, g->y0, g->ch, g->ny);
    uint32_t cy1 = cell_of(hi[1] + big, g->y0, g->ch, g->ny);
    for (uint32_t cy = cy0; cy <= cy1; cy++)
        for (uint32_t cx = cx0; cx <= cx1; cx++) {
            uint32_t cell = cy * g->nx + cx;
            for (uint32_t x = g->start[cell]; x < g->start[cell + 1]; x++) {
                uint32_t j = g->occ[x];
                if (r->dead[j] || j == a || j == i || j == c ||
                    (r->kind[j] == 1 && !r->dup[j]))
                    continue;
                const double *Q = P[r->pt[j]];
                double e = slack + (s->sure && s->perr ? s->perr[r->pt[j]] : 0);
                if (Q[0] < lo[0] - e || Q[0] > hi[0] + e ||
                    Q[1] < lo[1] - e || Q[1] > hi[1] + e)
                    continue;
                if (spoils(s, r, j, pa, pb, pc))
                    return false;
            }
        }
    return true;
}

static void add_triangle(ring *r, uint32_t a, uint32_t i, uint32_t c,
                         uint32_t sca)
{
    uint32_t t = r->ntri++;
    r->tri[t][0] = r->pt[a];
    r->tri[t][1] = r->pt[i];
    r->tri[t][2] = r->pt[c];
    r->tslot[t][0] = r->eslot[a];
    r->tslot[t][1] = r->eslot[i];
    r->tslot[t][2] = sca;
    slot_add(r, r->eslot[a], t);
    slot_add(r, r->eslot[i], t);
    slot_add(r, sca, t);
}

static int8_t turn_at(const splitter *s, const ring *r, uint32_t i)
{
    return (int8_t)turn(s, r->pt[r->prev[i]], r->pt[i], r->pt[r->next[i]]);
}

static int clip_ears(splitter *s, ring *r, uint32_t loop)
{
    uint32_t *susp = malloc(((size_t)r->n + 1) * sizeof *susp);
    if (!susp)
        return geo_err_set(s->err, -ENOMEM, "out of memory");
    for (uint32_t i = 0; i < r->n; i++)
        s->cnt[r->pt[i]] = 0;
    for (uint32_t i = 0; i < r->n; i++)
        s->cnt[r->pt[i]]++;
    uint32_t nsusp = 0;
    for (uint32_t i = 0; i < r->n; i++) {
        r->kind[i] = turn_at(s, r, i);
        r->dup[i] = s->cnt[r->pt[i]] > 1;
        if (r->kind[i] != 1 || r->dup[i])
            susp[nsusp++] = i;
    }
    grid g;
    if (grid_build(s, r, susp, nsusp, &g) < 0) {
        grid_free(&g);
        free(susp);
        return geo_err_set(s->err, -ENOMEM, "out of memory");
    }
    free(susp);
    /* Candidates in a FIFO of convex corners, first in ring order. After
     * a clip, its two neighbours go to the back, and a neighbour still
     * waiting in this pass is put back once: clipping every other corner
     * of a run keeps triangles small (a fan from one corner would cross
     * the part with ever longer diagonals), and the corners next to the
     * last clip, where a part closes up like a zip, are retried without a
     * sweep over the reflex corners. An empty queue is refilled from the
     * ring; a refill after which nothing is clipped means no ear. */
    size_t qcap = (size_t)r->n + 1;
    uint32_t *q = malloc(qcap * sizeof *q);
    uint8_t *inq = calloc(qcap, 1), *skip = calloc(qcap, 1);
    uint32_t remaining = r->n, i = 0, qh = 0, qn = 0;
    int rc = 0;
    if (!q || !inq || !skip) {
        rc = geo_err_set(s->err, -ENOMEM, "out of memory");
        goto out;
    }
    bool clipped = true;
    while (remaining > 3) {
        if (qn == 0) {
            if (!clipped) {
                rc = geo_err_set(s->err, -EINVAL,
                                 "loop %u: no ear left with %u corners (the "
                                 "boundary crosses or touches itself)",
                                 loop, remaining);
                goto out;
            }
            clipped = false;
            uint32_t j = i;
            do {
                if (r->kind[j] == 1) {
                    inq[j] = 1, skip[j] = 0;
                    q[(qh + qn++) % qcap] = j;
                }
                j = r->next[j];
            } while (j != i);
            continue;
        }
        uint32_t x = q[qh];
        qh = (qh + 1) % qcap, qn--;
        inq[x] = 0;
        if (r->dead[x] || r->kind[x] != 1)
            continue;
        if (skip[x]) {
            skip[x] = 0;
            inq[x] = 1;
            q[(qh + qn++) % qcap] = x;
            continue;
        }
        if (!is_ear(s, r, x, &g))
            continue;
        uint32_t a = r->prev[x], c = r->next[x];
        uint32_t sl = new_slot(r);
        add_triangle(r, a, x, c, sl);
        r->eslot[a] = sl;
        r->next[a] = c;
        r->prev[c] = a;
        r->dead[x] = 1;
        remaining--;
        clipped = true;
        i = a;
        r->kind[a] = turn_at(s, r, a);
        r->kind[c] = turn_at(s, r, c);
        const uint32_t nb[2] = {c, a};
        for (int k = 0; k < 2; k++) {
            if (inq[nb[k]]) {
                skip[nb[k]] = k == 0;
            } else if (r->kind[nb[k]] == 1) {
                inq[nb[k]] = 1, skip[nb[k]] = 0;
                q[(qh + qn++) % qcap] = nb[k];
            }
        }
    }
out:
    free(q), free(inq), free(skip);
    if (rc < 0) {
        grid_free(&g);
        return rc;
    }
    grid_free(&g);
    uint32_t a = r->prev[i], c = r->next[i];
    if (turn_at(s, r, i) != 1)
        return geo_err_set(s->err, -EINVAL,
                           "loop %u: the last triangle is flat (the boundary "
                           "crosses or touches itself)", loop);
    add_triangle(r, a, i, c, r->eslot[c]);
    if (r->overfull)
        return geo_err_set(s->err, -EINVAL, "loop %u: an edge borders more "
                           "than two triangles", loop);
    for (uint32_t sl = 0; sl < r->nslot; sl++)
        if (r->slotn[sl] != 2)
            return geo_err_set(s->err, -EINVAL, "loop %u: a diagonal with "
                               "%u triangles", loop, r->slotn[sl]);
    return 0;
}

/* Triangle across slot sl from t, and the point of it off that edge. */
static uint32_t across(const ring *r, uint32_t t, uint32_t sl, uint32_t *ret_w)
{
    uint32_t u = r->slot[sl][0] == t ? r->slot[sl][1] : r->slot[sl][0];
    for (int e = 0; e < 3; e++)
        if (r->tslot[u][e] == sl)
            *ret_w = r->tri[u][(e + 2) % 3];
    return u;
}

/* Merges the triangles into simple pieces and emits them. */
static int merge_and_emit(splitter *s, ring *r, uint32_t part, uint32_t loop)
{
    uint32_t nt = r->ntri;
    size_t m = (size_t)nt + 1;
    uint32_t *piece = malloc(m * sizeof *piece);
    uint32_t *queue = malloc(m * sizeof *queue);
    uint32_t *parent = malloc(m * sizeof *parent);
    uint32_t *head = malloc(m * sizeof *head);
    uint32_t *tail = malloc(m * sizeof *tail);
    uint32_t *tnext = malloc(m * sizeof *tnext);
    uint32_t *walk = malloc(3 * m * sizeof *walk);
    int rc = 0;
    if (!piece || !queue || !parent || !head || !tail || !tnext || !walk) {
        rc = geo_err_set(s->err, -ENOMEM, "out of memory");
        goto done;
    }
    /* growth: a triangle joins when it brings a new point */
    uint32_t np = 0;
    for (uint32_t t = 0; t < nt; t++)
        piece[t] = NONE;
    for (uint32_t t0 = 0; t0 < nt; t0++) {
        if (piece[t0] != NONE)
            continue;
        uint32_t id = np++, ep = new_epoch(s), qh = 0, qt = 0;
        piece[t0] = id;
        for (int e = 0; e < 3; e++)
            s->stamp[r->tri[t0][e]] = ep;
        queue[qt++] = t0;
        while (qh < qt) {
            uint32_t t = queue[qh++];
            for (int e = 0; e < 3; e++) {
                uint32_t sl = r->tslot[t][e], w = NONE;
                if (sl == NONE)
                    continue;
                uint32_t u = across(r, t, sl, &w);
                if (piece[u] != NONE || s->stamp[w] == ep)
                    continue;
                piece[u] = id;
                s->stamp[w] = ep;
                queue[qt++] = u;
            }
        }
    }
    for (uint32_t q = 0; q < np; q++)
        parent[q] = q, head[q] = NONE, tail[q] = NONE;
    for (uint32_t t = nt; t-- > 0;) {
        tnext[t] = head[piece[t]];
        if (head[piece[t]] == NONE)
            tail[piece[t]] = t;
        head[piece[t]] = t;
    }
    /* joining pieces that meet in exactly one edge */
    for (bool changed = true; changed;) {
        changed = false;
        for (uint32_t sl = 0; sl < r->nslot; sl++) {
            uint32_t A = geo_uf_find(parent, piece[r->slot[sl][0]]);
            uint32_t B = geo_uf_find(parent, piece[r->slot[sl][1]]);
            if (A == B)
                continue;
            uint32_t ea = new_epoch(s), eb = new_epoch(s), shared = 0;
            for (uint32_t t = head[A]; t != NONE; t = tnext[t])
                for (int e = 0; e < 3; e++)
                    s->stamp[r->tri[t][e]] = ea;
            for (uint32_t t = head[B]; t != NONE && shared <= 2; t = tnext[t])
                for (int e = 0; e < 3; e++) {
                    uint32_t q = r->tri[t][e];
                    if (s->stamp[q] == ea)
                        shared++;
                    s->stamp[q] = eb;
                }
            if (shared != 2)
                continue;
            parent[B] = A;
            tnext[tail[A]] = head[B];
            tail[A] = tail[B];
            changed = true;
        }
    }
    /* each piece's boundary: its triangles' edges not shared inside it */
    for (uint32_t q = 0; q < np; q++) {
        if (geo_uf_find(parent, q) != q)
            continue;
        uint32_t ep = new_epoch(s), nb = 0, start = NONE;
        for (uint32_t t = head[q]; t != NONE; t = tnext[t])
            for (int e = 0; e < 3; e++) {
                uint32_t sl = r->tslot[t][e], w;
                if (sl != NONE &&
                    geo_uf_find(parent, piece[across(r, t, sl, &w)]) == q)
                    continue;
                uint32_t x = r->tri[t][e], y = r->tri[t][(e + 1) % 3];
                if (s->stamp[x] == ep) {
                    rc = geo_err_set(s->err, -EINVAL, "loop %u: a merged "
                                     "piece touches itself", loop);
                    goto done;
                }
                s->stamp[x] = ep;
                s->nxt[x] = y;
                nb++;
                start = x;
            }
        uint32_t len = 0, x = start;
        do {
            if (len == nb || s->stamp[x] != ep)
                break;
            walk[len++] = x;
            x = s->nxt[x];
        } while (x != start);
        if (len != nb || x != start) {
            rc = geo_err_set(s->err, -EINVAL, "loop %u: a merged piece is "
                             "not one simple polygon", loop);
            goto done;
        }
        if ((rc = emit(s, walk, len, part)) < 0)
            goto done;
    }
done:
    free(piece), free(queue), free(parent), free(head), free(tail);
    free(tnext), free(walk);
    return rc;
}

/* Splits part `outer` with its holes (loop indices, any order). */
static int split_once(splitter *s, uint32_t outer, uint32_t *holes,
                      uint32_t nholes, uint32_t part)
{
    uint32_t b = s->ls[outer], n = s->ls[outer + 1] - b;
    size_t total = n;
    for (uint32_t h = 0; h < nholes; h++)
        total += (size_t)(s->ls[holes[h] + 1] - s->ls[holes[h]]) + 2;
    if (total > UINT32_MAX / 4)
        return geo_err_set(s->err, -EINVAL, "loop %u: too many points", outer);
    ring r;
    cand *cands = NULL;
    hole_key *keys = NULL;
    int rc = 0;
    if (ring_alloc(&r, (uint32_t)total) < 0 ||
        !(cands = malloc((total + 1) * sizeof *cands)) ||
        !(keys = malloc(((size_t)nholes + 1) * sizeof *keys))) {
        rc = geo_err_set(s->err, -ENOMEM, "out of memory");
        goto done;
    }
    for (uint32_t h = 0; h < nholes; h++)
        for (uint32_t c = s->ls[holes[h]]; c < s->ls[holes[h] + 1]; c++)
            s->cnt[s->li[c]] = 0;
    for (uint32_t i = 0; i < n; i++)
        s->cnt[s->li[b + i]] = 0;
    for (uint32_t i = 0; i < n; i++) {
        r.pt[i] = s->li[b + i];
        r.next[i] = i + 1 < n ? i + 1 : 0;
        r.prev[i] = i ? i - 1 : n - 1;
        r.eslot[i] = NONE;
        note_occ(s, i, r.pt[i]);
    }
    r.n = n;
    /* Eberly's order: by greatest point, decreasing */
    for (uint32_t h = 0; h < nholes; h++) {
        uint32_t l = holes[h], hb = s->ls[l], he = s->ls[l + 1], top = hb;
        for (uint32_t c = hb + 1; c < he; c++)
            if (lex_less(s->P[s->li[top]], s->P[s->li[c]]))
                top = c;
        keys[h].x = s->P[s->li[top]][0];
        keys[h].y = s->P[s->li[top]][1];
        keys[h].loop = l;
    }
    qsort(keys, nholes, sizeof *keys, cmp_hole_desc);
    for (uint32_t h = 0; h < nholes; h++)
        holes[h] = keys[h].loop;
    for (uint32_t h = 0; h < nholes; h++)
        if ((rc = bridge_hole(s, &r, holes, nholes, h, cands)) < 0)
            goto done;
    if ((rc = clip_ears(s, &r, outer)) < 0)
        goto done;
    rc = merge_and_emit(s, &r, part, outer);
done:
    ring_free(&r);
    free(cands), free(keys);
    return rc;
}

/* Splits a part deciding surely for every position within the bounds;
 * when that finds no way (the bounds leave too much unsure), decides on
 * the given positions alone. */
static int split_part(splitter *s, uint32_t outer, uint32_t *holes,
                      uint32_t nholes, uint32_t part)
{
    uint32_t before = s->out->npieces;
    s->sure = s->perr != NULL;
    int rc = split_once(s, outer, holes, nholes, part);
    if (rc == -EINVAL && s->sure) {
        s->out->npieces = before;
        s->sure = false;
        s->out->nfallback++;
        rc = split_once(s, outer, holes, nholes, part);
    }
    return rc;
}

/* ---- classification ----------------------------------------------------- */

typedef struct keyed_point {
    double x, y;
    uint32_t i;
} keyed_point;

static int cmp_keyed(const void *a, const void *b)
{
    const keyed_point *p = a, *q = b;
    if (p->x != q->x)
        return p->x < q->x ? -1 : 1;
    if (p->y != q->y)
        return p->y < q->y ? -1 : 1;
    return (p->i > q->i) - (p->i < q->i);
}

static int check_loops(splitter *s)
{
    pts_t P = s->P;
    for (uint32_t l = 0; l < s->nloops; l++) {
        uint32_t b = s->ls[l], e = s->ls[l + 1];
        if (e < b || e - b < 3)
            return geo_err_set(s->err, -EINVAL, "loop %u: fewer than 3 points", l);
        for (uint32_t c = b; c < e; c++) {
            if (s->li[c] >= s->npts)
                return geo_err_set(s->err, -EINVAL, "loop %u: point %u out "
                                   "of range (%u points)", l, s->li[c], s->npts);
            if (s->li[c] == s->li[c + 1 < e ? c + 1 : b])
                return geo_err_set(s->err, -EINVAL, "loop %u: point %u "
                                   "twice in a row", l, s->li[c]);
        }
    }
    /* distinct indices must have distinct positions */
    uint32_t ep = new_epoch(s), nk = 0;
    size_t total = s->ls[s->nloops];
    keyed_point *k = malloc((total + 1) * sizeof *k);
    if (!k)
        return geo_err_set(s->err, -ENOMEM, "out of memory");
    for (size_t c = 0; c < total; c++) {
        uint32_t i = s->li[c];
        if (s->stamp[i] == ep)
            continue;
        s->stamp[i] = ep;
        k[nk].x = P[i][0];
        k[nk].y = P[i][1];
        k[nk].i = i;
        nk++;
    }
    qsort(k, nk, sizeof *k, cmp_keyed);
    int rc = 0;
    for (uint32_t j = 1; j < nk && rc == 0; j++)
        if (k[j].x == k[j - 1].x && k[j].y == k[j - 1].y)
            rc = geo_err_set(s->err, -EINVAL, "points %u and %u are at the "
                             "same position", k[j - 1].i, k[j].i);
    free(k);
    return rc;
}

/* Is hole h inside part loop o? Decided at a point of h that o does not
 * pass through; false when every such test lands on o. */
static bool hole_inside(splitter *s, uint32_t h, uint32_t o)
{
    uint32_t ep = new_epoch(s);
    for (uint32_t c = s->ls[o]; c < s->ls[o + 1]; c++)
        s->stamp[s->li[c]] = ep;
    for (uint32_t c = s->ls[h]; c < s->ls[h + 1]; c++) {
        uint32_t q = s->li[c];
        if (s->stamp[q] == ep)
            continue;
        int in = point_in_loop(s->P, s->li + s->ls[o], s->ls[o + 1] - s->ls[o],
                               s->P[q]);
        if (in)
            return in > 0;
    }
    return false;
}

int geo_region_split(const double (*pts)[2], const double *perr,
                     uint32_t npts, const uint32_t *loop_start,
                     const uint32_t *loop_idx, uint32_t nloops,
                     geo_region_pieces *ret, geo_err *err)
{
    memset(ret, 0, sizeof *ret);
    splitter s;
    memset(&s, 0, sizeof s);
    s.P = pts;
    s.perr = perr;
    s.npts = npts;
    s.ls = loop_start;
    s.li = loop_idx;
    s.nloops = nloops;
    s.err = err;
    s.out = ret;
    size_t m = (size_t)npts + 1;
    s.stamp = calloc(m, sizeof *s.stamp);
    s.nxt = malloc(m * sizeof *s.nxt);
    s.cnt = malloc(m * sizeof *s.cnt);
    s.occ_at = malloc(m * sizeof *s.occ_at);
    s.info = malloc(((size_t)nloops + 1) * sizeof *s.info);
    uint32_t *holes = malloc(((size_t)nloops + 1) * sizeof *holes);
    uint32_t *hstart = calloc((size_t)nloops + 2, sizeof *hstart);
    int rc = 0;
    if (!s.stamp || !s.nxt || !s.cnt || !s.occ_at || !s.info || !holes ||
        !hstart) {
        rc = geo_err_set(err, -ENOMEM, "out of memory");
        goto done;
    }
    if ((rc = check_loops(&s)) < 0)
        goto done;
    for (uint32_t i = 0; perr && i < npts; i++)
        s.maxerr = perr[i] > s.maxerr ? perr[i] : s.maxerr;
    for (uint32_t l = 0; l < nloops; l++) {
        loopinfo *li = &s.info[l];
        const uint32_t *lp = loop_idx + loop_start[l];
        uint32_t n = loop_start[l + 1] - loop_start[l];
        double area = loop_area(pts, lp, n);
        li->sign = loop_sign(pts, lp, n, area);
        if (li->sign == 0) {
            rc = geo_err_set(err, -EINVAL, "loop %u: zero area", l);
            goto done;
        }
        li->area = area < 0 ? -area : area;
        uint32_t ep = new_epoch(&s);
        li->repeats = false;
        li->lo[0] = li->hi[0] = pts[lp[0]][0];
        li->lo[1] = li->hi[1] = pts[lp[0]][1];
        for (uint32_t j = 0; j < n; j++) {
            const double *q = pts[lp[j]];
            li->repeats |= s.stamp[lp[j]] == ep;
            s.stamp[lp[j]] = ep;
            for (int k = 0; k < 2; k++) {
                li->lo[k] = q[k] < li->lo[k] ? q[k] : li->lo[k];
                li->hi[k] = q[k] > li->hi[k] ? q[k] : li->hi[k];
            }
        }
        li->owner = NONE;
        if (li->sign > 0)
            li->owner = ret->nparts++;
        else
            ret->nholes++;
    }
    /* each hole to the innermost part containing it */
    for (uint32_t h = 0; h < nloops; h++) {
        loopinfo *hi = &s.info[h];
        if (hi->sign > 0)
            continue;
        for (uint32_t o = 0; o < nloops; o++) {
            const loopinfo *oi = &s.info[o];
            if (oi->sign < 0 || oi->lo[0] > hi->lo[0] || oi->lo[1] > hi->lo[1] ||
                oi->hi[0] < hi->hi[0] || oi->hi[1] < hi->hi[1] ||
                (hi->owner != NONE && oi->area >= s.info[hi->owner].area) ||
                !hole_inside(&s, h, o))
                continue;
            hi->owner = o;
        }
        if (hi->owner == NONE) {
            rc = geo_err_set(err, -EINVAL, "loop %u: a hole (clockwise) not "
                             "inside any part", h);
            goto done;
        }
        hstart[hi->owner + 1]++;
    }
    for (uint32_t o = 0; o < nloops; o++)
        hstart[o + 1] += hstart[o];
    for (uint32_t h = 0; h < nloops; h++)
        if (s.info[h].sign < 0)
            holes[hstart[s.info[h].owner]++] = h;
    for (uint32_t o = nloops; o-- > 0;)
        hstart[o + 1] = hstart[o];
    hstart[0] = 0;
    for (uint32_t o = 0; o < nloops; o++) {
        const loopinfo *oi = &s.info[o];
        if (oi->sign < 0)
            continue;
        uint32_t nh = hstart[o + 1] - hstart[o];
        if (nh == 0 && !oi->repeats) {
            rc = emit(&s, loop_idx + loop_start[o],
                      loop_start[o + 1] - loop_start[o], oi->owner);
        } else {
            ret->nsplit++;
            rc = split_part(&s, o, holes + hstart[o], nh, oi->owner);
        }
        if (rc < 0)
            goto done;
    }
done:
    free(s.stamp), free(s.nxt), free(s.cnt), free(s.occ_at), free(s.info);
    free(holes), free(hstart);
    if (rc < 0)
        geo_region_pieces_clear(ret);
    return rc;
}

int geo_region_needs_split(const double (*pts)[2], uint32_t npts,
                           const uint32_t *loop_start, const uint32_t *loop_idx,
                           uint32_t nloops)
{
    uint8_t *seen = calloc((size_t)npts + 1, 1);
    if (!seen)
        return -ENOMEM;
    int need = 0;
    for (uint32_t l = 0; l < nloops && !need; l++) {
        const uint32_t *lp = loop_idx + loop_start[l];
        uint32_t n = loop_start[l + 1] - loop_start[l];
        if (n < 3) {
            need = 1;
            break;
        }
        for (uint32_t j = 0; j < n && !need; j++) {
            if (lp[j] >= npts || seen[lp[j]])
                need = 1;
            else
                seen[lp[j]] = 1;
        }
        for (uint32_t j = 0; j < n && lp[j] < npts; j++)
            seen[lp[j]] = 0;
        if (!need)
            need = loop_sign(pts, lp, n, loop_area(pts, lp, n)) <= 0;
    }
    free(seen);
    return need;
}

void geo_region_pieces_clear(geo_region_pieces *r)
{
    if (!r)
        return;
    free(r->start), free(r->idx), free(r->part);
    memset(r, 0, sizeof *r);
}
