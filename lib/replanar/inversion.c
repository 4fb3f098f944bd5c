/* inversion.c — the inversion statistics of Palachev 2012, §4.3.4: random
 * vertex moves by fractions of the nearest-vertex distance, re-planarised
 * in parallel, tabulated per magnitude with Wilson intervals.
 *
 * Invariant: run i = (sample i / nmag, magnitude i % nmag) depends only
 * on (seed, sample, magnitude), never on the thread that ran it. */
#include "inversion.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bvh.h"
#include "vec.h"

static const double PAPER_M[] = {1,     0.5,    0.1,    0.05,   0.01,
                                 0.005, 0.001,  0.0005, 0.0001, 0.00005};

void geo_inversion_opts_default(geo_inversion_opts *o)
{
    memset(o, 0, sizeof *o);
    o->samples = 100;
    o->nmagnitudes = sizeof PAPER_M / sizeof PAPER_M[0];
    memcpy(o->magnitudes, PAPER_M, sizeof PAPER_M);
    o->schedule = GEO_REPLANAR_SCALED;
    geo_replanar_opts_default(&o->replanar, o->schedule);
}

void geo_inversion_stats_clear(geo_inversion_stats *s)
{
    if (!s)
        return;
    free(s->rows);
    free(s->runs);
    memset(s, 0, sizeof *s);
}

void geo_wilson95(uint32_t k, uint32_t n, double *ret_lo, double *ret_hi)
{
    if (n == 0) {
        *ret_lo = 0;
        *ret_hi = 1;
        return;
    }
    const double z = 1.959963984540054;
    double p = (double)k / n, z2n = z * z / n;
    double centre = (p + 0.5 * z2n) / (1 + z2n);
    double half = z / (1 + z2n) * sqrt(p * (1 - p) / n + 0.25 * z2n / n);
    *ret_lo = k == 0 ? 0.0 : fmax(0.0, centre - half);
    *ret_hi = k == n ? 1.0 : fmin(1.0, centre + half);
}

/* ---- nearest vertex ---- */

typedef struct nn_query {
    const geo_poly *p;
    uint32_t v;
    double best2;
} nn_query;

static bool nn_visit(void *user, uint32_t item)
{
    nn_query *q = user;
    if (item == q->v)
        return true;
    double d[3];
    geo_vsub(q->p->verts[item], q->p->verts[q->v], d);
    double d2 = geo_vdot(d, d);
    if (d2 < q->best2)
        q->best2 = d2;
    return true;
}

/* Distance from v to its nearest other vertex: boxes of half-size r about
 * v, doubling r until one holds a vertex within distance r (then the box
 * holds the nearest one). */
static double nearest_distance(const geo_poly *p, const geo_bvh *h,
                               uint32_t v, double r0)
{
    double r = r0;
    for (;;) {
        nn_query q = {p, v, INFINITY};
        geo_bbox b;
        for (int k = 0; k < 3; k++) {
            b.lo[k] = p->verts[v][k] - r;
            b.hi[k] = p->verts[v][k] + r;
        }
        geo_bvh_query_box(h, &b, nn_visit, &q);
        if (q.best2 <= r * r)
            return sqrt(q.best2);
        r *= 2;
    }
}

/* ---- the runs ---- */

typedef struct job {
    const geo_poly *p;
    geo_replanar_prep *prep;
    geo_bvh *vbvh;
    const geo_inversion_opts *o;
    geo_replanar_opts ropts;
    geo_ctx ctx;          /* cancellation only: no progress from workers */
    uint64_t seed;
    double r0;
    uint32_t base;        /* first run of the current batch */
    geo_inversion_run *runs;
    int *rc;              /* per run */
} job;

static uint64_t sample_seed(uint64_t seed, uint32_t s)
{
    uint64_t st = seed ^ (0xd1b54a32d192ed03ULL * ((uint64_t)s + 1));
    return geo_rand_next(&st);
}

/* A uniform index in [0, n) without modulo bias. */
static uint32_t rand_below(uint64_t *st, uint32_t n)
{
    uint64_t lim = UINT64_MAX - UINT64_MAX % n, x;
    do
        x = geo_rand_next(st);
    while (x >= lim);
    return (uint32_t)(x % n);
}

static void run_one(void *arg, size_t i)
{
    job *j = arg;
    uint32_t idx = j->base + (uint32_t)i, nm = j->o->nmagnitudes;
    uint32_t s = idx / nm, mi = idx % nm;
    geo_inversion_run *out = &j->runs[idx];
    uint64_t st = sample_seed(j->seed, s);
    uint32_t v = rand_below(&st, j->p->nverts);
    double dir[3], l2;
    do {
        for (int k = 0; k < 3; k++)
            dir[k] = 2 * geo_rand_unit(&st) - 1;
        l2 = geo_vdot(dir, dir);
    } while (l2 > 1 || l2 < 1e-12);
    geo_vnormalize(dir);
    double delta = nearest_distance(j->p, j->vbvh, v, j->r0);
    double m = j->o->magnitudes[mi], target[3];
    geo_vmadd(j->p->verts[v], m * delta, dir, target);

    geo_replanar_result res;
    const double(*t)[3] = (const double(*)[3])target;
    j->rc[idx] = geo_replanar_solve(j->prep, 1, &v, t, j->o->schedule,
                                    &j->ropts, &j->ctx, NULL, &res, NULL,
                                    NULL);
    *out = (geo_inversion_run){
        .sample = s, .vertex = v, .m = m, .delta = delta,
        .dir = {dir[0], dir[1], dir[2]}, .converged = res.converged,
        .nselfint = res.nselfint, .ninverted = res.ninverted,
        .volume = res.volume, .steps = res.steps,
        .first_selfint_step = res.first_selfint_step};
    out->inverted = !geo_replanar_result_valid(&res);
}

