/* clusters.c — collapsing heaps of vertices joined by short edges
 * (clusters.h). Invariant: p is only replaced by a candidate that passed
 * geo_inspect as valid; every attempt starts again from the input with
 * fewer clusters, so a rolled-back cluster leaves no trace. */
#include "clusters.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "plane.h"
#include "replanar.h"
#include "stats.h"
#include "topo.h"
#include "uf.h"
#include "vec.h"

void geo_collapse_opts_default(geo_collapse_opts *o)
{
    o->radius = 0;
    o->rel_radius = 2e-4;
    o->max_move = 0;
    o->max_attempts = 4;
    o->max_steps = 400;
}

void geo_collapse_report_clear(geo_collapse_report *r)
{
    if (!r)
        return;
    free(r->cstart);
    free(r->cverts);
    free(r->cnew);
    free(r->vmap);
    memset(r, 0, sizeof *r);
}

/* The clusters of p: CSR lists, each sorted, clusters ordered by their
 * smallest vertex. 0 or -ENOMEM. */
static int find_clusters(const geo_poly *p, const geo_topo *t, double radius,
                         geo_collapse_report *rep)
{
    uint32_t nv = p->nverts, nc = geo_poly_ncorners(p);
    uint32_t *parent = malloc(((size_t)nv + 1) * sizeof *parent);
    uint32_t *size = calloc((size_t)nv + 1, sizeof *size);
    uint32_t *idx = malloc(((size_t)nv + 1) * sizeof *idx);
    if (!parent || !size || !idx) {
        free(parent), free(size), free(idx);
        return -ENOMEM;
    }
    for (uint32_t v = 0; v < nv; v++)
        parent[v] = v;
    for (uint32_t c = 0; c < nc; c++) {
        uint32_t m = t->mate[c];
        if (m != GEO_NONE && m < c)
            continue;
        uint32_t a = p->fidx[c], b = p->fidx[geo_topo_next(p, t, c)];
        if (geo_vdist(p->verts[a], p->verts[b]) < radius) {
            uint32_t ra = geo_uf_find(parent, a), rb = geo_uf_find(parent, b);
            if (ra != rb)
                parent[ra > rb ? ra : rb] = ra < rb ? ra : rb;
        }
    }
    uint32_t ncl = 0, total = 0;
    for (uint32_t v = 0; v < nv; v++)
        size[geo_uf_find(parent, v)]++;
    for (uint32_t v = 0; v < nv; v++) {
        idx[v] = GEO_NONE;
        if (parent[v] == v && size[v] >= 2) {
            idx[v] = ncl++;
            total += size[v];
        }
    }
    rep->cstart = calloc((size_t)ncl + 1, sizeof *rep->cstart);
    rep->cverts = malloc(((size_t)total + 1) * sizeof *rep->cverts);
    rep->cnew = malloc(((size_t)ncl + 1) * sizeof *rep->cnew);
    if (!rep->cstart || !rep->cverts || !rep->cnew) {
        free(parent), free(size), free(idx);
        return -ENOMEM;
    }
    for (uint32_t v = 0; v < nv; v++) {
        uint32_t r = geo_uf_find(parent, v);
        if (idx[r] != GEO_NONE)
            rep->cstart[idx[r] + 1]++;
    }
    for (uint32_t c = 0; c < ncl; c++)
        rep->cstart[c + 1] += rep->cstart[c];
    uint32_t *fill = size; /* reused as per-cluster fill counters */
    memset(fill, 0, ((size_t)nv + 1) * sizeof *fill);
    for (uint32_t v = 0; v < nv; v++) {
        uint32_t r = geo_uf_find(parent, v);
        if (idx[r] == GEO_NONE)
            continue;
        uint32_t c = idx[r];
        rep->cverts[rep->cstart[c] + fill[c]++] = v;
    }
    rep->clusters = ncl;
    free(parent), free(size), free(idx);
    return 0;
}

/* The point nearest (least squares) to the planes of the facets around
 * cluster c, pulled lightly towards its centroid. */
