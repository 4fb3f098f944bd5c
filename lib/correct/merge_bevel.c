/* merge_bevel.c — removing the bevel strips a shadow-profile scanner
 * leaves along sharp edges (the pass geo_merge_auto runs once its rounds
 * have converged).
 *
 * Along a true edge between facets A and B the views between A's and
 * B's own azimuths see the edge itself as a silhouette vertex; their
 * noisy silhouette planes pass through it and cut a strip off the
 * scanned corner whose normal lies anywhere between A's and B's. No
 * angle or deviation bound of the groups brings such a strip in: it is
 * 10°–20° off both neighbours, and the plane of a group of it with
 * either leans towards the other. But its every vertex lies within the
 * scan's error of both planes extended: the strip is the sharp edge
 * A∩B, bevelled by noise. A facet S is taken for a bevel of A and B when
 *  (1) A and B are neighbours of S (across edges), each larger than S;
 *  (2) S's normal lies between theirs: n_S·n_A > n_A·n_B and
 *      n_S·n_B > n_A·n_B;
 *  (3) every vertex of S lies within GEO_BEVEL_DEPTH_FACTOR times the
 *      deviation bound of the groups (max_dev, the scan's error) of A's
 *      plane and of B's plane. The bevel is the innermost of the many
 *      noisy silhouettes through the edge (every view between A's and
 *      B's azimuths: tens to hundreds), about sqrt(2 ln N) σ deep for N
 *      views of silhouette noise σ (2–3 σ for N = 10–100), so deeper than
 *      one facet's slivers, and its vertices on B lie about twice that
 *      from A's plane: 4–6 σ. Three times the 5 µm bound of a 10 mm
 *      stone covers that up to σ = 2.5 µm (README);
 *  (4) S is a strip along the edge: its extent along the direction of
 *      A∩B is at least GEO_BEVEL_ASPECT times its extent across it (in
 *      its plane) — which keeps the narrow true facets out (a jubilee's
 *      girdle facet between neighbours 3.75° off is as wide as long).
 * Among the pairs that qualify, the one sharing the longest edges with S
 * is taken. S is then merged with the larger of A and B by the paper's
 * four steps with that neighbour's plane kept (no refit): S's vertices
 * below it are lifted along the other facets' edges up to it, which
 * extends the other neighbour to the restored edge, and the cut does the
 * rest (§2.6, §3.4). A merge that fails (any step, or the local validity
 * check) is rolled back and the other neighbour is tried.
 *
 * Only facets that existed when the pass began are candidates. Cost:
 * O(Σ k² + n log n) for facets of k edges (pairs of neighbours), plus
 * the merges, each local. */
#include "merge_impl.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "vec.h"

#define GEO_BEVEL_DEPTH_FACTOR 3.0
#define GEO_BEVEL_ASPECT 4.0

typedef struct nb {
    uint32_t f;
    double shared; /* length of the edges shared with S */
    double area;
} nb;

typedef struct area_id {
    double area;
    uint32_t f;
} area_id;

static int cmp_area_asc(const void *a, const void *b)
{
    const area_id *x = a, *y = b;
    if (x->area != y->area)
        return x->area < y->area ? -1 : 1;
    return (x->f > y->f) - (x->f < y->f);
}

static double facet_area(const geo_edit *e, uint32_t f)
{
    double a[3];
    geo_edit_area_vector(e, f, a);
    return geo_vlen(a);
}

/* Is s a bevel strip (see the top)? On true, *ret_a is the larger of its
 * two neighbours and *ret_b the other. nbs: scratch of room for s's
 * edge count. */
