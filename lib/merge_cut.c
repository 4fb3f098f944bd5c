/* merge_cut.c — the last step of a merge: the cut of the model by the
 * merged facet's plane in the form of seed 000 §3.4, done locally.
 *
 * What it computes is what geo_cut (lib/cut.c) computes with
 * opts.main_facet: everything on the outer side of the plane π goes, the
 * main facet (all its vertices on or above π after lifting) is replaced by
 * the section, and the section must be one component (§3.4 item 1). The
 * difference is the reach: geo_cut classifies every vertex of the model;
 * here only the part above π that touches the main facet is visited
 * (breadth first over vertices above π), and the facet BVH of the round
 * proves that no other facet has a vertex above π — such a vertex would
 * make a second section component, which §3.4 refuses, so the group is
 * refused too. The result is the same model; the cost is proportional to
 * the cut-off cap, not to the model.
 *
 * Each facet crossing π is cut by the paper's stages as in cut.c: nodes
 * (vertices and crossing points; one new vertex per crossed edge, shared
 * by its two facets), the events on l = facet ∩ π sorted exactly along l
 * (geo_plane_crossing_cmp), the direction sweep, and the pieces by
 * cycles B and A; every segment of l walked by cycle A is, reversed, an
 * edge of the section. Edges lying in π join the section where the facet
 * on one side of them is kept and the other is not (§3.4 item 2: the main
 * facet's own edges in π enter the section this way, in its
 * counter-clockwise order). Sides are decided once: 0 within geo_poly_eps
 * of π (the lifted points lie on π to rounding), else the sign. */
#include "merge_impl.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "predicates.h"
#include "vec.h"

enum ev_type { EV_ENTRY, EV_EXIT, EV_DOUBLE, EV_PASS };
enum seg_type { SEG_KEPT, SEG_REMOVED };

typedef struct node {
    uint32_t i, vout;
    uint8_t crossing, in, out;
    int32_t ev;
} node;

typedef struct event {
    uint8_t type;
    uint32_t node;
    const double *p0, *p1;
    int32_t partner;
} event;

/* Edge-keyed map (undirected) for crossing vertices and visited edges. */
typedef struct emap {
    uint64_t *key;
    uint32_t *val;
    size_t cap;
} emap;

static uint64_t ekey(uint32_t a, uint32_t b)
{
    return a < b ? ((uint64_t)a << 32) | b : ((uint64_t)b << 32) | a;
}

static int emap_init(emap *m, size_t n)
{
    m->cap = 64;
    while (m->cap < 2 * n + 16)
        m->cap *= 2;
    m->key = malloc(m->cap * sizeof *m->key);
    m->val = malloc(m->cap * sizeof *m->val);
    if (!m->key || !m->val)
        return -ENOMEM;
    for (size_t i = 0; i < m->cap; i++)
        m->val[i] = GEO_NONE;
    return 0;
}

static void emap_free(emap *m)
{
    free(m->key);
    free(m->val);
}

/* The slot of key (empty: val GEO_NONE). The map never fills: it is
 * sized for every edge of the region. */
static size_t emap_slot(const emap *m, uint64_t k)
{
    size_t h = (size_t)((k * 0x9e3779b97f4a7c15ULL) >> 17);
    for (size_t i = h & (m->cap - 1);; i = (i + 1) & (m->cap - 1))
        if (m->val[i] == GEO_NONE || m->key[i] == k)
            return i;
}

typedef struct cutter {
    geo_mw *w;
    geo_edit *e;
    const double *plane;
    emap xmap;             /* crossed edge → new vertex */
    uint32_t (*cap)[2];    /* section edges (src, dst) */
    size_t ncap, capcap;
    node *nodes;
    size_t capnodes;
    event *ev;
    size_t capev;
    uint32_t *piece, *pstart;
    size_t cappiece, cappstart;
    uint8_t *used;
    size_t capused;
    geo_err *err;
} cutter;

static int grow(void **buf, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap)
        return 0;
    size_t c = *cap ? *cap : 16;
    while (c < need)
        c *= 2;
    void *b = realloc(*buf, c * elem);
    if (!b)
        return -ENOMEM;
    *buf = b;
    *cap = c;
    return 0;
}

static int push_cap(cutter *k, uint32_t a, uint32_t b)
{
    if (grow((void **)&k->cap, &k->capcap, k->ncap + 1, sizeof *k->cap) < 0)
        return -ENOMEM;
    k->cap[k->ncap][0] = a;
    k->cap[k->ncap][1] = b;
    k->ncap++;
    return 0;
}