static void cluster_point(const geo_poly *p, const geo_topo *t,
                          const uint32_t *vs, uint32_t n, double ret[3])
{
    double cen[3] = {0, 0, 0};
    for (uint32_t i = 0; i < n; i++)
        geo_vadd(cen, p->verts[vs[i]], cen);
    geo_vscale(cen, 1.0 / n, cen);
    /* Σ n nᵀ (x − cen) = −Σ n (n·cen + d), plus λ (x − cen) = 0 */
    double m[3][3] = {{0}}, b[3] = {0, 0, 0};
    uint32_t nf = 0, seen[64];
    for (uint32_t i = 0; i < n; i++) {
        uint32_t v = vs[i];
        for (uint32_t k = t->vstart[v]; k < t->vstart[v + 1]; k++) {
            uint32_t f = t->corner_facet[t->vcorners[k]];
            bool have = false;
            for (uint32_t j = 0; j < nf && j < 64 && !have; j++)
                have = seen[j] == f;
            if (have)
                continue;
            if (nf < 64)
                seen[nf] = f;
            nf++;
            const double *pl = p->planes[f];
            double r = geo_plane_eval(pl, cen);
            for (int a = 0; a < 3; a++) {
                b[a] -= pl[a] * r;
                for (int c = 0; c < 3; c++)
                    m[a][c] += pl[a] * pl[c];
            }
        }
    }
    double lambda = 1e-3 * (nf ? nf : 1);
    for (int a = 0; a < 3; a++)
        m[a][a] += lambda;
    double x[3];
    if (geo_spd3_solve(m, b, x))
        geo_vadd(cen, x, ret);
    else
        memcpy(ret, cen, sizeof cen);
}

/* Removes from q's facets every vertex left in exactly two facets (it
 * lies on their common edge line up to the collapse's moves; the
 * validity rules want every vertex in ≥ 3 facets), repeatedly; a facet
 * left with fewer than three vertices goes (the check then finds what
 * that breaks). 0 or -ENOMEM. */
static int drop_hanging(geo_poly *q)
{
    uint32_t *cnt = malloc(((size_t)q->nverts + 1) * sizeof *cnt);
    if (!cnt)
        return -ENOMEM;
    for (bool again = true; again;) {
        again = false;
        memset(cnt, 0, (size_t)q->nverts * sizeof *cnt);
        for (uint32_t c = 0; c < geo_poly_ncorners(q); c++)
            cnt[q->fidx[c]]++;
        uint32_t w = 0;
        for (uint32_t f = 0; f < q->nfacets; f++) {
            uint32_t s0 = q->fstart[f], e0 = q->fstart[f + 1], start = w;
            for (uint32_t c = s0; c < e0; c++)
                if (cnt[q->fidx[c]] != 2)
                    q->fidx[w++] = q->fidx[c];
                else
                    again = true;
            q->fstart[f] = start;
            if (w - start < 3)
                w = start;
        }
        q->fstart[q->nfacets] = w;
        /* drop emptied facets */
        uint32_t k = 0;
        for (uint32_t f = 0; f < q->nfacets; f++) {
            uint32_t s0 = q->fstart[f], e0 = q->fstart[f + 1];
            if (e0 == s0)
                continue;
            q->fstart[k] = s0;
            memmove(q->planes[k], q->planes[f], sizeof q->planes[f]);
            k++;
        }
        q->fstart[k] = q->fstart[q->nfacets];
        q->nfacets = k;
    }
    free(cnt);
    return 0;
}

/* Keeps at most two active clusters on any facet: the re-planarization
 * cannot hold three fixed points of one facet that are not coplanar.
 * Clusters are taken in order; one that would be a facet's third is
 * left out. 0 or -ENOMEM. */
static int limit_per_facet(const geo_poly *p, const geo_topo *t,
                           const geo_collapse_report *rep, bool *active)
{
    uint8_t *cnt = calloc((size_t)p->nfacets + 1, 1);
    uint32_t *mark = malloc(((size_t)p->nfacets + 1) * sizeof *mark);
    if (!cnt || !mark) {
        free(cnt), free(mark);
        return -ENOMEM;
    }
    for (uint32_t f = 0; f < p->nfacets; f++)
        mark[f] = GEO_NONE;
    for (uint32_t c = 0; c < rep->clusters; c++) {
        if (!active[c])
            continue;
        bool ok = true;
        for (int pass = 0; pass < 2; pass++)
            for (uint32_t k = rep->cstart[c]; k < rep->cstart[c + 1]; k++) {
                uint32_t v = rep->cverts[k];
                for (uint32_t j = t->vstart[v]; j < t->vstart[v + 1]; j++) {
                    uint32_t f = t->corner_facet[t->vcorners[j]];
                    if (pass == 0) {
                        ok &= cnt[f] < 2 || mark[f] == c;
                        mark[f] = c;
                    } else if (ok && mark[f] == c) {
                        cnt[f]++;
                        mark[f] = GEO_NONE - 1; /* counted once */
                    }
                }
            }
        active[c] = ok;
        /* leave no mark equal to a later cluster's index */
        for (uint32_t k = rep->cstart[c]; k < rep->cstart[c + 1]; k++) {
            uint32_t v = rep->cverts[k];
            for (uint32_t j = t->vstart[v]; j < t->vstart[v + 1]; j++)
                mark[t->corner_facet[t->vcorners[j]]] = GEO_NONE;
        }
    }
    free(cnt), free(mark);
    return 0;
}

