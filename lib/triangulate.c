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
    double tol, max_step, cos_hard, crease_tol;
} surface;

static void project_cb(void *user, double p[3])
{
    const surface *s = user;
    geo_frep_project(s->f, p, s->tol, s->max_step);
}

/* A hard edge of an F-rep surface is a crease between smooth pieces: an
 * edge lying on one (both ends on the same two pieces, as the crease
 * recovery leaves them) or crossing one whose normals differ by more than
 * the hard angle. A smooth surface has none, however coarse the
 * sampling. */
static bool hard_cb(void *user, const double p[3], const double q[3])
{
    const surface *s = user;
    uint32_t a[4], b[4];
    uint32_t na = geo_frep_pieces_at(s->f, p, s->crease_tol, a, 4);
    uint32_t nb = geo_frep_pieces_at(s->f, q, s->crease_tol, b, 4);
    uint32_t common = 0;
    for (uint32_t i = 0; i < na && i < 4; i++)
        for (uint32_t j = 0; j < nb && j < 4; j++)
            common += a[i] == b[j];
    if (common >= 2)
        return true;
    if (common == 1)
        return false;
    uint32_t n, pp, pq;
    const geo_frep_op *prog = geo_frep_program(s->f, &n);
    double gp[3], gq[3];
    geo_frep_run_piece(s->f, prog, n, p, gp, &pp);
    geo_frep_run_piece(s->f, prog, n, q, gq, &pq);
    if (pp == pq || geo_vnormalize(gp) == 0 || geo_vnormalize(gq) == 0)
        return false;
    return geo_vdot(gp, gq) < s->cos_hard;
}

int geo_frep_triangulate(const geo_frep *f, const geo_tri_opts *opts,
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
    if (g->nruns == 0) {
        rc = geo_err_set(err, -EINVAL,
                         "no surface found: the object is empty or thinner "
                         "than a voxel at these levels");
        goto fail;
    }
    rep.npoints = 2 * g->nruns;
    rep.nevals = g->nevals;
    rep.nboxes = g->nboxes;
    rep.voxel[0] = rep.voxel[1] = g->hx;
    rep.voxel[2] = g->hz;
    t = now();
    rep.t_sample = t - t0;

    if ((rc = geo_frep_connect(g, ctx, &mesh, &flat, &rep.connect, err)) < 0)
        goto fail;
    if ((rc = geo_poly_compact(mesh, NULL, NULL, NULL)) < 0) {
        geo_err_set(err, rc, "out of memory");
        goto fail;
    }
    if ((rc = geo_ctx_progress(ctx, 0.55)) < 0) {
        geo_err_set(err, rc, "canceled");
        goto fail;
    }
    rep.t_connect = now() - t;
    t = now();

    surface surf = {f, 1e-12 * g->side, 8.0 * g->hx,
                    cos(o.hard_angle_deg * M_PI / 180.0), 1e-9 * g->side};
    geo_fill_opts fo;
    geo_fill_opts_default(&fo);
    fo.weight = o.fill;
    fo.refine = o.refine;
    fo.fair = o.fair;
    fo.density = o.density;
    fo.hard_angle_deg = o.hard_angle_deg;
    fo.project = project_cb;
    fo.hard_edge = hard_cb;
    fo.project_user = &surf;
    /* holes first, refinement after the creases are recovered: a
     * centroid of a triangle lying on one smooth piece then stays on it */
    geo_fill_opts lo = fo;
    lo.refine = false;
    lo.fair = GEO_FAIR_NONE;
    sc = sub_ctx(ctx, &sr, 0.55, 0.65);
    uint32_t nf0 = mesh->nfacets;
    if ((rc = geo_fill_holes(mesh, &lo, &sc, &rep.fill, err)) < 0)
        goto fail;
    uint8_t *region = realloc(flat, (size_t)mesh->nfacets + 1);
    if (!region) {
        rc = geo_err_set(err, -ENOMEM, "out of memory");
        goto fail;
    }
    flat = region;
    for (uint32_t fc = nf0; fc < mesh->nfacets; fc++)
        flat[fc] = 1;
    rep.t_fill = now() - t;
    t = now();
    if (o.sharpen &&
        (rc = geo_frep_sharpen(f, mesh, &flat, ctx, &rep.sharpen, err)) < 0)
        goto fail;
    rep.t_sharpen = now() - t;
    t = now();
    geo_fill_stats rs = {0};
    sc = sub_ctx(ctx, &sr, 0.65, 0.9);
    if ((o.refine || o.fair != GEO_FAIR_NONE) &&
        (rc = geo_refine_region(mesh, flat, &fo, &sc, &rs, err)) < 0)
        goto fail;
    rep.fill.nverts_added = rs.nverts_added;
    rep.fill.nregion_facets = rs.nregion_facets;
    rep.fill.nsplits = rs.nsplits;
    rep.fill.nflips = rs.nflips;
    rep.fill.nhard_splits = rs.nhard_splits;
    rep.fill.nfair_sweeps = rs.nfair_sweeps;
    rep.t_fill += now() - t;
    t = now();
    /* refinement may split a curved crease off itself: recover again */
    geo_sharpen_stats s2;
    if (o.sharpen && (rc = geo_frep_sharpen(f, mesh, NULL, ctx, &s2, err)) < 0)
        goto fail;
    rep.sharpen.nedge_splits += s2.nedge_splits;
    rep.sharpen.nsnaps += s2.nsnaps;
    rep.sharpen.ncorners += s2.ncorners;
    rep.sharpen.nrejected = s2.nrejected;
    geo_poly_compute_planes(mesh, GEO_PLANE_UNWEIGHTED);
    if ((rc = geo_ctx_progress(ctx, 0.92)) < 0) {
        geo_err_set(err, rc, "canceled");
        goto fail;
    }
    rep.t_sharpen += now() - t;
    t = now();

    if ((rc = geo_frep_mesh_metrics(f, mesh, &rep.quality, err)) < 0)
        goto fail;
    rep.t_metrics = now() - t;
    rep.t_total = now() - t0;
    if ((rc = geo_ctx_progress(ctx, 1.0)) < 0) {
        geo_err_set(err, rc, "canceled");
        goto fail;
    }
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