static int dominant_axis(const double v[3])
{
    int k = 0;
    for (int j = 1; j < 3; j++)
        if (fabs(v[j]) > fabs(v[k]))
            k = j;
    return k;
}

/* As in cut.c: the crossing of edge a–b from the end nearer to the
 * plane, so the same edge gives the same bits whichever facet asks. */
static void crossing_point(const double plane[4], const double a[3],
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
}

/* The new vertex on crossed edge a–b (created once). */
static int64_t crossing_vertex(cutter *k, uint32_t a, uint32_t b)
{
    size_t s = emap_slot(&k->xmap, ekey(a, b));
    if (k->xmap.val[s] != GEO_NONE)
        return k->xmap.val[s];
    double x[3];
    crossing_point(k->plane, k->e->verts[a], k->e->verts[b], x);
    int64_t id = geo_edit_add_vertex(k->e, x);
    if (id < 0)
        return id;
    k->xmap.key[s] = ekey(a, b);
    k->xmap.val[s] = (uint32_t)id;
    return id;
}

typedef struct facet_frame {
    int k, esign, drop, osign;
} facet_frame;

static int along(const cutter *k, const facet_frame *fr, const double *a0,
                 const double *a1, const double *b0, const double *b1)
{
    return fr->esign * geo_plane_crossing_cmp(k->plane, a0, a1, b0, b1, fr->k);
}

static int insert_event(cutter *k, const facet_frame *fr, size_t *nev,
                        const event *e)
{
    if (grow((void **)&k->ev, &k->capev, *nev + 1, sizeof *k->ev) < 0)
        return -ENOMEM;
    size_t lo = 0, hi = *nev;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        const event *m = &k->ev[mid];
        if (along(k, fr, m->p0, m->p1, e->p0, e->p1) <= 0)
            lo = mid + 1;
        else
            hi = mid;
    }
    memmove(k->ev + lo + 1, k->ev + lo, (*nev - lo) * sizeof *k->ev);
    k->ev[lo] = *e;
    (*nev)++;
    return 0;
}

static int facet_error(cutter *k, uint32_t f, const char *what)
{
    return geo_err_set(k->err, -EINVAL, "facets[%u]: %s while cutting by the "
                       "merged plane", f, what);
}

static int piece_push(cutter *k, size_t *np, uint32_t v)
{
    if (grow((void **)&k->piece, &k->cappiece, *np + 1, sizeof *k->piece) < 0)
        return -ENOMEM;
    k->piece[(*np)++] = v;
    return 0;
}

/* Cuts facet f (vertex cycle vs[0..n), copied by the caller) into its
 * kept pieces: piece p is k->piece[pstart[p] .. pstart[p+1]). Section
 * segments go to k->cap. Returns the number of pieces or an error. */