/* One candidate: the input with the active clusters collapsed. On
 * success *ret is the compacted candidate, ret_rep[c] the candidate
 * vertex of cluster c (GEO_NONE when inactive); returns 0, or 1 when
 * some cluster made a facet pass a vertex twice (deactivated), or
 * -ENOMEM. */
static int build_candidate(const geo_poly *p, const geo_topo *t,
                           const geo_collapse_report *rep, bool *active,
                           geo_poly **ret, uint32_t *ret_rep,
                           uint32_t *vmap)
{
    uint32_t nv = p->nverts;
    uint32_t *cl = malloc(((size_t)nv + 1) * sizeof *cl);
    geo_poly *q = geo_poly_new();
    uint32_t *buf = NULL;
    int r = -ENOMEM;
    if (!cl || !q || geo_poly_reserve(q, nv, p->nfacets, geo_poly_ncorners(p)) < 0)
        goto done;
    for (uint32_t v = 0; v < nv; v++) {
        cl[v] = GEO_NONE;
        vmap[v] = v;
    }
    memcpy(q->verts, p->verts, (size_t)nv * sizeof *p->verts);
    q->nverts = nv;
    for (uint32_t c = 0; c < rep->clusters; c++) {
        if (!active[c])
            continue;
        const uint32_t *vs = rep->cverts + rep->cstart[c];
        uint32_t n = rep->cstart[c + 1] - rep->cstart[c];
        for (uint32_t i = 0; i < n; i++) {
            cl[vs[i]] = c;
            vmap[vs[i]] = vs[0];
        }
        cluster_point(p, t, vs, n, q->verts[vs[0]]);
    }
    uint32_t maxn = 0;
    for (uint32_t f = 0; f < p->nfacets; f++)
        if (geo_poly_facet_size(p, f) > maxn)
            maxn = geo_poly_facet_size(p, f);
    buf = malloc(((size_t)maxn + 1) * sizeof *buf);
    if (!buf)
        goto done;
    bool bad = false;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f), k = 0;
        const uint32_t *vs = geo_poly_facet(p, f);
        for (uint32_t i = 0; i < n; i++) {
            uint32_t v = vmap[vs[i]];
            if (k == 0 || buf[k - 1] != v)
                buf[k++] = v;
        }
        while (k > 1 && buf[k - 1] == buf[0])
            k--;
        if (k < 3)
            continue;
        /* a vertex passed twice: the facet would pinch */
        for (uint32_t i = 0; i < k; i++)
            for (uint32_t j = i + 1; j < k; j++)
                if (buf[i] == buf[j] && cl[buf[i]] != GEO_NONE) {
                    active[cl[buf[i]]] = false;
                    bad = true;
                }
        int64_t g = geo_poly_add_facet(q, buf, k);
        if (g < 0)
            goto done;
        memcpy(q->planes[g], p->planes[f], sizeof p->planes[f]);
    }
    if (bad) {
        r = 1;
        goto done;
    }
    if (drop_hanging(q) < 0)
        goto done;
    uint32_t *cmap = malloc(((size_t)nv + 1) * sizeof *cmap);
    if (!cmap || geo_poly_compact(q, NULL, cmap, NULL) < 0) {
        free(cmap);
        goto done;
    }
    for (uint32_t c = 0; c < rep->clusters; c++)
        ret_rep[c] = active[c] ? cmap[rep->cverts[rep->cstart[c]]] : GEO_NONE;
    for (uint32_t v = 0; v < nv; v++)
        vmap[v] = cmap[vmap[v]];
    free(cmap);
    *ret = q;
    q = NULL;
    r = 0;
done:
    geo_poly_free(q);
    free(cl), free(buf);
    return r;
}

/* Deactivates the clusters whose vertex lies in a facet marked bad or,
 * when none does, in a facet sharing a vertex with one. Returns how many
 * were deactivated. */
