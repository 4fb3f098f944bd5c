/* frep_sharpen.c — crease recovery (see frep_sharpen.h).
 *
 * Each vertex carries the set of smooth pieces it lies on (one for a
 * vertex found by the ray search, two on a recovered crease, three at a
 * corner). Two vertices "share" a piece when their sets intersect; an edge
 * between vertices that share nothing spans a crease. */
#include "frep_sharpen.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "edgemap.h"
#include "trimesh.h"
#include "vec.h"

#define NOPIECE UINT32_MAX
/* new triangles must keep every angle above this (radians, 1°) */
#define MIN_ANGLE (M_PI / 180.0)

typedef struct sharpener {
    const geo_frep *f;
    const geo_frep_op *prog;
    uint32_t nprog;
    geo_tmesh m;
    uint32_t (*ps)[3]; /* piece set per vertex */
    size_t cap_ps;
    double *s;         /* mean edge length per original vertex */
    double tol, L, lo[3];
    geo_edgemap corners; /* quantised position → corner vertex */
    geo_tmesh_probe probe;
    geo_sharpen_stats st;
} sharpener;

/* Value and gradient of smooth piece p (a subtree of the program). */
static double piece_eval(const sharpener *S, uint32_t p, const double x[3],
                         double g[3])
{
    uint32_t s0 = S->prog[p].start;
    return geo_frep_run_grad(S->f, S->prog + s0, p - s0 + 1, x, g);
}

/* Least-norm Gauss–Newton towards {G_p = 0, G_q = 0} from x. */
static bool solve2(const sharpener *S, uint32_t p, uint32_t q, double x[3])
{
    for (int it = 0; it < 16; it++) {
        double g1[3], g2[3];
        double v1 = piece_eval(S, p, x, g1), v2 = piece_eval(S, q, x, g2);
        double a = geo_vdot(g1, g1), b = geo_vdot(g1, g2),
               c = geo_vdot(g2, g2), det = a * c - b * b;
        /* nearly parallel pieces: no well-defined crease */
        if (!(det > 1e-6 * a * c))
            return false;
        if (fabs(v1) <= S->tol * sqrt(a) && fabs(v2) <= S->tol * sqrt(c))
            return true;
        double l1 = (c * v1 - b * v2) / det, l2 = (a * v2 - b * v1) / det;
        for (int k = 0; k < 3; k++)
            x[k] -= l1 * g1[k] + l2 * g2[k];
    }
    return false;
}

/* Newton towards {G_p = G_q = G_r = 0} from x. */
static bool solve3(const sharpener *S, const uint32_t pcs[3], double x[3])
{
    for (int it = 0; it < 16; it++) {
        double g[3][3], v[3], ok = 1;
        for (int i = 0; i < 3; i++) {
            v[i] = piece_eval(S, pcs[i], x, g[i]);
            if (fabs(v[i]) > S->tol * geo_vlen(g[i]))
                ok = 0;
        }
        if (ok)
            return true;
        double c12[3], c20[3], c01[3];
        geo_vcross(g[1], g[2], c12);
        geo_vcross(g[2], g[0], c20);
        geo_vcross(g[0], g[1], c01);
        double det = geo_vdot(g[0], c12);
        double scale = geo_vlen(g[0]) * geo_vlen(g[1]) * geo_vlen(g[2]);
        if (!(fabs(det) > 1e-3 * scale))
            return false;
        for (int k = 0; k < 3; k++)
            x[k] -= (v[0] * c12[k] + v[1] * c20[k] + v[2] * c01[k]) / det;
    }
    return false;
}

/* True when x lies on the surface itself, not on a part of the crease
 * that another piece cuts away. */
static bool on_surface(const sharpener *S, const double x[3])
{
    double g[3], v = geo_frep_run_grad(S->f, S->prog, S->nprog, x, g);
    double gl = geo_vlen(g);
    return gl > 0 && fabs(v) <= 1e3 * S->tol * gl;
}

static bool share(const uint32_t a[3], const uint32_t b[3])
{
    for (int i = 0; i < 3 && a[i] != NOPIECE; i++)
        for (int j = 0; j < 3 && b[j] != NOPIECE; j++)
            if (a[i] == b[j])
                return true;
    return false;
}

