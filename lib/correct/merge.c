/* merge.c — merging facet groups (merge.h): the merge workspace, one
 * group's transaction (contour, plane, lift, cut, local check, commit or
 * rollback) and the public entry points.
 *
 * Invariant: between groups the edit holds a model that passed every
 * check; a group either commits whole or leaves no trace (rollback
 * restores the edit bit for bit). */
#include "merge_impl.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "topo.h"
#include "vec.h"

void geo_merge_opts_default(geo_merge_opts *o)
{
    o->plane = GEO_MERGE_PLANE_AREA;
    o->lift_order = GEO_LIFT_EVENT_HEIGHT;
    o->check = true;
    o->max_angle_deg = 60.0;
    o->max_deviation = 0;
    o->rel_deviation = 5e-4;
    o->views = 0;
    o->noise = 0;
    o->bevels = true;
    o->max_rounds = 16;
}

void geo_merge_report_clear(geo_merge_report *r)
{
    if (!r)
        return;
    free(r->groups);
    free(r->facets);
    free(r->moved);
    free(r->vmap);
    memset(r, 0, sizeof *r);
}

int geo_mw_grow(uint32_t **buf, uint32_t *cap, size_t need)
{
    if (need <= *cap)
        return 0;
    size_t c = *cap ? *cap : 64;
    while (c < need)
        c *= 2;
    if (c > UINT32_MAX)
        return -ENOMEM;
    uint32_t *b = realloc(*buf, c * sizeof *b);
    if (!b)
        return -ENOMEM;
    *buf = b;
    *cap = (uint32_t)c;
    return 0;
}

geo_mw *geo_mw_new(geo_edit *e, const geo_merge_opts *opts, geo_err *err)
{
    geo_mw *w = calloc(1, sizeof *w);
    if (!w) {
        geo_err_set(err, -ENOMEM, "out of memory");
        return NULL;
    }
    w->e = e;
    w->plane_mode = opts->plane;
    w->lift_order = opts->lift_order;
    w->check = opts->check;
    double lo[3] = {INFINITY, INFINITY, INFINITY};
    double hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t v = 0; v < e->nverts; v++)
        for (int k = 0; k < 3; k++)
            geo_minmax(e->verts[v][k], &lo[k], &hi[k]);
    double size = 0;
    if (e->nverts) {
        double d[3];
        geo_vsub(hi, lo, d);
        size = geo_vlen(d);
        for (int k = 0; k < 3; k++)
            w->origin[k] = 0.5 * (lo[k] + hi[k]);
    }
    w->eps = geo_eps_of_size(size);
    w->max_cut = opts->max_deviation > 0 ? opts->max_deviation
                                         : opts->rel_deviation * size;
    w->gen = 1;
    if (geo_mw_stamp(w) < 0) {
        geo_err_set(err, -ENOMEM, "out of memory");
        return geo_mw_free(w);
    }
    return w;
}

geo_mw *geo_mw_free(geo_mw *w)
{
    if (!w)
        return NULL;
    geo_bvh_free(w->bvh);
    free(w->slot_of), free(w->leaf_of), free(w->parent), free(w->extra);
    free(w->fmark), free(w->vmark), free(w->vmark2);
    free(w->vside_at), free(w->vside);
    free(w->buf_a), free(w->buf_b), free(w->buf_c);
    free(w);
    return NULL;
}

static int grow_stamps(uint32_t **a, uint32_t old, uint32_t cap)
{
    uint32_t *b = realloc(*a, (size_t)cap * sizeof *b);
    if (!b)
        return -ENOMEM;
    memset(b + old, 0, (size_t)(cap - old) * sizeof *b);
    *a = b;
    return 0;
}