static int cut_facet(cutter *k, uint32_t f, const uint32_t *vs, uint32_t n)
{
    geo_mw *w = k->w;
    geo_edit *e = k->e;
    double nf[3], ev3[3];
    geo_edit_area_vector(e, f, nf);
    geo_vcross(k->plane, nf, ev3);
    if (!(geo_vlen(ev3) > 0.0))
        return facet_error(k, f, "crosses the plane but is parallel to it");
    facet_frame fr;
    fr.k = dominant_axis(ev3);
    fr.esign = ev3[fr.k] > 0 ? 1 : -1;
    fr.drop = dominant_axis(nf);
    fr.osign = nf[fr.drop] > 0 ? 1 : -1;

    if (grow((void **)&k->nodes, &k->capnodes, 2 * (size_t)n, sizeof *k->nodes) < 0)
        return -ENOMEM;
    uint32_t nn = 0;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t j = i + 1 < n ? i + 1 : 0;
        int si = geo_mw_side(w, vs[i], k->plane), sj = geo_mw_side(w, vs[j], k->plane);
        node *v = &k->nodes[nn++];
        v->i = i;
        v->vout = vs[i];
        v->crossing = 0;
        v->ev = -1;
        if (si * sj < 0) {
            v->out = si < 0 ? SEG_KEPT : SEG_REMOVED;
            int64_t x = crossing_vertex(k, vs[i], vs[j]);
            if (x < 0)
                return (int)x;
            node *c = &k->nodes[nn++];
            c->i = i;
            c->vout = (uint32_t)x;
            c->crossing = 1;
            c->ev = -1;
            c->in = v->out;
            c->out = sj < 0 ? SEG_KEPT : SEG_REMOVED;
        } else if (si < 0 || sj < 0) {
            v->out = SEG_KEPT;
        } else if (si > 0 || sj > 0) {
            v->out = SEG_REMOVED;
        } else {
            int d = along(k, &fr, e->verts[vs[j]], NULL, e->verts[vs[i]], NULL);
            if (d == 0)
                return facet_error(k, f, "an edge in the plane has zero length");
            v->out = d < 0 ? SEG_KEPT : SEG_REMOVED;
        }
    }
    for (uint32_t a = 0; a < nn; a++)
        if (!k->nodes[a].crossing)
            k->nodes[a].in = k->nodes[a ? a - 1 : nn - 1].out;

    size_t nev = 0;
    for (uint32_t a = 0; a < nn; a++) {
        node *v = &k->nodes[a];
        event evt = {0, a, NULL, NULL, -1};
        if (v->crossing) {
            uint32_t j = v->i + 1 < n ? v->i + 1 : 0;
            evt.p0 = e->verts[vs[v->i]];
            evt.p1 = e->verts[vs[j]];
        } else {
            if (geo_mw_side(w, vs[v->i], k->plane) != 0)
                continue;
            evt.p0 = e->verts[vs[v->i]];
        }
        if (v->in == SEG_REMOVED && v->out == SEG_KEPT) {
            evt.type = EV_ENTRY;
        } else if (v->in == SEG_KEPT && v->out == SEG_REMOVED) {
            evt.type = EV_EXIT;
        } else {
            uint32_t ip = v->i ? v->i - 1 : n - 1, in = v->i + 1 < n ? v->i + 1 : 0;
            int sp = geo_mw_side(w, vs[ip], k->plane), sn = geo_mw_side(w, vs[in], k->plane);
            if (sp == 0 || sn == 0 || sp != sn)
                continue;
            int turn = fr.osign * geo_orient2d_proj(e->verts[vs[ip]], e->verts[vs[v->i]],
                                                    e->verts[vs[in]], fr.drop);
            if (turn >= 0)
                continue;
            evt.type = sp < 0 ? EV_DOUBLE : EV_PASS;
        }
        int r = insert_event(k, &fr, &nev, &evt);
        if (r < 0)
            return r;
    }

    int32_t open = -1;
    for (size_t s = 0; s < nev; s++) {
        event *x = &k->ev[s];
        k->nodes[x->node].ev = (int32_t)s;
        switch (x->type) {
        case EV_ENTRY:
            if (open >= 0)
                return facet_error(k, f, "two entries in a row along the section");
            open = (int32_t)s;
            break;
        case EV_PASS:
            if (open < 0)
                return facet_error(k, f, "a reflex vertex outside the section");
            break;
        case EV_EXIT:
        case EV_DOUBLE:
            if (open < 0)
                return facet_error(k, f, "an exit before any entry along the section");
            x->partner = open;
            open = x->type == EV_DOUBLE ? (int32_t)s : -1;
            break;
        }
    }
    if (open >= 0 || nev == 0)
        return facet_error(k, f, "the section does not close");

    if (grow((void **)&k->used, &k->capused, nev, 1) < 0)
        return -ENOMEM;
    memset(k->used, 0, nev);
    size_t np = 0;
    uint32_t pieces = 0;
    size_t guard = 0, limit = 4 * ((size_t)nn + nev) + 16;
    if (grow((void **)&k->pstart, &k->cappstart, 1, sizeof *k->pstart) < 0)
        return -ENOMEM;
    k->pstart[0] = 0;
    for (size_t s0 = 0; s0 < nev; s0++) {
        const event *start = &k->ev[s0];
        if ((start->type != EV_ENTRY && start->type != EV_DOUBLE) || k->used[s0])
            continue;
        size_t p0 = np;
        uint32_t cur = start->node;
        for (;;) {
            k->used[k->nodes[cur].ev] = 1;
            uint32_t a = cur;
            for (;;) {
                if (++guard > limit)
                    return facet_error(k, f, "the pieces do not close");
                if (piece_push(k, &np, k->nodes[a].vout) < 0)
                    return -ENOMEM;
                if (a != cur && k->nodes[a].ev >= 0) {
                    uint8_t ty = k->ev[k->nodes[a].ev].type;
                    if (ty == EV_EXIT || ty == EV_DOUBLE)
                        break;
                }
                a = a + 1 < nn ? a + 1 : 0;
                if (k->nodes[a].in != SEG_KEPT)
                    return facet_error(k, f, "the kept boundary is interrupted");
            }
            int32_t x = k->nodes[a].ev, en = k->ev[x].partner;
            for (int32_t s = x; s > en; s--) {
                uint32_t hi = k->nodes[k->ev[s].node].vout;
                uint32_t lo = k->nodes[k->ev[s - 1].node].vout;
                if (push_cap(k, lo, hi) < 0)
                    return -ENOMEM;
                if (s - 1 > en && piece_push(k, &np, lo) < 0)
                    return -ENOMEM;
            }
            cur = k->ev[en].node;
            if (cur == start->node)
                break;
            if (k->used[en])
                return facet_error(k, f, "an entry is reached twice");
        }
        if (np - p0 < 3)
            return facet_error(k, f, "a piece with fewer than 3 vertices");
        pieces++;
        if (grow((void **)&k->pstart, &k->cappstart, pieces + 1, sizeof *k->pstart) < 0)
            return -ENOMEM;
        k->pstart[pieces] = (uint32_t)np;
    }
    for (size_t s = 0; s < nev; s++)
        if (!k->used[s] && (k->ev[s].type == EV_ENTRY || k->ev[s].type == EV_DOUBLE))
            return facet_error(k, f, "an entry is not on any piece");
    return (int)pieces;
}