static int set_size(const uint32_t a[3])
{
    int n = 0;
    while (n < 3 && a[n] != NOPIECE)
        n++;
    return n;
}

static int add_vertex(sharpener *S, const double x[3], const uint32_t set[3],
                      double sval)
{
    if (S->m.nv >= S->cap_ps) {
        size_t nc = 2 * S->cap_ps + 64;
        uint32_t(*n)[3] = realloc(S->ps, nc * sizeof *n);
        if (!n)
            return -ENOMEM;
        S->ps = n;
        double *ns = realloc(S->s, nc * sizeof *ns);
        if (!ns)
            return -ENOMEM;
        S->s = ns;
        S->cap_ps = nc;
    }
    S->s[S->m.nv] = sval;
    int64_t v = geo_tmesh_add_vertex(&S->m, x);
    if (v < 0)
        return (int)v;
    memcpy(S->ps[v], set, sizeof S->ps[0]);
    return (int)v;
}

/* The smallest angle of triangle p, q, r (radians). */
static double min_angle(const double *p, const double *q, const double *r)
{
    const double *v[3] = {p, q, r};
    double m = M_PI;
    for (int k = 0; k < 3; k++) {
        double u[3], w[3], x[3];
        geo_vsub(v[(k + 1) % 3], v[k], u);
        geo_vsub(v[(k + 2) % 3], v[k], w);
        geo_vcross(u, w, x);
        m = fmin(m, atan2(geo_vlen(x), geo_vdot(u, w)));
    }
    return m;
}

/* Whether triangle p, q, r is a fair replacement for a triangle of
 * normal n0 (any length): not a sliver, and not turned against it. */
static bool fair_tri(const double *p, const double *q, const double *r,
                     const double n0[3])
{
    double u[3], w[3], n[3];
    geo_vsub(q, p, u);
    geo_vsub(r, p, w);
    geo_vcross(u, w, n);
    return min_angle(p, q, r) > MIN_ANGLE &&
           geo_vdot(n, n0) > 0.5 * geo_vlen(n) * geo_vlen(n0);
}

/* Whether vertex v (with neighbour b across a known half-edge v→b) can
 * move to x with every one of its triangles staying fair. */
static bool can_move(const sharpener *S, uint32_t v, uint32_t b,
                     const double x[3])
{
    const geo_tmesh *m = &S->m;
    uint32_t w = b;
    for (uint32_t guard = 0; guard < 4096; guard++) {
        uint32_t h = geo_tmesh_find(m, v, w);
        if (h == UINT32_MAX)
            return false;
        uint32_t c = geo_tmesh_opposite(m, h);
        double e1[3], e2[3], n0[3];
        geo_vsub(m->v[w], m->v[v], e1);
        geo_vsub(m->v[c], m->v[v], e2);
        geo_vcross(e1, e2, n0);
        if (!fair_tri(x, m->v[w], m->v[c], n0))
            return false;
        w = c;
        if (w == b)
            return true;
    }
    return false;
}

/* A crease point for edge a–b, whose ends share no piece; false when
 * none passes the checks. */
static bool crease_point(sharpener *S, uint32_t a, uint32_t b, double ret[3],
                         uint32_t ret_set[3])
{
    const double *pa = S->m.v[a], *pb = S->m.v[b];
    double sa = S->s[a] > 0 ? S->s[a] : 1, sb = S->s[b] > 0 ? S->s[b] : 1;
    double seed[3], ab[3], len2;
    for (int k = 0; k < 3; k++)
        seed[k] = (sa * pb[k] + sb * pa[k]) / (sa + sb);
    geo_vsub(pb, pa, ab);
    len2 = geo_vdot(ab, ab);
    bool found = false;
    double best = INFINITY;
    for (int i = 0; i < 3 && S->ps[a][i] != NOPIECE; i++)
        for (int j = 0; j < 3 && S->ps[b][j] != NOPIECE; j++) {
            double x[3] = {seed[0], seed[1], seed[2]};
            uint32_t p = S->ps[a][i], q = S->ps[b][j];
            if (!solve2(S, p, q, x) || !on_surface(S, x))
                continue;
            double ax[3], t, d[3];
            geo_vsub(x, pa, ax);
            t = geo_vdot(ax, ab) / len2;
            geo_vmadd(pa, t, ab, d);
            double off = geo_vdist(d, x);
            if (!(t > 0 && t < 1) || off > 0.75 * sqrt(len2) || off >= best)
                continue;
            best = off;
            memcpy(ret, x, 3 * sizeof *x);
            ret_set[0] = p < q ? p : q;
            ret_set[1] = p < q ? q : p;
            ret_set[2] = NOPIECE;
            found = true;
        }
    return found;
}

