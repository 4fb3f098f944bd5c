/* triangulate.c — the F-rep triangulation pipeline (see triangulate.h):
 * runs the stages in order, maps each stage's progress into its share of
 * the caller's, times them and assembles the report. */
#include "triangulate.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "frep_grid.h"
#include "selfint.h"
#include "topo.h"
#include "vec.h"

void geo_tri_opts_default(geo_tri_opts *o)
{
    memset(o, 0, sizeof *o);
    o->quad_levels = 9;
    o->binary_levels = 10;
    o->fill = GEO_FILL_AREA;
    o->refine = true;
    o->fair = GEO_FAIR_UNIFORM;
    o->sharpen = true;
    o->hard_angle_deg = 45.0;
    o->density = 1.0;
}

void geo_tri_report_clear(geo_tri_report *r)
{
    if (!r)
        return;
    geo_fill_stats_clear(&r->fill);
    memset(r, 0, sizeof *r);
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* A stage's view of the caller's context: fractions 0..1 of the stage
 * become a..b of the whole. */
typedef struct subrange {
    const geo_ctx *outer;
    double a, b;
} subrange;

static int sub_progress(void *user, double fraction)
{
    const subrange *s = user;
    return geo_ctx_progress(s->outer, s->a + (s->b - s->a) * fraction);
}

static geo_ctx sub_ctx(const geo_ctx *outer, subrange *s, double a, double b)
{
    geo_ctx c = {0};
    s->outer = outer;
    s->a = a;
    s->b = b;
    if (outer) {
        c.cancel = outer->cancel;
        c.seed = outer->seed;
        c.parallel_for = outer->parallel_for;
        c.pf_user = outer->pf_user;
    }
    c.progress = sub_progress;
    c.user = s;
    return c;
}

typedef struct surface {
    const geo_frep *f;
    double tol, max_step, crease_tol;
} surface;

/* Newton onto F = 0; a point it leaves farther than 1000·tol (the
 * bound geo_frep_project_pieces puts on a point of the surface) is
 * refused: where F is very flat or very steep on one side (a perturbation
 * of huge amplitude, F growing like q³ from q = 0) Newton creeps and a
 * centroid kept where it stopped lay half a voxel off the surface. */
static bool project_cb(void *user, double p[3])
{
    const surface *s = user;
    double q[3] = {p[0], p[1], p[2]};
    if (!(geo_frep_project(s->f, q, s->tol, s->max_step) <= 1000 * s->tol))
        return false;
    memcpy(p, q, sizeof q);
    return true;
}

/* Keeps a point made from vertices on the surface on what they share: the
 * smooth piece all of them lie on, or the crease (corner) when they share
 * two (three); refuses it when they share nothing — a triangle across a
 * crease is not split, since its centroid would land on either side and
 * fold the mesh — or when that part of the piece is not on the surface
 * there. */
static bool place_cb(void *user, double p[3], const double *const *from,
                     uint32_t n)
{
    const surface *s = user;
    uint32_t common[4], nc = 0;
    for (uint32_t k = 0; k < n; k++) {
        uint32_t pc[4];
        uint32_t np = geo_frep_pieces_at(s->f, from[k], s->crease_tol, pc, 4);
        if (np > 4)
            np = 4;
        if (k == 0) {
            memcpy(common, pc, np * sizeof *pc);
            nc = np;
            continue;
        }
        uint32_t keep = 0;
        for (uint32_t i = 0; i < nc; i++)
            for (uint32_t j = 0; j < np; j++)
                if (common[i] == pc[j]) {
                    common[keep++] = common[i];
                    break;
                }
        nc = keep;
    }
    if (nc == 0)
        return false;
    return geo_frep_project_pieces(s->f, common, nc < 3 ? nc : 3, p, s->tol,
                                   s->max_step);
}

/* How many smooth pieces of F the points p and q have in common (pieces
 * through a point: lib/frep/frep.h); UINT32_MAX when neither lies on any
 * piece within the tolerance. */
static uint32_t common_pieces(const surface *s, const double p[3],
                              const double q[3])
{
    uint32_t a[4], b[4];
    uint32_t na = geo_frep_pieces_at(s->f, p, s->crease_tol, a, 4);
    uint32_t nb = geo_frep_pieces_at(s->f, q, s->crease_tol, b, 4);
    if (na == 0 || nb == 0)
        return UINT32_MAX;
    uint32_t common = 0;
    for (uint32_t i = 0; i < na && i < 4; i++)
        for (uint32_t j = 0; j < nb && j < 4; j++)
            common += a[i] == b[j];
    return common;
}

/* The hard edges of an F-rep surface are its creases (every one: they
 * are known exactly); an edge lies along one when both its ends are on
 * the same two pieces, as the crease recovery leaves them. A smooth
 * surface has none, however coarse the sampling. */
static bool hard_cb(void *user, const double p[3], const double q[3])
{
    uint32_t c = common_pieces(user, p, q);
    return c != UINT32_MAX && c >= 2;
}

/* An edge whose ends share no piece cuts across a crease. */
static bool crosses_cb(void *user, const double p[3], const double q[3])
{
    return common_pieces(user, p, q) == 0;
}

/* A cell of the contour graph that visits a point twice leaves that point
 * pinched between two fans of quads. Removing the point's triangles turns
 * the holes around it into one, which the filler then closes as a disk
 * without the point. Repeats while pinches remain (a few rounds at most;
 * they are rare and isolated). flat is kept aligned with the facets. */
static int unpinch(geo_poly *m, uint8_t **flat, const geo_ctx *ctx,
                   uint32_t *ret_n, geo_err *err)
{
    *ret_n = 0;
    for (int round = 0; round < 8; round++) {
        if (geo_ctx_canceled(ctx))
            return geo_err_set(err, -ECANCELED, "canceled");
        geo_topo *t = geo_topo_build(m, err);
        if (!t)
            return -ENOMEM;
        if (t->nnonmanifold_vertices == 0) {
            geo_topo_free(t);
            return 0;
        }
        bool *keep = malloc(((size_t)m->nfacets + 1) * sizeof *keep);
        uint32_t *fmap = malloc(((size_t)m->nfacets + 1) * sizeof *fmap);
        if (!keep || !fmap) {
            free(keep), free(fmap);
            geo_topo_free(t);
            return geo_err_set(err, -ENOMEM, "out of memory");
        }
        for (uint32_t f = 0; f < m->nfacets; f++)
            keep[f] = true;
        for (uint32_t v = 0; v < m->nverts; v++) {
            if (t->vertex_kind[v] != GEO_VERTEX_NONMANIFOLD)
                continue;
            (*ret_n)++;
            for (uint32_t k = t->vstart[v]; k < t->vstart[v + 1]; k++)
                keep[t->corner_facet[t->vcorners[k]]] = false;
        }
        geo_topo_free(t);
        uint32_t nf = m->nfacets;
        int rc = geo_poly_compact(m, keep, NULL, fmap);
        if (rc == 0)
            for (uint32_t f = 0; f < nf; f++)
                if (fmap[f] != UINT32_MAX)
                    (*flat)[fmap[f]] = (*flat)[f];
        free(keep), free(fmap);
        if (rc < 0)
            return geo_err_set(err, rc, "out of memory");
    }
    return 0;
}

/* Removes the connected pieces (facets linked through shared vertices)
 * that enclose next to nothing: signed volume at most min_volume. Where
 * a sheet is about as thin as a voxel the sections can still close tiny
 * pieces of it on themselves — four triangles of one plane facing both
 * ways, a triangle and its reverse — which enclose no volume and overlap
 * themselves; like the parts the sampling drops (frep_grid.h) they are
 * below the resolution. A piece of the closed surface is itself closed,
 * so the rest stays closed. flat is kept aligned with the facets. */
static int drop_empty_pieces(geo_poly *m, uint8_t *flat, double min_volume,
                             uint32_t *ret_n, geo_err *err)
{
    uint32_t nv = m->nverts, nf = m->nfacets;
    uint32_t *par = malloc(((size_t)nv + 1) * sizeof *par);
    double *vol = calloc((size_t)nv + 1, sizeof *vol);
    bool *keep = malloc(((size_t)nf + 1) * sizeof *keep);
    uint32_t *fmap = malloc(((size_t)nf + 1) * sizeof *fmap);
    if (!par || !vol || !keep || !fmap) {
        free(par), free(vol), free(keep), free(fmap);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    for (uint32_t v = 0; v < nv; v++)
        par[v] = v;
    for (uint32_t f = 0; f < nf; f++) {
        const uint32_t *fv = geo_poly_facet(m, f);
        for (uint32_t k = 1; k < geo_poly_facet_size(m, f); k++) {
            uint32_t a = fv[0], b = fv[k];
            while (par[a] != a)
                a = par[a] = par[par[a]];
            while (par[b] != b)
                b = par[b] = par[par[b]];
            if (a != b)
                par[a < b ? b : a] = a < b ? a : b;
        }
    }
    for (uint32_t v = 0; v < nv; v++)
        while (par[v] != par[par[v]])
            par[v] = par[par[v]];
    /* signed volume: Σ over the fan triangles of det(a, b, c) / 6, taken
     * about the piece's first vertex so that it does not depend on where
     * the origin lies */
    for (uint32_t f = 0; f < nf; f++) {
        const uint32_t *fv = geo_poly_facet(m, f);
        uint32_t root = par[fv[0]];
        const double *o = m->verts[root];
        for (uint32_t k = 1; k + 1 < geo_poly_facet_size(m, f); k++) {
            double a[3], b[3], c[3], x[3];
            geo_vsub(m->verts[fv[0]], o, a);
            geo_vsub(m->verts[fv[k]], o, b);
            geo_vsub(m->verts[fv[k + 1]], o, c);
            geo_vcross(b, c, x);
            vol[root] += geo_vdot(a, x) / 6.0;
        }
    }
    uint32_t ndrop = 0;
    for (uint32_t f = 0; f < nf; f++) {
        keep[f] = vol[par[geo_poly_facet(m, f)[0]]] > min_volume;
        ndrop += !keep[f];
    }
    int rc = 0;
    if (ndrop > 0) {
        rc = geo_poly_compact(m, keep, NULL, fmap);
        if (rc == 0)
            for (uint32_t f = 0; f < nf; f++)
                if (fmap[f] != UINT32_MAX)
                    flat[fmap[f]] = flat[f];
    }
    free(par), free(vol), free(keep), free(fmap);
    if (rc < 0)
        return geo_err_set(err, rc, "out of memory");
    *ret_n = ndrop;
    return 0;
}

/* Adds to the refinement region every triangle sharing a vertex with it:
 * a wall (a triangle parallel to the rays) at a silhouette is a long
 * sliver between the last points of its columns, and only flips across
 * its edges, into the triangles beside it, can replace it by fair ones. */
static int grow_region(const geo_poly *m, uint8_t *region, geo_err *err)
{
    uint8_t *mark = calloc((size_t)m->nverts + 1, 1);
    if (!mark)
        return geo_err_set(err, -ENOMEM, "out of memory");
    for (uint32_t f = 0; f < m->nfacets; f++)
        if (region[f]) {
            const uint32_t *fv = geo_poly_facet(m, f);
            for (uint32_t k = 0; k < geo_poly_facet_size(m, f); k++)
                mark[fv[k]] = 1;
        }
    for (uint32_t f = 0; f < m->nfacets; f++) {
        const uint32_t *fv = geo_poly_facet(m, f);
        for (uint32_t k = 0; k < geo_poly_facet_size(m, f) && !region[f]; k++)
            region[f] = mark[fv[k]];
    }
    free(mark);
    return 0;
}

int geo_triangulate(const geo_frep *f, const geo_tri_opts *opts,
                         const geo_ctx *ctx, geo_poly **ret_mesh,
                         geo_tri_report *report, geo_err *err)
{
    geo_tri_opts o;
    if (opts)
        o = *opts;
    else
        geo_tri_opts_default(&o);
    geo_tri_report rep = {.self_intersections = -1};
    geo_frep_grid *g = NULL;
    geo_poly *mesh = NULL;
    uint8_t *flat = NULL;
    subrange sr;
    geo_ctx sc;
    double t0 = now(), t;
    int rc;

    sc = sub_ctx(ctx, &sr, 0.0, 0.45);
    if ((rc = geo_frep_grid_build(f, o.quad_levels, o.binary_levels, &sc, 0,
                                  1, &g, err)) < 0)
        goto fail;
    rep.npoints = 2 * g->nruns;
    rep.nevals = g->nevals;
    rep.nboxes = g->nboxes;
    rep.voxel[0] = rep.voxel[1] = g->hx;
    rep.voxel[2] = g->hz;
    t = now();
    rep.t_sample = t - t0;
    if (g->nruns == 0) {
        /* an empty object (or one thinner than a column everywhere) is a
         * result, the empty surface, not a failure */
        if (!(mesh = geo_poly_new())) {
            rc = geo_err_set(err, -ENOMEM, "out of memory");
            goto fail;
        }
        rep.empty = true;
        rep.self_intersections = 0;
        rep.t_total = now() - t0;
        if ((rc = geo_ctx_progress(ctx, 1.0)) < 0) {
            geo_err_set(err, rc, "canceled");
            goto fail;
        }
        goto done;
    }

    if ((rc = geo_frep_connect(g, ctx, &mesh, &flat, &rep.connect, err)) < 0)
        goto fail;
    if (geo_ctx_canceled(ctx)) {
        rc = geo_err_set(err, -ECANCELED, "canceled");
        goto fail;
    }
    if ((rc = geo_poly_compact(mesh, NULL, NULL, NULL)) < 0) {
        geo_err_set(err, rc, "out of memory");
        goto fail;
    }
    if ((rc = unpinch(mesh, &flat, ctx, &rep.npinched, err)) < 0)
        goto fail;
    if ((rc = geo_ctx_progress(ctx, 0.55)) < 0) {
        geo_err_set(err, rc, "canceled");
        goto fail;
    }
    rep.t_connect = now() - t;
    t = now();

    surface surf = {f, 1e-12 * g->side, 8.0 * g->hx, 1e-9 * g->side};
    geo_fill_opts fo;
    geo_fill_opts_default(&fo);
    fo.weight = o.fill;
    fo.refine = o.refine;
    fo.fair = o.fair;
    fo.density = o.density;
    fo.hard_angle_deg = o.hard_angle_deg;
    fo.project = project_cb;
    fo.hard_edge = hard_cb;
    fo.crosses_feature = crosses_cb;
    uint32_t nprog;
    const geo_frep_op *prog = geo_frep_program(f, &nprog);
    for (uint32_t i = 0; i < nprog; i++)
        if (prog[i].code == GEO_FREP_OP_MIN || prog[i].code == GEO_FREP_OP_MAX)
            fo.place = place_cb;
    fo.project_user = &surf;
    /* holes first, refinement after the creases are recovered: a
     * centroid of a triangle lying on one smooth piece then stays on it */
    geo_fill_opts lo = fo;
    lo.refine = false;
    lo.fair = GEO_FAIR_NONE;
    sc = sub_ctx(ctx, &sr, 0.55, 0.6);
    uint32_t nf0 = mesh->nfacets;
    if ((rc = geo_fill_loops(mesh, &lo, &sc, &rep.fill, err)) < 0)
        goto fail;
    uint8_t *region = realloc(flat, (size_t)mesh->nfacets + 1);
    if (!region) {
        rc = geo_err_set(err, -ENOMEM, "out of memory");
        goto fail;
    }
    flat = region;
    for (uint32_t fc = nf0; fc < mesh->nfacets; fc++)
        flat[fc] = 1;
    if ((rc = drop_empty_pieces(mesh, flat, 1e-3 * g->hx * g->hx * g->hz,
                                &rep.ndropped, err)) < 0)
        goto fail;
    if (mesh->nfacets == 0) {
        rep.empty = true;
        rep.self_intersections = 0;
        rep.t_fill = now() - t;
        rep.t_total = now() - t0;
        if ((rc = geo_ctx_progress(ctx, 1.0)) < 0) {
            geo_err_set(err, rc, "canceled");
            goto fail;
        }
        goto done;
    }
    rep.t_fill = now() - t;
    t = now();
    sc = sub_ctx(ctx, &sr, 0.6, 0.7);
    if (o.sharpen &&
        (rc = geo_frep_sharpen(f, mesh, &flat, &sc, &rep.sharpen, err)) < 0)
        goto fail;
    rep.t_sharpen = now() - t;
    t = now();
    if ((rc = grow_region(mesh, flat, err)) < 0)
        goto fail;
    geo_fill_stats rs = {0};
    sc = sub_ctx(ctx, &sr, 0.7, 0.9);
    if ((o.refine || o.fair != GEO_FAIR_NONE) &&
        (rc = geo_refine_region(mesh, flat, &fo, &sc, &rs, err)) < 0)
        goto fail;
    rep.fill.nverts_added = rs.nverts_added;
    rep.fill.nregion_facets = rs.nregion_facets;
    rep.fill.nsplits = rs.nsplits;
    rep.fill.nflips = rs.nflips;
    rep.fill.nhard_splits = rs.nhard_splits;
    rep.fill.nfair_sweeps = rs.nfair_sweeps;
    for (uint32_t fc = 0; fc < mesh->nfacets; fc++) {
        if ((fc & 65535) == 0 && geo_ctx_canceled(ctx)) {
            rc = geo_err_set(err, -ECANCELED, "canceled");
            goto fail;
        }
        geo_poly_facet_fit_plane(mesh, fc, GEO_PLANE_UNWEIGHTED,
                                 mesh->planes[fc]);
    }
    rep.t_fill += now() - t;
    t = now();
    if ((rc = geo_ctx_progress(ctx, 0.92)) < 0) {
        geo_err_set(err, rc, "canceled");
        goto fail;
    }

    if ((rc = geo_frep_mesh_metrics(f, mesh, ctx, &rep.quality, err)) < 0)
        goto fail;
    geo_selfint si;
    sc = sub_ctx(ctx, &sr, 0.94, 1.0);
    if ((rc = geo_selfint_find(mesh, NULL, NULL, &sc, &si, err)) < 0)
        goto fail;
    rep.self_intersections = (int64_t)si.count;
    rep.ndegenerate = si.ndegenerate;
    geo_selfint_clear(&si);
    rep.t_metrics = now() - t;
    rep.t_total = now() - t0;
    if ((rc = geo_ctx_progress(ctx, 1.0)) < 0) {
        geo_err_set(err, rc, "canceled");
        goto fail;
    }
done:
    geo_frep_grid_free(g);
    free(flat);
    *ret_mesh = mesh;
    if (report)
        *report = rep;
    else
        geo_tri_report_clear(&rep);
    return 0;
fail:
    geo_frep_grid_free(g);
    geo_poly_free(mesh);
    free(flat);
    geo_tri_report_clear(&rep);
    return rc;
}