/* Does a live facet other than skip have the directed edge a→b? */
static bool has_edge(const geo_edit *e, uint32_t a, uint32_t b, uint32_t skip)
{
    const uint32_t *l = geo_edit_vf(e, a);
    for (uint32_t i = 0; i < geo_edit_vn(e, a); i++) {
        uint32_t g = l[i];
        if (g == skip || !e->falive[g])
            continue;
        const uint32_t *vs = geo_edit_fv(e, g);
        uint32_t n = geo_edit_fn(e, g);
        for (uint32_t j = 0; j < n; j++)
            if (vs[j] == a && vs[j + 1 < n ? j + 1 : 0] == b)
                return true;
    }
    return false;
}

/* The region above π that touches the main facet: facets listed in
 * w->buf_b[0 .. *ret_n), marked in fmark; main included first. */
static int find_region(geo_mw *w, uint32_t main, const double *plane,
                       uint32_t *ret_n, geo_err *err)
{
    geo_edit *e = w->e;
    uint32_t nq = 0, head = 0, nr = 0;
    if (geo_mw_grow(&w->buf_b, &w->cap_b, 16) < 0)
        return -ENOMEM;
    w->fmark[main] = w->gen;
    w->buf_b[nr++] = main;
    uint32_t m = geo_edit_fn(e, main);
    for (uint32_t i = 0; i < m; i++) {
        uint32_t v = geo_edit_fv(e, main)[i];
        int s = geo_mw_side(w, v, plane);
        if (s < 0)
            return geo_err_set(err, -EINVAL, "vertices[%u]: below the plane "
                               "after lifting", v);
        if (s > 0 && w->vmark[v] != w->gen) {
            w->vmark[v] = w->gen;
            if (geo_mw_grow(&w->buf_a, &w->cap_a, (size_t)nq + 1) < 0)
                return -ENOMEM;
            w->buf_a[nq++] = v;
        }
    }
    while (head < nq) {
        uint32_t v = w->buf_a[head++];
        for (uint32_t i = 0; i < geo_edit_vn(e, v); i++) {
            uint32_t g = geo_edit_vf(e, v)[i];
            if (w->fmark[g] == w->gen)
                continue;
            w->fmark[g] = w->gen;
            if (geo_mw_grow(&w->buf_b, &w->cap_b, (size_t)nr + 1) < 0)
                return -ENOMEM;
            w->buf_b[nr++] = g;
            for (uint32_t j = 0; j < geo_edit_fn(e, g); j++) {
                uint32_t u = geo_edit_fv(e, g)[j];
                if (w->vmark[u] == w->gen || geo_mw_side(w, u, plane) <= 0)
                    continue;
                w->vmark[u] = w->gen;
                if (geo_mw_grow(&w->buf_a, &w->cap_a, (size_t)nq + 1) < 0)
                    return -ENOMEM;
                w->buf_a[nq++] = u;
            }
        }
    }
    *ret_n = nr;
    return 0;
}