/* A point of the surface between the ends of edge a–b, which share no
 * piece and no crease of theirs passes the checks: the ends lie on two
 * pieces that do not meet there, with a third piece between them — the
 * typical case is a wall parallel to the rays, whose top and bottom ends
 * lie on the pieces above and below a face the rays never hit. The
 * paper's point S is moved onto F = 0 by Newton steps along ∇F; it must
 * land on a piece neither end lies on, over the edge's interior and near
 * it. Splitting there turns one edge that cannot be recovered into two
 * that span a real crease each. */
static bool middle_point(sharpener *S, uint32_t a, uint32_t b, double ret[3],
                         uint32_t ret_set[3])
{
    const double *pa = S->m.v[a], *pb = S->m.v[b];
    double sa = S->s[a] > 0 ? S->s[a] : 1, sb = S->s[b] > 0 ? S->s[b] : 1;
    double x[3], ab[3], ax[3], d[3];
    for (int k = 0; k < 3; k++)
        x[k] = (sa * pb[k] + sb * pa[k]) / (sa + sb);
    geo_vsub(pb, pa, ab);
    double len2 = geo_vdot(ab, ab);
    if (geo_frep_project(S->f, x, S->tol, sqrt(len2)) > S->tol)
        return false;
    uint32_t set[3] = {NOPIECE, NOPIECE, NOPIECE};
    geo_frep_run_piece(S->f, S->prog, S->nprog, x, NULL, &set[0]);
    if (share(set, S->ps[a]) || share(set, S->ps[b]))
        return false;
    geo_vsub(x, pa, ax);
    double t = geo_vdot(ax, ab) / len2;
    geo_vmadd(pa, t, ab, d);
    if (!(t > 0.1 && t < 0.9) || geo_vdist(d, x) > 0.75 * sqrt(len2))
        return false;
    memcpy(ret, x, sizeof x);
    memcpy(ret_set, set, sizeof set);
    return true;
}

/* Whether splitting edge a–b at x leaves fair triangles on both sides. */
static bool split_is_fair(const sharpener *S, uint32_t a, uint32_t b,
                          const double x[3])
{
    const geo_tmesh *m = &S->m;
    uint32_t h[2] = {geo_tmesh_find(m, a, b), geo_tmesh_find(m, b, a)};
    for (int k = 0; k < 2; k++) {
        uint32_t p = k ? b : a, q = k ? a : b, r = geo_tmesh_opposite(m, h[k]);
        double u[3], w[3], n0[3];
        geo_vsub(m->v[q], m->v[p], u);
        geo_vsub(m->v[r], m->v[p], w);
        geo_vcross(u, w, n0);
        if (!fair_tri(m->v[p], x, m->v[r], n0) ||
            !fair_tri(x, m->v[q], m->v[r], n0))
            return false;
    }
    return true;
}

/* Whether replacing triangles old[0..nold) by newt[0..nnew) (see
 * geo_tmesh_clashes) leaves the surface free of contacts within two rings
 * of them: every operation is checked exactly before it is applied, so
 * recovery never folds the mesh onto itself. 1 clear, 0 not, or
 * -ENOMEM. */
static int clear_of(sharpener *S, const uint32_t *old, uint32_t nold,
                    const uint32_t (*newt)[3], uint32_t nnew, uint32_t moved,
                    const double x[3])
{
    int rc = geo_tmesh_clashes(&S->m, &S->probe, old, nold, newt, nnew, moved,
                               x, 2);
    return rc < 0 ? rc : !rc;
}

/* Splits edge a–b at x (pieces set) when the four new triangles are fair
 * and clear. 1 split, 0 refused, or -ENOMEM. */
