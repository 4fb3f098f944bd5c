/* merge_cut.c — the last step of a merge: the cut of the model by the
 * merged facet's plane in the form of Palachev 2012, §3.4, done locally.
 *
 * What it computes is what geo_cut (lib/cut/cut.c) computes with
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
 * Each facet crossing π is cut by the same code as in geo_cut,
 * lib/cut/cut_facet.c (nodes, events on l = facet ∩ π sorted exactly, the
 * direction sweep, the pieces by cycles B and A; every segment of l
 * walked by cycle A is, reversed, an edge of the section); what this file
 * keeps is what differs: which facets are visited (the cap), the sides
 * (below), the crossing vertices (one per crossed edge, created on first
 * use in an edge map, shared by its two facets), the proof of one
 * component and the assembly of the new main facet. Edges lying in π join
 * the section where the facet on one side of them is kept and the other
 * is not (§3.4 item 2: the main facet's own edges in π enter the section
 * this way, in its counter-clockwise order). Sides are decided once: 0
 * within geo_poly_eps of π (the lifted points lie on π to rounding), else
 * the sign; they are read into a per-facet array for the shared code. */
#include "merge_impl.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "cut_facet.h"
#include "vec.h"

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
    geo_cutf cf;           /* the per-facet stages; cf.sec: section edges */
    int8_t *fside;         /* one facet's sides, in its order */
    uint32_t *fxv;         /* one facet's crossing vertices, by position */
    size_t capfside, capfxv;
    geo_err *err;
} cutter;

/* The new vertex on crossed edge a–b (created once). */
static int64_t crossing_vertex(cutter *k, uint32_t a, uint32_t b)
{
    size_t s = emap_slot(&k->xmap, ekey(a, b));
    if (k->xmap.val[s] != GEO_NONE)
        return k->xmap.val[s];
    double x[3];
    geo_cutf_crossing_point(k->plane, k->e->verts[a], k->e->verts[b], x);
    int64_t id = geo_edit_add_vertex(k->e, x);
    if (id < 0)
        return id;
    k->xmap.key[s] = ekey(a, b);
    k->xmap.val[s] = (uint32_t)id;
    return id;
}

static int facet_error(cutter *k, uint32_t f, const char *what)
{
    return geo_err_set(k->err, -EINVAL, "facets[%u]: %s while cutting by the "
                       "merged plane", f, what);
}

/* Cuts facet f (vertex cycle vs[0..n), copied by the caller) by the
 * shared stages (lib/cut/cut_facet.h) into its kept pieces: piece p is
 * k->cf.piece[pstart[p] .. pstart[p+1]). Section segments go to
 * k->cf.sec. The sides are the merge's cached ones; the crossing
 * vertices are created here, in the facet's order. Returns the number of
 * pieces or an error. */
static int cut_facet(cutter *k, uint32_t f, const uint32_t *vs, uint32_t n)
{
    double nf[3];
    geo_edit_area_vector(k->e, f, nf);
    if (geo_cutf_frame(&k->cf, nf) < 0)
        return facet_error(k, f, k->cf.why);
    if (geo_grow((void **)&k->fside, &k->capfside, n, 1) < 0 ||
        geo_grow((void **)&k->fxv, &k->capfxv, n, sizeof *k->fxv) < 0)
        return -ENOMEM;
    for (uint32_t i = 0; i < n; i++)
        k->fside[i] = (int8_t)geo_mw_side(k->w, vs[i], k->plane);
    for (uint32_t i = 0; i < n; i++) {
        uint32_t j = i + 1 < n ? i + 1 : 0;
        if (k->fside[i] * k->fside[j] >= 0)
            continue;
        int64_t x = crossing_vertex(k, vs[i], vs[j]);
        if (x < 0)
            return (int)x;
        k->fxv[i] = (uint32_t)x;
    }
    int np = geo_cutf_facet(&k->cf, (const double(*)[3])k->e->verts, vs,
                            k->fside, k->fxv, n);
    return np == -EINVAL ? facet_error(k, f, k->cf.why) : np;
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

/* -EINVAL when vertex v (above π) lies deeper above it than the
 * deviation bound: merging nearly coplanar facets cuts off slivers, and
 * a plane that would cut off more (the group on a saddle, its
 * surroundings rising above its plane) is not a merge but a cut through
 * the model. */
static int check_depth(const geo_mw *w, uint32_t v, const double *plane,
                       geo_err *err)
{
    double h = geo_plane_eval(plane, w->e->verts[v]);
    if (h > w->max_cut)
        return geo_err_set(err, -EINVAL, "vertices[%u]: the merged plane "
                           "would cut the model %.3g mm deep here, beyond "
                           "the deviation bound %.3g mm", v, h, w->max_cut);
    return 0;
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
            int r = check_depth(w, v, plane, err);
            if (r < 0)
                return r;
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
                int r = check_depth(w, u, plane, err);
                if (r < 0)
                    return r;
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
    k.cf.plane = plane;
    k.cf.frame = plane;
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
            if (geo_grow((void **)&inpl, &capinpl, ninpl + 1, sizeof *inpl) < 0) {
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
        if (geo_grow((void **)&cyc, &capcyc, n, sizeof *cyc) < 0) {
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
            const uint32_t *pc = k.cf.piece + k.cf.pstart[p];
            uint32_t len = k.cf.pstart[p + 1] - k.cf.pstart[p];
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
            r = geo_cutf_push_section(&k.cf, b, a);
        else if (ba && !ab)
            r = geo_cutf_push_section(&k.cf, a, b);
        if (r < 0) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            goto done;
        }
    }

    /* the section: one closed chain (§3.4 item 1) */
    if (k.cf.nsec < 3) {
        r = geo_err_set(err, -EINVAL, "the section has %zu edges", k.cf.nsec);
        goto done;
    }
    {
        emap next;
        if (emap_init(&next, k.cf.nsec) < 0) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            goto done;
        }
        for (size_t i = 0; i < k.cf.nsec && r == 0; i++) {
            uint64_t key = k.cf.sec[i][0];
            size_t s = emap_slot(&next, key);
            if (next.val[s] != GEO_NONE)
                r = geo_err_set(err, -EINVAL, "vertices[%u]: the section "
                                "touches itself here", k.cf.sec[i][0]);
            next.key[s] = key;
            next.val[s] = (uint32_t)i;
        }
        size_t len = 0;
        if (r == 0 && geo_grow((void **)&cyc, &capcyc, k.cf.nsec, sizeof *cyc) < 0)
            r = geo_err_set(err, -ENOMEM, "out of memory");
        for (size_t i = 0; r == 0;) {
            cyc[len++] = k.cf.sec[i][0];
            size_t s = emap_slot(&next, k.cf.sec[i][1]);
            if (next.val[s] == GEO_NONE) {
                r = geo_err_set(err, -EINVAL, "vertices[%u]: the section "
                                "does not close here", k.cf.sec[i][1]);
                break;
            }
            i = next.val[s];
            if (i == 0)
                break;
            if (len >= k.cf.nsec) {
                r = geo_err_set(err, -EINVAL, "the section does not close");
                break;
            }
        }
        emap_free(&next);
        if (r == 0 && len != k.cf.nsec)
            r = geo_err_set(err, -EINVAL, "the section has more than one "
                            "component (%zu of its %zu edges in the first)",
                            len, k.cf.nsec);
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
    geo_cutf_free(&k.cf);
    free(k.fside), free(k.fxv), free(cyc), free(inpl);
    return r;
}