static bool is_bevel(const geo_edit *e, uint32_t s, double max_dev, nb *nbs,
                     uint32_t *ret_a, uint32_t *ret_b)
{
    uint32_t n = geo_edit_fn(e, s), nn = 0;
    double as = facet_area(e, s);
    for (uint32_t i = 0; i < n; i++) {
        const uint32_t *fv = geo_edit_fv(e, s);
        uint32_t a = fv[i], b = fv[i + 1 < n ? i + 1 : 0];
        uint32_t h = geo_edit_across(e, s, a, b);
        if (h == GEO_NONE)
            return false;
        double len = geo_vdist(e->verts[a], e->verts[b]);
        uint32_t j = 0;
        while (j < nn && nbs[j].f != h)
            j++;
        if (j == nn) {
            nbs[nn].f = h;
            nbs[nn].shared = 0;
            nbs[nn].area = facet_area(e, h);
            nn++;
        }
        nbs[j].shared += len;
    }
    const double *ns = e->planes[s];
    double best = 0;
    bool found = false;
    for (uint32_t i = 0; i < nn; i++) {
        if (!(nbs[i].area > as))
            continue;
        const double *pa = e->planes[nbs[i].f];
        for (uint32_t j = i + 1; j < nn; j++) {
            if (!(nbs[j].area > as) || nbs[i].shared + nbs[j].shared <= best)
                continue;
            const double *pb = e->planes[nbs[j].f];
            double cab = geo_vdot(pa, pb);
            if (!(geo_vdot(ns, pa) > cab && geo_vdot(ns, pb) > cab))
                continue;
            double u[3];
            geo_vcross(pa, pb, u);
            if (geo_vnormalize(u) <= 0)
                continue;
            double across[3];
            geo_vcross(ns, u, across);
            if (geo_vnormalize(across) <= 0)
                continue;
            bool near = true;
            double lo = INFINITY, hi = -INFINITY, wlo = INFINITY, whi = -INFINITY;
            for (uint32_t k = 0; k < n && near; k++) {
                const double *x = e->verts[geo_edit_fv(e, s)[k]];
                near = fabs(geo_plane_eval(pa, x)) <= max_dev &&
                       fabs(geo_plane_eval(pb, x)) <= max_dev;
                double t = geo_vdot(u, x), q = geo_vdot(across, x);
                lo = fmin(lo, t), hi = fmax(hi, t);
                wlo = fmin(wlo, q), whi = fmax(whi, q);
            }
            if (!near || GEO_BEVEL_ASPECT * (whi - wlo) > hi - lo)
                continue;
            best = nbs[i].shared + nbs[j].shared;
            found = true;
            bool ia = nbs[i].area >= nbs[j].area;
            *ret_a = ia ? nbs[i].f : nbs[j].f;
            *ret_b = ia ? nbs[j].f : nbs[i].f;
        }
    }
    return found;
}

int geo_mw_bevel_pass(geo_mw *w, const geo_group_crit *c, const geo_ctx *ctx,
                      geo_merge_report *rep, uint32_t *ret_merged,
                      geo_err *err)
{
    w->ctx = ctx;
    geo_edit *e = w->e;
    *ret_merged = 0;
    int r = geo_mw_world_build(w, err);
    if (r < 0)
        return r;
    uint32_t nf = e->nfacets, nlive = 0, maxn = 0;
    area_id *order = malloc(((size_t)nf + 1) * sizeof *order);
    if (!order)
        return geo_err_set(err, -ENOMEM, "out of memory");
    for (uint32_t f = 0; f < nf; f++) {
        if (!e->falive[f])
            continue;
        order[nlive].area = facet_area(e, f);
        order[nlive++].f = f;
        if (geo_edit_fn(e, f) > maxn)
            maxn = geo_edit_fn(e, f);
    }
    qsort(order, nlive, sizeof *order, cmp_area_asc);
    nb *nbs = malloc(((size_t)maxn + 1) * sizeof *nbs);
    if (!nbs) {
        free(order);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    for (uint32_t k = 0; k < nlive && r == 0; k++) {
        if ((k & 63) == 0 && geo_ctx_canceled(ctx)) {
            r = geo_err_set(err, -ECANCELED, "merge canceled");
            break;
        }
        uint32_t s = order[k].f, a, b;
        /* a facet an earlier merge changed may have grown past maxn */
        if (!e->falive[s] || geo_edit_fn(e, s) > maxn ||
            !is_bevel(e, s, GEO_BEVEL_DEPTH_FACTOR * c->max_dev, nbs, &a, &b))
            continue;
        uint32_t target[2] = {a, b};
        for (int t = 0; t < 2; t++) {
            double plane[4];
            memcpy(plane, e->planes[target[t]], sizeof plane);
            uint32_t group[2] = {target[t], s};
            geo_merge_group *gr;
            if (geo_merge_report_add(rep, group, 2, &gr) < 0) {
                r = geo_err_set(err, -ENOMEM, "out of memory");
                break;
            }
            geo_err gerr;
            w->fixed_plane = plane;
            r = geo_mw_merge(w, group, 2, gr, &gerr);
            w->fixed_plane = NULL;
            if (r == 0) {
                ++*ret_merged;
                break;
            }
            if (r != -EINVAL) {
                geo_err_set(err, r, "%s", gerr.msg);
                break;
            }
            r = 0;
        }
    }
    free(order), free(nbs);
    return r;
}