static int split_at(sharpener *S, uint32_t a, uint32_t b, const double x[3],
                    const uint32_t set[3])
{
    if (!split_is_fair(S, a, b, x))
        return 0;
    uint32_t h1 = geo_tmesh_find(&S->m, a, b), h2 = geo_tmesh_find(&S->m, b, a);
    uint32_t c = geo_tmesh_opposite(&S->m, h1),
             d = geo_tmesh_opposite(&S->m, h2), X = GEO_TMESH_NEWV;
    uint32_t old[2] = {h1 / 3, h2 / 3};
    uint32_t nt[4][3] = {{a, X, c}, {X, b, c}, {b, X, d}, {X, a, d}};
    int ok = clear_of(S, old, 2, (const uint32_t(*)[3])nt, 4, UINT32_MAX, x);
    if (ok <= 0)
        return ok;
    int v = add_vertex(S, x, set, 0.5 * (S->s[a] + S->s[b]));
    if (v < 0)
        return v;
    int rc = geo_tmesh_split_edge(&S->m, a, b, (uint32_t)v);
    return rc < 0 ? rc : 1;
}

/* Moves vertex v (neighbour b) to x when its triangles stay fair and
 * clear. 1 moved, 0 refused, or -ENOMEM. */
static int move_to(sharpener *S, uint32_t v, uint32_t b, const double x[3])
{
    if (!can_move(S, v, b, x))
        return 0;
    uint32_t old[64], nt[64][3], n = 0, w = b;
    do {
        uint32_t h = geo_tmesh_find(&S->m, v, w);
        if (h == UINT32_MAX || n == 64)
            return 0;
        old[n] = h / 3;
        memcpy(nt[n], S->m.t[h / 3], sizeof nt[n]);
        n++;
        w = geo_tmesh_opposite(&S->m, h);
    } while (w != b);
    int ok = clear_of(S, old, n, (const uint32_t(*)[3])nt, n, v, x);
    if (ok <= 0)
        return ok;
    memcpy(S->m.v[v], x, sizeof S->m.v[0]);
    return 1;
}

static int edge_pass(sharpener *S, uint32_t *changed, const geo_ctx *ctx)
{
    uint32_t nt = S->m.nt;
    for (uint32_t t = 0; t < nt; t++) {
        if ((t & 4095) == 0 && geo_ctx_canceled(ctx))
            return -ECANCELED;
        for (int k = 0; k < 3 && !S->m.dead[t]; k++) {
            uint32_t a = S->m.t[t][k], b = S->m.t[t][(k + 1) % 3];
            if (a > b || share(S->ps[a], S->ps[b]) ||
                geo_tmesh_find(&S->m, b, a) == UINT32_MAX)
                continue;
            double x[3];
            uint32_t set[3];
            int rc;
            if (!crease_point(S, a, b, x, set)) {
                rc = middle_point(S, a, b, x, set) ? split_at(S, a, b, x, set)
                                                   : 0;
                if (rc < 0)
                    return rc;
                if (rc) {
                    S->st.nmiddle_splits++;
                    (*changed)++;
                } else {
                    S->st.nrejected++;
                }
                continue;
            }
            double ax[3], ab[3];
            geo_vsub(x, S->m.v[a], ax);
            geo_vsub(S->m.v[b], S->m.v[a], ab);
            double tt = geo_vdot(ax, ab) / geo_vdot(ab, ab);
            uint32_t mv = UINT32_MAX;
            rc = 0;
            if (tt < 0.25 && set_size(S->ps[a]) == 1 &&
                (rc = move_to(S, a, b, x)) > 0)
                mv = a;
            else if (rc >= 0 && tt > 0.75 && set_size(S->ps[b]) == 1 &&
                     (rc = move_to(S, b, a, x)) > 0)
                mv = b;
            if (rc < 0)
                return rc;
            if (mv != UINT32_MAX) {
                memcpy(S->ps[mv], set, sizeof S->ps[0]);
                S->st.nsnaps++;
                (*changed)++;
                continue;
            }
            if ((rc = split_at(S, a, b, x, set)) < 0)
                return rc;
            if (rc) {
                S->st.nedge_splits++;
                (*changed)++;
            } else {
                S->st.nrejected++;
            }
        }
    }
    return 0;
}