static uint32_t blame(const geo_poly *q, const uint8_t *badf,
                      const uint32_t *crep, uint32_t ncl, bool *active)
{
    uint8_t *hit = calloc((size_t)q->nverts + 1, 1);
    uint8_t *wide = calloc((size_t)q->nverts + 1, 1);
    uint32_t n = 0;
    if (!hit || !wide) {
        free(hit), free(wide);
        return 0;
    }
    for (uint32_t f = 0; f < q->nfacets; f++)
        if (badf[f])
            for (uint32_t i = 0; i < geo_poly_facet_size(q, f); i++)
                hit[geo_poly_facet(q, f)[i]] = 1;
    for (int ring = 0; ring < 2 && n == 0; ring++) {
        if (ring == 1) {
            for (uint32_t f = 0; f < q->nfacets; f++) {
                bool touch = false;
                for (uint32_t i = 0; i < geo_poly_facet_size(q, f) && !touch; i++)
                    touch = hit[geo_poly_facet(q, f)[i]];
                if (touch)
                    for (uint32_t i = 0; i < geo_poly_facet_size(q, f); i++)
                        wide[geo_poly_facet(q, f)[i]] = 1;
            }
            memcpy(hit, wide, q->nverts);
        }
        for (uint32_t c = 0; c < ncl; c++)
            if (active[c] && crep[c] != GEO_NONE && hit[crep[c]]) {
                active[c] = false;
                n++;
            }
    }
    free(hit), free(wide);
    return n;
}