typedef struct far_check {
    geo_mw *w;
    const double *plane;
    uint32_t hit;
} far_check;

static bool far_visit(void *user, uint32_t f)
{
    far_check *c = user;
    geo_mw *w = c->w;
    geo_edit *e = w->e;
    if (f >= e->nfacets || !e->falive[f] || w->fmark[f] == w->gen)
        return true;
    for (uint32_t j = 0; j < geo_edit_fn(e, f); j++)
        if (geo_mw_side(w, geo_edit_fv(e, f)[j], c->plane) > 0) {
            c->hit = f;
            return false;
        }
    return true;
}

int geo_mw_cut(geo_mw *w, uint32_t main, const double plane[4],
               geo_merge_group *rep, geo_err *err)
{
    (void)rep;
    geo_edit *e = w->e;
    if (geo_mw_stamp(w) < 0)
        return geo_err_set(err, -ENOMEM, "out of memory");
    geo_mw_side_reset(w);
    uint32_t nr = 0;
    int r = find_region(w, main, plane, &nr, err);
    if (r < 0)
        return r == -ENOMEM ? geo_err_set(err, r, "out of memory") : r;

    /* §3.4 item 1: no second component */
    far_check fc = {w, plane, GEO_NONE};
    if (w->bvh)
        geo_bvh_query_plane(w->bvh, plane, far_visit, &fc);
    for (uint32_t i = 0; i < w->nextra && fc.hit == GEO_NONE; i++)
        far_visit(&fc, w->extra[i]);
    if (fc.hit != GEO_NONE)
        return geo_err_set(err, -EINVAL, "facets[%u]: the plane also cuts "
                           "the model here, away from the group (the section "
                           "would have more than one component)", fc.hit);

    cutter k;
    memset(&k, 0, sizeof k);
    k.w = w;
    k.e = e;
    k.plane = plane;
    k.err = err;
    size_t corners = 0;
    for (uint32_t i = 0; i < nr; i++)
        corners += geo_edit_fn(e, w->buf_b[i]);
    emap seen = {0};
    uint32_t *cyc = NULL;
    uint32_t (*inpl)[2] = NULL;
    size_t ninpl = 0, capinpl = 0, capcyc = 0;
    if (emap_init(&k.xmap, corners) < 0 || emap_init(&seen, corners) < 0) {
        r = geo_err_set(err, -ENOMEM, "out of memory");
        goto done;
    }

    /* edges lying in π of the region's facets (before any change) */
    for (uint32_t i = 0; i < nr; i++) {
        uint32_t f = w->buf_b[i], n = geo_edit_fn(e, f);
        for (uint32_t j = 0; j < n; j++) {
            const uint32_t *vs = geo_edit_fv(e, f);
            uint32_t a = vs[j], b = vs[j + 1 < n ? j + 1 : 0];
            if (geo_mw_side(w, a, plane) != 0 || geo_mw_side(w, b, plane) != 0)
                continue;
            size_t s = emap_slot(&seen, ekey(a, b));
            if (seen.val[s] != GEO_NONE)
                continue;
            seen.key[s] = ekey(a, b);
            seen.val[s] = 1;
            if (grow((void **)&inpl, &capinpl, ninpl + 1, sizeof *inpl) < 0) {
                r = geo_err_set(err, -ENOMEM, "out of memory");
                goto done;
            }
            inpl[ninpl][0] = a;
            inpl[ninpl][1] = b;
            ninpl++;
        }
    }

    /* the region's facets: removed whole, or cut into kept pieces */
    for (uint32_t i = 1; i < nr; i++) {
        uint32_t f = w->buf_b[i], n = geo_edit_fn(e, f);
        bool neg = false;
        for (uint32_t j = 0; j < n && !neg; j++)
            neg = geo_mw_side(w, geo_edit_fv(e, f)[j], plane) < 0;
        if (!neg) {
            if (geo_edit_kill_facet(e, f) < 0) {
                r = geo_err_set(err, -ENOMEM, "out of memory");
                goto done;
            }
            continue;
        }
        if (grow((void **)&cyc, &capcyc, n, sizeof *cyc) < 0) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            goto done;
        }
        memcpy(cyc, geo_edit_fv(e, f), n * sizeof *cyc);
        int np = cut_facet(&k, f, cyc, n);
        if (np < 0) {
            r = np == -ENOMEM ? geo_err_set(err, np, "out of memory") : np;
            goto done;
        }
        double pl[4];
        memcpy(pl, e->planes[f], sizeof pl);
        for (int p = 0; p < np; p++) {
            const uint32_t *pc = k.piece + k.pstart[p];
            uint32_t len = k.pstart[p + 1] - k.pstart[p];
            int64_t g = p == 0 ? geo_edit_set_facet(e, f, pc, len)
                               : geo_edit_add_facet(e, pc, len, pl);
            if (g < 0) {
                r = geo_err_set(err, (int)g, "out of memory");
                goto done;
            }
        }
    }

    /* edges in π join the section where one side is kept and the other
     * not (the main facet counts as not kept: it is being replaced) */
    for (size_t i = 0; i < ninpl; i++) {
        uint32_t a = inpl[i][0], b = inpl[i][1];
        bool ab = has_edge(e, a, b, main), ba = has_edge(e, b, a, main);
        if (ab && !ba)
            r = push_cap(&k, b, a);
        else if (ba && !ab)
            r = push_cap(&k, a, b);
        if (r < 0) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            goto done;
        }
    }

    /* the section: one closed chain (§3.4 item 1) */
    if (k.ncap < 3) {
        r = geo_err_set(err, -EINVAL, "the section has %zu edges", k.ncap);
        goto done;
    }
    {
        emap next;
        if (emap_init(&next, k.ncap) < 0) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            goto done;
        }
        for (size_t i = 0; i < k.ncap && r == 0; i++) {
            uint64_t key = k.cap[i][0];
            size_t s = emap_slot(&next, key);
            if (next.val[s] != GEO_NONE)
                r = geo_err_set(err, -EINVAL, "vertices[%u]: the section "
                                "touches itself here", k.cap[i][0]);
            next.key[s] = key;
            next.val[s] = (uint32_t)i;
        }
        size_t len = 0;
        if (r == 0 && grow((void **)&cyc, &capcyc, k.ncap, sizeof *cyc) < 0)
            r = geo_err_set(err, -ENOMEM, "out of memory");
        for (size_t i = 0; r == 0;) {
            cyc[len++] = k.cap[i][0];
            size_t s = emap_slot(&next, k.cap[i][1]);
            if (next.val[s] == GEO_NONE) {
                r = geo_err_set(err, -EINVAL, "vertices[%u]: the section "
                                "does not close here", k.cap[i][1]);
                break;
            }
            i = next.val[s];
            if (i == 0)
                break;
            if (len >= k.ncap) {
                r = geo_err_set(err, -EINVAL, "the section does not close");
                break;
            }
        }
        emap_free(&next);
        if (r == 0 && len != k.ncap)
            r = geo_err_set(err, -EINVAL, "the section has more than one "
                            "component (%zu of its %zu edges in the first)",
                            len, k.ncap);
        if (r < 0)
            goto done;
        if (geo_edit_set_facet(e, main, cyc, (uint32_t)len) < 0 ||
            geo_edit_set_plane(e, main, plane) < 0) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            goto done;
        }
    }
    double area[3];
    geo_edit_area_vector(e, main, area);
    if (!(geo_vdot(area, plane) > 0)) {
        r = geo_err_set(err, -EINVAL, "the section runs against the plane's "
                        "normal (it would need a hole)");
        goto done;
    }

    /* on-plane vertices left in two facets lie on the straight edge
     * between them: dropped (as geo_cut's drop_hanging) */
    for (uint32_t i = 0; i < geo_edit_fn(e, main);) {
        uint32_t v = geo_edit_fv(e, main)[i];
        if (geo_edit_vn(e, v) != 2 || v >= w->capv) {
            i++;
            continue;
        }
        const uint32_t *l = geo_edit_vf(e, v);
        uint32_t other = l[0] == main ? l[1] : l[0];
        uint32_t po = geo_edit_find(e, other, v);
        if (geo_edit_remove(e, main, i) < 0 || geo_edit_remove(e, other, po) < 0) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            goto done;
        }
        if (geo_edit_fn(e, other) < 3 || geo_edit_fn(e, main) < 3) {
            r = geo_err_set(err, -EINVAL, "facets[%u]: degenerates when the "
                            "hanging vertex %u is removed", other, v);
            goto done;
        }
    }
    r = 0;
done:
    emap_free(&k.xmap);
    emap_free(&seen);
    free(k.cap), free(k.nodes), free(k.ev), free(k.piece), free(k.pstart);
    free(k.used), free(cyc), free(inpl);
    return r;
}