/* Corners are found once each: several triangles may span the same
 * corner (four or more pieces can meet at one point, so even different
 * triples of pieces give the same point), and a second vertex there would
 * touch the first. Positions are hashed on a grid of 2⁻²⁰ of the bounds,
 * and the 27 cells around a point are looked up. */
static uint64_t corner_key(const sharpener *S, const double x[3], int dx,
                           int dy, int dz)
{
    int d[3] = {dx, dy, dz};
    uint64_t key = 0;
    for (int k = 0; k < 3; k++) {
        double q = floor((x[k] - S->lo[k]) / S->L * 1048576.0) + d[k];
        uint64_t c = q < 0 ? 0 : q > 2097151.0 ? 2097151u : (uint64_t)q;
        key = key << 21 | c;
    }
    return key;
}

static uint32_t corner_find(const sharpener *S, const double x[3])
{
    for (int dx = -1; dx <= 1; dx++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dz = -1; dz <= 1; dz++) {
                uint32_t v = geo_edgemap_get(&S->corners,
                                             corner_key(S, x, dx, dy, dz));
                if (v != UINT32_MAX &&
                    geo_vdist(S->m.v[v], x) <= 1e3 * S->tol)
                    return v;
            }
    return UINT32_MAX;
}

/* Triangle t spans a corner that already has vertex cx: when cx is the
 * vertex opposite one of t's edges in the neighbouring triangle, that
 * edge is flipped so that t's corners connect to cx (both new triangles
 * must be fair and clear). 1 flipped, 0 not, or -ENOMEM. */
static int flip_to_corner(sharpener *S, uint32_t t, uint32_t cx)
{
    geo_tmesh *m = &S->m;
    for (int k = 0; k < 3; k++) {
        uint32_t a = m->t[t][k], b = m->t[t][(k + 1) % 3],
                 c = m->t[t][(k + 2) % 3];
        uint32_t h = geo_tmesh_find(m, b, a);
        if (h == UINT32_MAX || geo_tmesh_opposite(m, h) != cx)
            continue;
        double e1[3], e2[3], n0[3];
        geo_vsub(m->v[b], m->v[a], e1);
        geo_vsub(m->v[c], m->v[a], e2);
        geo_vcross(e1, e2, n0);
        /* flipping a–b turns (a,b,c), (b,a,cx) into (a,cx,c), (b,c,cx) */
        if (!fair_tri(m->v[a], m->v[cx], m->v[c], n0) ||
            !fair_tri(m->v[b], m->v[c], m->v[cx], n0))
            return 0;
        uint32_t old[2] = {t, h / 3};
        uint32_t nt[2][3] = {{a, cx, c}, {b, c, cx}};
        int ok = clear_of(S, old, 2, (const uint32_t(*)[3])nt, 2, UINT32_MAX,
                          m->v[cx]);
        if (ok <= 0)
            return ok;
        return geo_tmesh_flip(m, a, b) == 0;
    }
    return 0;
}