int geo_collapse(geo_poly *p, const geo_collapse_opts *opts,
                          const geo_ctx *ctx, geo_collapse_report *report,
                          geo_err *err)
{
    geo_collapse_opts o;
    if (opts)
        o = *opts;
    else
        geo_collapse_opts_default(&o);
    geo_collapse_report local, *rep = report ? report : &local;
    /* an output only: callers hand in uninitialised reports */
    memset(rep, 0, sizeof *rep);
    int r = geo_poly_validate_indices(p, err);
    if (r < 0)
        return r;
    if (!(o.radius >= 0) || !(o.rel_radius >= 0))
        return geo_err_set(err, -EINVAL, "radius must be non-negative");
    rep->radius = o.radius > 0 ? o.radius : o.rel_radius * geo_poly_size(p);
    rep->vertices_before = rep->vertices_after = p->nverts;
    rep->facets_before = rep->facets_after = p->nfacets;
    rep->vmap = malloc(((size_t)p->nverts + 1) * sizeof *rep->vmap);
    if (!rep->vmap)
        return geo_err_set(err, -ENOMEM, "out of memory");
    for (uint32_t v = 0; v < p->nverts; v++)
        rep->vmap[v] = v;
    geo_topo *t = geo_topo_build(p, err);
    if (!t)
        return -ENOMEM;
    geo_poly *q = NULL;
    bool *active = NULL;
    uint32_t *crep = NULL, *vmap = NULL, *fixed = NULL;
    uint8_t *badf = NULL;
    geo_stats st;
    memset(&st, 0, sizeof st);
    if (!geo_topo_is_closed_manifold(t)) {
        r = geo_err_set(err, -EINVAL, "the model is not a closed oriented "
                        "manifold");
        goto done;
    }
    if (find_clusters(p, t, rep->radius, rep) < 0)
        goto oom;
    uint32_t ncl = rep->clusters;
    for (uint32_t c = 0; c < ncl; c++)
        rep->cnew[c] = GEO_NONE;
    if (ncl == 0)
        goto done;
    active = malloc(ncl * sizeof *active);
    crep = malloc(ncl * sizeof *crep);
    vmap = malloc(((size_t)p->nverts + 1) * sizeof *vmap);
    fixed = malloc(ncl * sizeof *fixed);
    if (!active || !crep || !vmap || !fixed)
        goto oom;
    for (uint32_t c = 0; c < ncl; c++)
        active[c] = true;
    if (limit_per_facet(p, t, rep, active) < 0)
        goto oom;
    uint32_t attempts = o.max_attempts ? o.max_attempts : 1;
    for (uint32_t a = 0; a < attempts; a++) {
        if (geo_ctx_progress(ctx, (double)a / attempts) < 0) {
            r = geo_err_set(err, -ECANCELED, "collapse canceled");
            goto done;
        }
        rep->attempts++;
        q = geo_poly_free(q);
        int b = build_candidate(p, t, rep, active, &q, crep, vmap);
        if (b < 0)
            goto oom;
        if (b == 1)
            continue;
        uint32_t nfix = 0;
        for (uint32_t c = 0; c < ncl; c++)
            if (crep[c] != GEO_NONE)
                fixed[nfix++] = crep[c];
        if (nfix == 0) {
            q = geo_poly_free(q);
            break;
        }
        geo_replanar_opts ro;
        geo_replanar_opts_default(&ro, GEO_REPLANAR_SCALED);
        ro.max_steps = o.max_steps;
        ro.check = false;
        geo_replanar_result res;
        geo_err rerr;
        int rr = geo_replanarize(q, fixed, nfix, GEO_REPLANAR_SCALED, &ro, ctx,
                                 NULL, &res, &rerr);
        if (rr == -ENOMEM || rr == -ECANCELED) {
            r = geo_err_set(err, rr, "%s", rerr.msg);
            goto done;
        }
        geo_stats_clear(&st);
        if (geo_inspect(q, NULL, ctx, &st, err) < 0)
            goto oom;
        double max_move = o.max_move > 0 ? o.max_move : 2 * rep->radius;
        uint8_t *far = calloc((size_t)q->nverts + 1, 1);
        if (!far)
            goto oom;
        bool any_far = false;
        for (uint32_t v = 0; v < p->nverts; v++)
            if (vmap[v] != GEO_NONE &&
                geo_vdist(p->verts[v], q->verts[vmap[v]]) > max_move) {
                far[vmap[v]] = 1;
                any_far = true;
            }
        if (rr == 0 && res.converged && st.valid && !any_far) {
            free(far);
            rep->replanar_steps = res.steps;
            break;
        }
        /* blame the clusters near what is wrong */
        free(badf);
        badf = calloc((size_t)q->nfacets + 1, 1);
        if (!badf)
            goto oom;
        double eps = geo_poly_eps(q);
        for (uint32_t f = 0; f < q->nfacets; f++) {
            double an[3];
            geo_poly_facet_area_vector(q, f, an);
            bool bad = st.selfint.facet_flags &&
                       (st.selfint.facet_flags[f] &
                        (GEO_SI_PAIR | GEO_SI_SELF | GEO_SI_DEGENERATE));
            bad |= geo_vdot(an, q->planes[f]) <= 0;
            for (uint32_t i = 0; i < geo_poly_facet_size(q, f) && !bad; i++) {
                uint32_t v = geo_poly_facet(q, f)[i];
                bad = fabs(geo_plane_eval(q->planes[f], q->verts[v])) > eps ||
                      far[v];
            }
            badf[f] = bad;
        }
        free(far);
        geo_topo *qt = geo_topo_build(q, err);
        if (!qt)
            goto oom;
        /* facets at a vertex that is not manifold or in < 3 facets */
        for (uint32_t v = 0; v < q->nverts; v++)
            if (qt->vertex_kind[v] != GEO_VERTEX_INTERIOR ||
                qt->vstart[v + 1] - qt->vstart[v] < 3)
                for (uint32_t k = qt->vstart[v]; k < qt->vstart[v + 1]; k++)
                    badf[qt->corner_facet[qt->vcorners[k]]] = 1;
        for (uint32_t c = 0; c < geo_poly_ncorners(q); c++)
            if (qt->edge_kind[c] != GEO_EDGE_INTERIOR)
                badf[qt->corner_facet[c]] = 1;
        geo_topo_free(qt);
        if (blame(q, badf, crep, ncl, active) == 0)
            for (uint32_t c = 0; c < ncl; c++)
                active[c] = false;
        q = geo_poly_free(q);
    }
    if (!q) {
        /* nothing could be collapsed: p stays as it was */
        rep->rolled_back = ncl;
        goto done;
    }
    double maxd = 0;
    for (uint32_t v = 0; v < p->nverts; v++)
        if (vmap[v] != GEO_NONE)
            maxd = fmax(maxd, geo_vdist(p->verts[v], q->verts[vmap[v]]));
    for (uint32_t c = 0; c < ncl; c++) {
        rep->cnew[c] = crep[c];
        rep->collapsed += crep[c] != GEO_NONE;
        rep->rolled_back += crep[c] == GEO_NONE;
    }
    rep->max_displacement = maxd;
    memcpy(rep->vmap, vmap, (size_t)p->nverts * sizeof *vmap);
    rep->vertices_after = q->nverts;
    rep->facets_after = q->nfacets;
    if (geo_poly_assign(p, q) < 0)
        goto oom;
    r = 0;
    goto done;
oom:
    r = geo_err_set(err, -ENOMEM, "out of memory");
done:
    geo_stats_clear(&st);
    geo_poly_free(q);
    geo_topo_free(t);
    free(active), free(crep), free(vmap), free(fixed), free(badf);
    if (r < 0)
        geo_collapse_report_clear(rep);
    if (!report)
        geo_collapse_report_clear(&local);
    return r;
}
