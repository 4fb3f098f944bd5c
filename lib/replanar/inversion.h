/* inversion.h — inversion statistics of the vertex move (Palachev 2012, §4.3.4,
 * §4.3.5): how often re-planarisation after moving one vertex by a
 * fraction m of the distance to its nearest vertex breaks the polyhedron.
 *
 * For each of N samples: a random vertex v, δ = the distance from v to its
 * nearest other vertex (found with a BVH over the vertices), a random unit
 * direction u (uniform on the sphere); then for every magnitude m one run
 * moves v to v + m·δ·u and re-planarises (lib/replanar/replanar.h). A run counts as
 * inverted when it does not converge within the step budget, when the
 * result has a self-intersection, an inverted facet, or a non-positive
 * volume.
 *
 * Determinism: sample s draws from its own generator seeded by
 * (ctx->seed, s), and runs are independent, so the result is the same for
 * any thread count and any order of execution. Runs are spread over
 * geo_ctx_parallel_for; progress is reported between batches from the
 * calling thread only. Thread-safe for distinct ret. */
#ifndef GEO_INVERSION_H
#define GEO_INVERSION_H

#include <stdbool.h>
#include <stdint.h>

#include "ctx.h"
#include "poly.h"
#include "replanar.h"

#define GEO_INVERSION_MAX_MAGNITUDES 64

typedef struct geo_inversion_opts {
    uint32_t samples;           /* N [100], at most 1,000,000 */
    uint32_t nmagnitudes;       /* [10] */
    double magnitudes[GEO_INVERSION_MAX_MAGNITUDES]; /* m, each > 0 and
                                   finite [1 .5 .1 .05 .01 .005 .001 .0005
                                   .0001 .00005] */
    enum geo_replanar_schedule schedule; /* [scaled, the schedule of the
                                   paper's §4.3.5 runs] */
    geo_replanar_opts replanar; /* per-run options [defaults of the
                                   schedule]; check is forced on */
    bool keep_runs;             /* fill ret->runs */
    bool first_selfint;         /* count self-intersections every step to
                                   record each run's first one (slower) */
} geo_inversion_opts;

/* The paper's set-up (see the brackets above). */
void geo_inversion_opts_default(geo_inversion_opts *o);

/* One run (kept with keep_runs). */
typedef struct geo_inversion_run {
    uint32_t sample, vertex;
    double m, delta;            /* magnitude, nearest-vertex distance (mm) */
    double dir[3];              /* unit direction */
    bool inverted;              /* any failure below */
    bool converged;
    int64_t nselfint, ninverted;
    double volume;
    uint32_t steps;
    int64_t first_selfint_step; /* −1 none or not tracked */
} geo_inversion_run;

/* One line of the table: magnitude m. */
typedef struct geo_inversion_row {
    double m;
    uint32_t runs, inverted;
    double p, lo, hi;           /* inverted / runs and its 95 % Wilson
                                   score interval */
    uint32_t not_converged, selfint, inverted_facets, nonpositive_volume;
} geo_inversion_row;

typedef struct geo_inversion_stats {
    uint32_t samples;
    uint64_t seed;
    enum geo_replanar_schedule schedule;
    uint32_t nrows;
    geo_inversion_row *rows;    /* nrows, in the order of opts.magnitudes */
    uint32_t nruns;
    geo_inversion_run *runs;    /* samples × nrows (sample-major) or NULL */
} geo_inversion_stats;

/* Releases ret's arrays and zeroes it; accepts NULL. */
void geo_inversion_stats_clear(geo_inversion_stats *s);

/* The 95 % Wilson score interval of k successes in n trials
 * (n = 0 gives [0, 1]). */
void geo_wilson95(uint32_t k, uint32_t n, double *ret_lo, double *ret_hi);

/* Runs the statistics on p (not modified; it needs ≥ 2 vertices). opts
 * NULL means the defaults; ctx gives the seed, the parallel loop,
 * progress and cancellation. Returns 0 with *ret filled (caller clears),
 * -EINVAL (bad options or model), -ENOMEM, or -ECANCELED (ret then
 * empty). */
int geo_inversion_stats_run(const geo_poly *p, const geo_inversion_opts *opts,
                            const geo_ctx *ctx, geo_inversion_stats *ret,
                            geo_err *err);

#endif