static int corner_pass(sharpener *S, uint32_t *changed, const geo_ctx *ctx)
{
    uint32_t nt = S->m.nt;
    for (uint32_t t = 0; t < nt; t++) {
        if ((t & 4095) == 0 && geo_ctx_canceled(ctx))
            return -ECANCELED;
        if (S->m.dead[t])
            continue;
        const uint32_t *tv = S->m.t[t];
        uint32_t u[9], nu = 0;
        for (int k = 0; k < 3; k++)
            for (int i = 0; i < 3 && S->ps[tv[k]][i] != NOPIECE; i++) {
                uint32_t p = S->ps[tv[k]][i];
                bool dup = false;
                for (uint32_t j = 0; j < nu; j++)
                    dup |= u[j] == p;
                if (!dup)
                    u[nu++] = p;
            }
        if (nu != 3)
            continue;
        /* a piece common to all three corners: the triangle lies on it */
        bool common = false;
        for (uint32_t j = 0; j < 3 && !common; j++) {
            int in = 0;
            for (int k = 0; k < 3; k++)
                for (int i = 0; i < 3; i++)
                    in += S->ps[tv[k]][i] == u[j];
            common = in == 3;
        }
        if (common)
            continue;
        double c[3] = {0, 0, 0}, emax = 0;
        for (int k = 0; k < 3; k++) {
            geo_vadd(c, S->m.v[tv[k]], c);
            emax = fmax(emax, geo_vdist(S->m.v[tv[k]],
                                        S->m.v[tv[(k + 1) % 3]]));
        }
        geo_vscale(c, 1.0 / 3.0, c);
        double x[3] = {c[0], c[1], c[2]};
        double e1[3], e2[3], n0[3];
        geo_vsub(S->m.v[tv[1]], S->m.v[tv[0]], e1);
        geo_vsub(S->m.v[tv[2]], S->m.v[tv[0]], e2);
        geo_vcross(e1, e2, n0);
        if (!solve3(S, u, x) || !on_surface(S, x) ||
            geo_vdist(x, c) > emax) {
            S->st.nrejected++;
            continue;
        }
        uint32_t cx = corner_find(S, x);
        if (cx != UINT32_MAX) {
            int rc = flip_to_corner(S, t, cx);
            if (rc < 0)
                return rc;
            if (rc) {
                S->st.ncorner_flips++;
                (*changed)++;
            } else {
                S->st.nrejected++;
            }
            continue;
        }
        if (!fair_tri(S->m.v[tv[0]], S->m.v[tv[1]], x, n0) ||
            !fair_tri(S->m.v[tv[1]], S->m.v[tv[2]], x, n0) ||
            !fair_tri(S->m.v[tv[2]], S->m.v[tv[0]], x, n0)) {
            S->st.nrejected++;
            continue;
        }
        uint32_t X = GEO_TMESH_NEWV;
        uint32_t nt3[3][3] = {{tv[0], tv[1], X}, {tv[1], tv[2], X},
                              {tv[2], tv[0], X}};
        int ok = clear_of(S, &t, 1, (const uint32_t(*)[3])nt3, 3, UINT32_MAX,
                          x);
        if (ok < 0)
            return ok;
        if (!ok) {
            S->st.nrejected++;
            continue;
        }
        uint32_t set[3] = {u[0], u[1], u[2]};
        int v = add_vertex(S, x, set, emax);
        if (v < 0)
            return v;
        int rc = geo_tmesh_split_tri(&S->m, t, (uint32_t)v);
        if (rc == 0)
            rc = geo_edgemap_put(&S->corners, corner_key(S, x, 0, 0, 0),
                                 (uint32_t)v);
        if (rc < 0)
            return rc;
        S->st.ncorners++;
        (*changed)++;
    }
    return 0;
}