int geo_mw_stamp(geo_mw *w)
{
    const geo_edit *e = w->e;
    if (e->nfacets + 1 > w->capf) {
        uint32_t c = e->nfacets + e->nfacets / 2 + 64;
        if (grow_stamps(&w->fmark, w->capf, c) < 0)
            return -ENOMEM;
        w->capf = c;
    }
    if (e->nverts + 1 > w->capv) {
        uint32_t c = e->nverts + e->nverts / 2 + 64;
        if (grow_stamps(&w->vmark, w->capv, c) < 0 ||
            grow_stamps(&w->vmark2, w->capv, c) < 0 ||
            grow_stamps(&w->vside_at, w->capv, c) < 0)
            return -ENOMEM;
        int8_t *s = realloc(w->vside, c);
        if (!s)
            return -ENOMEM;
        w->vside = s;
        w->capv = c;
    }
    w->gen++;
    return 0;
}

void geo_mw_side_reset(geo_mw *w)
{
    w->sgen++;
}

int geo_mw_side(geo_mw *w, uint32_t v, const double plane[4])
{
    if (w->vside_at[v] == w->sgen)
        return w->vside[v];
    double s = geo_plane_eval(plane, w->e->verts[v]);
    int8_t r = fabs(s) <= w->eps ? 0 : s > 0 ? 1 : -1;
    w->vside[v] = r;
    w->vside_at[v] = w->sgen;
    return r;
}

/* Volume of facet f's cycle cyc[0..n) with the positions before the
 * running transaction (saved positions where a vertex was saved). */
static double volume_before(const geo_edit *e, const uint32_t *cyc, uint32_t n,
                            const double *o)
{
    if (n < 3)
        return 0;
    double p[3][3], s = 0;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t v = cyc[i];
        const double *x = e->verts[v];
        if (v < e->txn_nverts && e->vstamp[v] == e->txn)
            for (size_t j = 0; j < e->nvsaved; j++)
                if (e->vsaved[j].id == v) {
                    x = e->vsaved[j].pos;
                    break;
                }
        if (i == 0) {
            geo_vsub(x, o, p[0]);
        } else {
            geo_vsub(x, o, p[2]);
            if (i >= 2) {
                double c[3];
                geo_vcross(p[1], p[2], c);
                s += geo_vdot(p[0], c);
            }
            memcpy(p[1], p[2], sizeof p[1]);
        }
    }
    return s / 6.0;
}

/* The volume change of the running transaction: over the facets it
 * changed and the facets holding a vertex it saved, after minus before. */
static double txn_volume_change(geo_mw *w)
{
    geo_edit *e = w->e;
    double dv = 0;
    w->gen++;
    for (size_t i = 0; i < e->nfsaved; i++) {
        const geo_edit_fsave *s = &e->fsaved[i];
        w->fmark[s->id] = w->gen;
        if (s->alive)
            dv -= volume_before(e, e->arena + s->s.off, s->s.n, w->origin);
        if (e->falive[s->id])
            dv += geo_edit_facet_volume(e, s->id, w->origin);
    }
    for (uint32_t f = e->txn_nfacets; f < e->nfacets; f++)
        if (e->falive[f])
            dv += geo_edit_facet_volume(e, f, w->origin);
    for (size_t i = 0; i < e->nvsaved; i++) {
        uint32_t v = e->vsaved[i].id;
        for (uint32_t j = 0; j < geo_edit_vn(e, v); j++) {
            uint32_t f = geo_edit_vf(e, v)[j];
            if (f >= e->txn_nfacets || w->fmark[f] == w->gen)
                continue;
            w->fmark[f] = w->gen;
            dv += geo_edit_facet_volume(e, f, w->origin);
            dv -= volume_before(e, geo_edit_fv(e, f), geo_edit_fn(e, f), w->origin);
        }
    }
    return dv;
}

static void fail_group(geo_merge_group *rep, int r, const geo_err *gerr)
{
    rep->status = r;
    rep->facet = GEO_NONE;
    rep->out_facet = GEO_NONE;
    size_t n = strlen(gerr->msg);
    if (n >= sizeof rep->reason)
        n = sizeof rep->reason - 1;
    memcpy(rep->reason, gerr->msg, n);
    rep->reason[n] = 0;
}