static int check_opts(const geo_poly *p, const geo_inversion_opts *o,
                      geo_err *err)
{
    if (p->nverts < 2)
        return geo_err_set(err, -EINVAL, "model: fewer than 2 vertices");
    if (o->samples == 0 || o->samples > 1000000)
        return geo_err_set(err, -EINVAL,
                           "samples: %u out of range [1, 1000000]",
                           o->samples);
    if (o->nmagnitudes == 0 ||
        o->nmagnitudes > GEO_INVERSION_MAX_MAGNITUDES)
        return geo_err_set(err, -EINVAL,
                           "magnitudes: %u given, 1 to %d allowed",
                           o->nmagnitudes, GEO_INVERSION_MAX_MAGNITUDES);
    for (uint32_t i = 0; i < o->nmagnitudes; i++)
        if (!(o->magnitudes[i] > 0) || !isfinite(o->magnitudes[i]))
            return geo_err_set(err, -EINVAL,
                               "magnitudes[%u]: must be positive and "
                               "finite", i);
    return 0;
}

static void tabulate(const geo_inversion_opts *o, const geo_inversion_run *runs,
                     uint32_t nruns, geo_inversion_row *rows)
{
    for (uint32_t k = 0; k < o->nmagnitudes; k++)
        rows[k] = (geo_inversion_row){.m = o->magnitudes[k]};
    for (uint32_t i = 0; i < nruns; i++) {
        const geo_inversion_run *r = &runs[i];
        geo_inversion_row *row = &rows[i % o->nmagnitudes];
        row->runs++;
        row->inverted += r->inverted;
        row->not_converged += !r->converged;
        row->selfint += r->nselfint > 0;
        row->inverted_facets += r->ninverted > 0;
        row->nonpositive_volume += !(r->volume > 0);
    }
    for (uint32_t k = 0; k < o->nmagnitudes; k++) {
        geo_inversion_row *row = &rows[k];
        row->p = row->runs ? (double)row->inverted / row->runs : 0;
        geo_wilson95(row->inverted, row->runs, &row->lo, &row->hi);
    }
}

int geo_inversion_stats_run(const geo_poly *p, const geo_inversion_opts *opts,
                            const geo_ctx *ctx, geo_inversion_stats *ret,
                            geo_err *err)
{
    geo_inversion_opts o;
    if (opts)
        o = *opts;
    else
        geo_inversion_opts_default(&o);
    memset(ret, 0, sizeof *ret);
    int rc = check_opts(p, &o, err);
    if (rc < 0)
        return rc;
    o.replanar.check = true;
    o.replanar.count_selfint = o.first_selfint;

    uint32_t nruns = o.samples * o.nmagnitudes;
    job j = {.p = p, .o = &o, .ropts = o.replanar,
             .seed = ctx ? ctx->seed : 0};
    if (ctx) {
        j.ctx.cancel = ctx->cancel;
        j.ctx.seed = ctx->seed;
    }
    j.prep = geo_replanar_prepare(p, err);
    if (!j.prep)
        return geo_poly_validate_indices(p, NULL) < 0 ? -EINVAL : -ENOMEM;
    geo_bbox *boxes = malloc((size_t)p->nverts * sizeof *boxes);
    j.runs = calloc(nruns, sizeof *j.runs);
    j.rc = calloc(nruns, sizeof *j.rc);
    ret->rows = calloc(o.nmagnitudes, sizeof *ret->rows);
    if (boxes)
        for (uint32_t v = 0; v < p->nverts; v++)
            for (int k = 0; k < 3; k++)
                boxes[v].lo[k] = boxes[v].hi[k] = p->verts[v][k];
    if (boxes && j.runs && j.rc && ret->rows)
        j.vbvh = geo_bvh_build(boxes, p->nverts, err);
    free(boxes);
    if (!j.vbvh) {
        rc = geo_err_set(err, -ENOMEM, "out of memory");
        goto out;
    }
    /* a first guess of the nearest-vertex distance: the spacing of the
     * vertices if they filled the bounding box */
    j.r0 = geo_poly_size(p) / cbrt((double)p->nverts) * 0.25 + 1e-300;

    uint32_t nbatch = nruns < 20 ? nruns : 20;
    for (uint32_t b = 0; b < nbatch && rc == 0; b++) {
        uint32_t lo = (uint32_t)((uint64_t)nruns * b / nbatch);
        uint32_t hi = (uint32_t)((uint64_t)nruns * (b + 1) / nbatch);
        j.base = lo;
        geo_ctx_parallel_for(ctx, hi - lo, run_one, &j);
        for (uint32_t i = lo; i < hi && rc == 0; i++)
            if (j.rc[i] < 0)
                rc = j.rc[i];
        if (rc == 0)
            rc = geo_ctx_progress(ctx, (double)hi / nruns);
    }
    if (rc < 0) {
        geo_err_set(err, rc, rc == -ECANCELED ? "canceled" : "out of memory");
        goto out;
    }
    ret->samples = o.samples;
    ret->seed = j.seed;
    ret->schedule = o.schedule;
    ret->nrows = o.nmagnitudes;
    tabulate(&o, j.runs, nruns, ret->rows);
    if (o.keep_runs) {
        ret->runs = j.runs;
        ret->nruns = nruns;
        j.runs = NULL;
    }
out:
    if (rc < 0)
        geo_inversion_stats_clear(ret);
    free(j.runs);
    free(j.rc);
    geo_bvh_free(j.vbvh);
    geo_replanar_prep_free(j.prep);
    return rc;
}