int geo_frep_sharpen(const geo_frep *f, geo_poly *m, uint8_t **tags,
                     const geo_ctx *ctx, geo_sharpen_stats *st, geo_err *err)
{
    sharpener S = {.f = f};
    S.prog = geo_frep_program(f, &S.nprog);
    int rc = 0;
    bool creases = false;
    for (uint32_t i = 0; i < S.nprog; i++)
        creases |= S.prog[i].code == GEO_FREP_OP_MAX ||
                   S.prog[i].code == GEO_FREP_OP_MIN;
    if (st)
        memset(st, 0, sizeof *st);
    for (uint32_t fc = 0; fc < m->nfacets; fc++)
        if (geo_poly_facet_size(m, fc) != 3)
            return geo_err_set(err, -EINVAL, "facets[%u]: not a triangle",
                               fc);
    if (!creases || m->nfacets == 0)
        return 0;
    double lo[3], hi[3];
    geo_frep_bounds(f, lo, hi);
    S.L = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    S.tol = 1e-12 * S.L;
    memcpy(S.lo, lo, sizeof S.lo);
    S.cap_ps = (size_t)m->nverts + 64;
    S.ps = malloc(S.cap_ps * sizeof *S.ps);
    S.s = calloc(S.cap_ps, sizeof *S.s);
    uint32_t *cnt = calloc((size_t)m->nverts + 1, sizeof *cnt);
    geo_poly *q = NULL;
    uint8_t *ntags = NULL;
    if (!S.ps || !S.s || !cnt || geo_edgemap_init(&S.corners, 64) < 0 ||
        geo_tmesh_init(&S.m, &m->verts[0][0], m->nverts) < 0)
        goto oom;
    for (uint32_t v = 0; v < m->nverts; v++) {
        if ((v & 65535) == 0 && geo_ctx_canceled(ctx)) {
            rc = geo_err_set(err, -ECANCELED, "canceled");
            goto done;
        }
        S.ps[v][1] = S.ps[v][2] = NOPIECE;
        geo_frep_run_piece(f, S.prog, S.nprog, m->verts[v], NULL,
                           &S.ps[v][0]);
    }
    for (uint32_t fc = 0; fc < m->nfacets; fc++) {
        if ((fc & 65535) == 0 && geo_ctx_canceled(ctx)) {
            rc = geo_err_set(err, -ECANCELED, "canceled");
            goto done;
        }
        const uint32_t *fv = geo_poly_facet(m, fc);
        for (int k = 0; k < 3; k++) {
            double l = geo_vdist(m->verts[fv[k]], m->verts[fv[(k + 1) % 3]]);
            S.s[fv[k]] += l, cnt[fv[k]]++;
        }
        int64_t t = geo_tmesh_add(&S.m, fv[0], fv[1], fv[2],
                                  tags && *tags ? (*tags)[fc] : 0);
        if (t == -EEXIST) {
            rc = geo_err_set(err, -EINVAL, "facets[%u]: repeats a directed "
                                           "edge", fc);
            goto done;
        }
        if (t < 0)
            goto oom;
    }
    for (uint32_t v = 0; v < m->nverts; v++)
        if (cnt[v])
            S.s[v] /= cnt[v];
    for (int round = 0; round < 4; round++) {
        if ((rc = geo_ctx_progress(ctx, round / 4.0)) < 0) {
            geo_err_set(err, rc, "canceled");
            goto done;
        }
        uint32_t changed = 0;
        if ((rc = edge_pass(&S, &changed, ctx)) < 0 ||
            (rc = corner_pass(&S, &changed, ctx)) < 0) {
            if (rc == -ECANCELED) {
                geo_err_set(err, rc, "canceled");
                goto done;
            }
            goto oom;
        }
        S.st.nrounds++;
        if (changed == 0)
            break;
    }
    uint32_t live = 0;
    for (uint32_t t = 0; t < S.m.nt; t++)
        live += !S.m.dead[t];
    q = geo_poly_new();
    if (!q || geo_poly_reserve(q, S.m.nv, live, 3 * (size_t)live) < 0)
        goto oom;
    if (tags && *tags && !(ntags = malloc((size_t)live + 1)))
        goto oom;
    for (uint32_t v = 0; v < S.m.nv; v++)
        if (geo_poly_add_vertex(q, S.m.v[v]) < 0)
            goto oom;
    for (uint32_t t = 0; t < S.m.nt; t++) {
        if (S.m.dead[t])
            continue;
        int64_t nf = geo_poly_add_facet(q, S.m.t[t], 3);
        if (nf < 0)
            goto oom;
        if (ntags)
            ntags[nf] = S.m.tag[t];
    }
    for (uint32_t fc = 0; fc < q->nfacets; fc++) {
        if ((fc & 65535) == 0 && geo_ctx_canceled(ctx)) {
            rc = geo_err_set(err, -ECANCELED, "canceled");
            goto done;
        }
        geo_poly_facet_fit_plane(q, fc, GEO_PLANE_UNWEIGHTED, q->planes[fc]);
    }
    if (ntags) {
        free(*tags);
        *tags = ntags;
        ntags = NULL;
    }
    geo_poly tmp = *m;
    *m = *q;
    *q = tmp;
    if (st)
        *st = S.st;
    goto done;
oom:
    rc = geo_err_set(err, -ENOMEM, "out of memory");
done:
    geo_poly_free(q);
    geo_tmesh_destroy(&S.m);
    geo_edgemap_destroy(&S.corners);
    geo_tmesh_probe_destroy(&S.probe);
    free(S.ps), free(S.s), free(cnt), free(ntags);
    return rc;
}