int geo_mw_merge(geo_mw *w, const uint32_t *group, uint32_t n,
                 geo_merge_group *rep, geo_err *err)
{
    geo_edit *e = w->e;
    uint32_t first = rep->first, count = rep->count;
    memset(rep, 0, sizeof *rep);
    rep->first = first;
    rep->count = count;
    rep->facet = rep->out_facet = GEO_NONE;
    if (geo_mw_stamp(w) < 0)
        return geo_err_set(err, -ENOMEM, "out of memory");
    geo_err gerr = {{0}};
    geo_edit_begin(e);
    uint32_t main = GEO_NONE, ngv = 0;
    double plane[4];
    int r = geo_mw_contour(w, group, n, &main, &ngv, rep, &gerr);
    if (r == 0)
        r = geo_mw_plane(w, main, plane, &gerr);
    if (r == 0) {
        double dev = 0;
        for (uint32_t i = 0; i < ngv; i++)
            dev = fmax(dev, fabs(geo_plane_eval(plane, e->verts[w->buf_c[i]])));
        rep->dev_before = dev;
        memcpy(rep->plane, plane, sizeof plane);
        r = geo_mw_lift(w, main, plane, rep, &gerr);
    }
    if (r == 0)
        r = geo_mw_cut(w, main, plane, rep, &gerr);
    if (r == 0 && w->check)
        r = geo_mw_check(w, &gerr);
    if (r < 0) {
        geo_edit_rollback(e);
        fail_group(rep, r, &gerr);
        return geo_err_set(err, r, "%s", gerr.msg);
    }
    /* figures of the group */
    for (size_t i = 0; i < e->nvsaved; i++) {
        const geo_edit_vsave *s = &e->vsaved[i];
        if (geo_edit_vn(e, s->id) == 0)
            continue;
        double d = geo_vdist(s->pos, e->verts[s->id]);
        if (d > 0) {
            rep->moved++;
            rep->max_lift = fmax(rep->max_lift, d);
        }
    }
    for (uint32_t i = 0; i < geo_edit_fn(e, main); i++)
        rep->dev_after = fmax(rep->dev_after,
                              fabs(geo_plane_eval(plane, e->verts[geo_edit_fv(e, main)[i]])));
    rep->volume_change = txn_volume_change(w);
    rep->facet = main;
    uint32_t nt = geo_edit_ntouched_facets(e);
    uint32_t *touched = malloc(((size_t)nt + 1) * sizeof *touched);
    if (!touched) {
        geo_edit_rollback(e);
        rep->status = -ENOMEM;
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    nt = geo_edit_touched_facets(e, touched);
    geo_edit_commit(e);
    r = geo_mw_world_update(w, touched, nt);
    free(touched);
    if (r < 0)
        return geo_err_set(err, r, "out of memory");
    return 0;
}

/* ---- report helpers ---------------------------------------------------- */

int geo_merge_report_add(geo_merge_report *rep, const uint32_t *facets,
                         uint32_t n, geo_merge_group **ret)
{
    geo_merge_group *g = realloc(rep->groups, ((size_t)rep->ngroups + 1) *
                                                  sizeof *g);
    if (!g)
        return -ENOMEM;
    rep->groups = g;
    uint32_t *f = realloc(rep->facets, ((size_t)rep->nfacets_listed + n + 1) *
                                           sizeof *f);
    if (!f)
        return -ENOMEM;
    rep->facets = f;
    memcpy(f + rep->nfacets_listed, facets, n * sizeof *f);
    geo_merge_group *x = &g[rep->ngroups++];
    memset(x, 0, sizeof *x);
    x->first = rep->nfacets_listed;
    x->count = n;
    x->facet = x->out_facet = GEO_NONE;
    rep->nfacets_listed += n;
    *ret = x;
    return 0;
}

int geo_merge_report_finish(geo_merge_report *rep, const geo_edit *e,
                            const double (*in_verts)[3], uint32_t nin,
                            geo_poly *out)
{
    uint32_t *vmap = malloc(((size_t)e->nverts + 1) * sizeof *vmap);
    uint32_t *fmap = malloc(((size_t)e->nfacets + 1) * sizeof *fmap);
    if (!vmap || !fmap || geo_edit_to_poly(e, out, vmap, fmap) < 0) {
        free(vmap), free(fmap);
        return -ENOMEM;
    }
    rep->merged = rep->failed = 0;
    for (uint32_t i = 0; i < rep->ngroups; i++) {
        geo_merge_group *g = &rep->groups[i];
        if (g->status == 0) {
            rep->merged++;
            g->out_facet = g->facet < e->nfacets ? fmap[g->facet] : GEO_NONE;
        } else {
            rep->failed++;
        }
    }
    free(rep->moved);
    rep->moved = NULL;
    rep->nmoved = 0;
    uint32_t cnt = 0;
    for (uint32_t v = 0; v < nin && v < e->nverts; v++)
        cnt += vmap[v] != GEO_NONE && memcmp(in_verts[v], e->verts[v], 24) != 0;
    if (cnt) {
        rep->moved = malloc(cnt * sizeof *rep->moved);
        if (!rep->moved) {
            free(vmap), free(fmap);
            return -ENOMEM;
        }
        for (uint32_t v = 0; v < nin && v < e->nverts; v++) {
            if (vmap[v] == GEO_NONE || memcmp(in_verts[v], e->verts[v], 24) == 0)
                continue;
            geo_moved_vertex *m = &rep->moved[rep->nmoved++];
            m->vertex = vmap[v];
            geo_vsub(e->verts[v], in_verts[v], m->by);
        }
    }
    free(rep->vmap);
    rep->vmap = malloc(((size_t)nin + 1) * sizeof *rep->vmap);
    if (!rep->vmap) {
        free(vmap), free(fmap);
        return -ENOMEM;
    }
    for (uint32_t v = 0; v < nin; v++)
        rep->vmap[v] = v < e->nverts ? vmap[v] : GEO_NONE;
    rep->vertices_after = out->nverts;
    rep->facets_after = out->nfacets;
    rep->volume_after = geo_poly_volume(out);
    free(vmap), free(fmap);
    return 0;
}

/* ---- entry points ------------------------------------------------------- */

typedef struct session {
    geo_edit *e;
    geo_mw *w;
    double (*in_verts)[3];
    uint32_t nin;
} session;

/* Opens a session on a copy of p; world: with the index of its facets
 * that merges are checked against (geo_mw_world_build). t: p's topology,
 * or NULL to build it (the indices are then checked too). */
static int session_open(session *s, const geo_poly *p, const geo_topo *t,
                        const geo_merge_opts *o, bool world,
                        geo_merge_report *rep, geo_err *err)
{
    memset(s, 0, sizeof *s);
    int r = 0;
    geo_topo *own = NULL;
    if (!t && !(t = own = geo_topo_build_checked(p, &r, err)))
        return r;
    bool ok = geo_topo_is_closed_manifold(t);
    geo_topo_free(own);
    if (!ok)
        return geo_err_set(err, -EINVAL, "the model is not a closed oriented "
                           "manifold");
    s->e = geo_edit_from_poly(p, err);
    if (!s->e)
        return -ENOMEM;
    s->w = geo_mw_new(s->e, o, err);
    s->in_verts = malloc(((size_t)p->nverts + 1) * sizeof *s->in_verts);
    if (!s->w || !s->in_verts) {
        geo_mw_free(s->w);
        geo_edit_free(s->e);
        free(s->in_verts);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    memcpy(s->in_verts, p->verts, (size_t)p->nverts * sizeof *p->verts);
    s->nin = p->nverts;
    rep->vertices_before = p->nverts;
    rep->facets_before = p->nfacets;
    rep->volume_before = geo_poly_volume(p);
    if (world && (r = geo_mw_world_build(s->w, err)) < 0) {
        geo_mw_free(s->w);
        geo_edit_free(s->e);
        free(s->in_verts);
        return r;
    }
    return 0;
}

static void session_close(session *s)
{
    geo_mw_free(s->w);
    geo_edit_free(s->e);
    free(s->in_verts);
}

/* Writes the session's model into p (on success only) and finishes the
 * report. */
static int session_finish(session *s, geo_poly *p, geo_merge_report *rep,
                          geo_err *err)
{
    geo_poly *out = geo_poly_new();
    bool any = false;
    for (uint32_t i = 0; i < rep->ngroups; i++)
        any |= rep->groups[i].status == 0;
    if (!out || geo_merge_report_finish(rep, s->e, (const double(*)[3])s->in_verts,
                                        s->nin, out) < 0 ||
        (any && geo_poly_assign(p, out) < 0)) {
        geo_poly_free(out);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    rep->statement_violations = s->w->statement_violations;
    if (!any) {
        /* nothing merged: p stays exactly as it was (not even renumbered) */
        for (uint32_t v = 0; v < s->nin; v++)
            rep->vmap[v] = v;
        free(rep->moved);
        rep->moved = NULL;
        rep->nmoved = 0;
        rep->vertices_after = p->nverts;
        rep->facets_after = p->nfacets;
        rep->volume_after = rep->volume_before;
    }
    geo_poly_free(out);
    return 0;
}

/* The end of a merge whose work so far returned r: the session finished
 * into p when r is 0, then closed; the report is cleared on failure, the
 * caller's local one (when it passed none) always. */
static int session_end(session *s, int r, geo_poly *p, geo_merge_report *rep,
                       geo_merge_report *local, geo_err *err)
{
    if (r == 0)
        r = session_finish(s, p, rep, err);
    session_close(s);
    if (r < 0)
        geo_merge_report_clear(rep);
    geo_merge_report_clear(local);
    return r;
}

/* The set-up of every entry point: the options (opts, or the defaults)
 * into *o, *rep zeroed (callers may hand in an uninitialised report), the
 * session opened on p; for the automatic grouping also the options
 * checked and the grouping criteria *c (angle, deviation bound, the view
 * step from o->views or read off the model), recorded in *rep. On error
 * nothing is left open and *rep holds nothing. t: as session_open's. */
static int session_begin(session *s, const geo_poly *p, const geo_topo *t,
                         const geo_merge_opts *opts, bool automatic,
                         bool world, geo_merge_opts *o, geo_merge_report *rep,
                         geo_group_crit *c, geo_err *err)
{
    if (opts)
        *o = *opts;
    else
        geo_merge_opts_default(o);
    memset(rep, 0, sizeof *rep);
    if (automatic &&
        (!(o->max_angle_deg > 0 && o->max_angle_deg < 90) ||
         !(o->max_deviation >= 0) || !(o->rel_deviation >= 0) ||
         isnan(o->noise)))
        return geo_err_set(err, -EINVAL, "max_angle_deg must be in (0, 90) "
                           "and the deviations non-negative");
    int r = session_open(s, p, t, o, world, rep, err);
    if (r < 0 || !automatic) {
        if (r < 0)
            geo_merge_report_clear(rep);
        return r;
    }
    *c = (geo_group_crit){cos(o->max_angle_deg * M_PI / 180.0),
                          geo_merge_max_deviation(o, p), 0, 0};
    uint32_t views = o->views;
    if (views == 0 && geo_merge_view_grid(p, &views, NULL) < 0) {
        session_close(s);
        geo_merge_report_clear(rep);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    c->step = views ? M_PI / views : 0;
    rep->views = views;
    rep->max_dev = c->max_dev;
    return 0;
}

int geo_merge_groups(geo_poly *p, uint32_t ngroups, const uint32_t *gstart,
                     const uint32_t *gfacets, const geo_merge_opts *opts,
                     const geo_ctx *ctx, geo_merge_report *report,
                     geo_err *err)
{
    for (uint32_t k = 0; k < gstart[ngroups]; k++)
        if (gfacets[k] >= p->nfacets)
            return geo_err_set(err, -EINVAL, "groups: facet %u out of range "
                               "(%u facets)", gfacets[k], p->nfacets);
    geo_merge_opts o;
    geo_merge_report local = {0}, *rep = report ? report : &local;
    session s;
    int r = session_begin(&s, p, NULL, opts, false, true, &o, rep, NULL, err);
    if (r < 0)
        return r;
    for (uint32_t g = 0; g < ngroups && r == 0; g++) {
        if ((r = geo_ctx_progress(ctx, (double)g / (ngroups ? ngroups : 1))) < 0) {
            r = geo_err_set(err, -ECANCELED, "merge canceled");
            break;
        }
        geo_merge_group *gr;
        uint32_t n = gstart[g + 1] - gstart[g];
        if (geo_merge_report_add(rep, gfacets + gstart[g], n, &gr) < 0) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            break;
        }
        geo_err gerr;
        r = geo_mw_merge(s.w, gfacets + gstart[g], n, gr, &gerr);
        if (r == -EINVAL)
            r = 0;
        else if (r < 0)
            geo_err_set(err, r, "%s", gerr.msg);
    }
    return session_end(&s, r, p, rep, &local, err);
}

int geo_merge(geo_poly *p, const uint32_t *group, uint32_t n,
                     const geo_merge_opts *opts, const geo_ctx *ctx,
                     geo_merge_report *report, geo_err *err)
{
    uint32_t gstart[2] = {0, n};
    geo_merge_report local = {0}, *rep = report ? report : &local;
    int r = geo_merge_groups(p, 1, gstart, group, opts, ctx, rep, err);
    if (r == 0 && rep->ngroups == 1 && rep->groups[0].status < 0) {
        r = geo_err_set(err, rep->groups[0].status, "%s",
                        rep->groups[0].reason);
    }
    geo_merge_report_clear(&local);
    return r;
}

double geo_merge_max_deviation(const geo_merge_opts *o, const geo_poly *p)
{
    return o->max_deviation > 0 ? o->max_deviation
                                : o->rel_deviation * geo_poly_size(p);
}


int geo_merge_surface_noise(const geo_poly *p, const geo_topo *t,
                            const geo_merge_opts *opts, const geo_ctx *ctx,
                            double *ret, geo_err *err)
{
    geo_merge_opts o;
    geo_merge_report rep;
    session s;
    geo_group_crit c;
    /* the groups only: no merge, so no index of the facets to check one */
    int r = session_begin(&s, p, t, opts, true, false, &o, &rep, &c, err);
    if (r < 0)
        return r;
    r = geo_mw_surface_noise(s.w, &c, ctx, ret);
    if (r < 0)
        geo_err_set(err, r, r == -ECANCELED ? "canceled" : "out of memory");
    session_close(&s);
    geo_merge_report_clear(&rep);
    return r;
}

int geo_merge_auto(geo_poly *p, const geo_merge_opts *opts,
                   const geo_ctx *ctx, geo_merge_report *report,
                   geo_err *err)
{
    geo_merge_opts o;
    geo_merge_report local = {0}, *rep = report ? report : &local;
    session s;
    geo_group_crit c;
    int r = session_begin(&s, p, NULL, opts, true, true, &o, rep, &c, err);
    if (r < 0)
        return r;
    if (o.noise > 0)
        c.noise = o.noise;
    else if (o.noise == 0 &&
             (r = geo_mw_surface_noise(s.w, &c, ctx, &c.noise)) < 0)
        r = geo_err_set(err, r, r == -ECANCELED ? "merge canceled"
                                                : "out of memory");
    rep->noise = c.noise;
    uint32_t rounds = o.max_rounds ? o.max_rounds : 1;
    bool bevel_done = !o.bevels;
    for (uint32_t k = 0; k < rounds && r == 0; k++) {
        uint32_t merged = 0;
        r = geo_mw_auto_round(s.w, &c, ctx, (double)k / rounds,
                              (double)(k + 1) / rounds, rep, &merged, err);
        rep->rounds++;
        if (r == 0 && merged == 0 && !bevel_done) {
            /* the rounds have converged: the bevel strips, once; the
             * rounds resume when any was merged */
            r = geo_mw_bevel_pass(s.w, &c, ctx, rep, &merged, err);
            rep->bevels += merged;
            bevel_done = true;
        }
        if (merged == 0)
            break;
        if (r == 0 && geo_edit_gc(s.e) < 0)
            r = geo_err_set(err, -ENOMEM, "out of memory");
    }
    return session_end(&s, r, p, rep, &local, err);
}
