/* replanar.h — moving vertices of a polyhedron and restoring the planarity
 * of its facets (Palachev 2012, §4, variant 3 of §4.2.3): alternate
 *   (a) least-squares planes of the facets (by default a facet through a
 *       fixed vertex is fitted through that vertex exactly), and
 *   (b) per-vertex penalised positions: every free vertex x minimises
 *       |x − x0|² + K Σ_f (n_f·x + d_f)² over its facets f, i.e. solves
 *       the 3×3 SPD system (I + K Σ n nᵀ) x = x0 − K Σ n d,
 * under one of three schedules for K and the stopping bound (§4.3.1–3).
 *
 * Quantities of the iteration log (units: mm, mm²):
 *   Δ   = Σ |x⁽ⁿ⁺¹⁾ − x⁽ⁿ⁾|² over the free vertices: the step's displacement
 *         (the first term of the §4.3.1 functional);
 *   S1  = Σ |x − x_start|² over the free vertices: the total displacement
 *         from the start (§4.3.2);
 *   S2  = max |n_f·x_v + d_f| over the incidences of the free vertices v
 *         with their facets f, with the planes of the step: the plane
 *         error, a distance. Every bound the schedules test (ε, ε₀, 1e-10)
 *         is a bound on S2;
 *   S2sum = Σ (n_f·x_v + d_f)² over the same incidences: the penalty term
 *         of the functional (J = S1 + K·S2sum).
 * Why S2 is a distance: in the paper's §4.3.1 table the error decays by
 * 0.62 per step while Δ decays by 0.39 = 0.62², so the error is linear in
 * the residuals and Δ quadratic. A mean or RMS over all incidences is
 * ruled out by scale: the paper's first row has Δ/ε² ≈ 65 (and 60 in the
 * §4.3.2 run); the maximum gives 30–600 on the sample stones, a mean
 * 10⁵–10⁸. The fixed vertices are left out as in the paper's sums
 * (i = 1 … N−1); with the default fit they lie on their planes anyway, and
 * ret->fixed_resid reports their distance.
 *
 * Only what can change is recomputed: the active facets start as the
 * facets through a fixed vertex (and any facet whose start residual
 * exceeds wake_tol·geo_poly_eps); a vertex is active when one of its
 * facets is; a free vertex that gets farther than wake_tol·geo_poly_eps
 * from its start activates all its facets for the next step. Inactive
 * vertices and planes are exactly those of the start, so every incidence
 * that can change touches an active vertex, and S2 (taken over those) is
 * the true maximum. The active set only grows, by adjacency, from the
 * fixed vertices; it degenerates to the whole model, O(corners) per step,
 * when the disturbance reaches everywhere (large moves, or wake_tol = 0).
 * The result differs from the global iteration's by the resolution of
 * sliver vertices only (on the sample scans ~1e-8 mm for moves of 1e-4 mm:
 * a vertex between two planes at angle θ moves by r/θ for a residual r).
 *
 * Self-intersections (opts.count_selfint, opts.check) are counted over the
 * pairs with at least one active facet, with the exact tests of
 * lib/inspect/selfint.h: the rest of the model is as at the start.
 *
 * All functions are reentrant; a geo_replanar_prep is read-only after
 * geo_replanar_prepare and may be shared by concurrent solves. */
#ifndef GEO_REPLANAR_H
#define GEO_REPLANAR_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ctx.h"
#include "poly.h"

enum geo_replanar_schedule {
    /* §4.3.1: the step is minimised (x0 = the previous iterate); inner loop
     * until S2 < ε, then K ×= k_factor, ε ×= eps_factor; outer_rounds
     * rounds. */
    GEO_REPLANAR_LOCAL_EXP = 0,
    /* §4.3.2: the step is minimised; after each step K = S1 / S2sum (or
     * S1 / S2, opts.scaled_k); until S2 < eps_final. */
    GEO_REPLANAR_SCALED = 1,
    /* §4.3.3: the total displacement is minimised (x0 = the start
     * position); K ×= k_factor each step until S2 < eps_final. */
    GEO_REPLANAR_GLOBAL_EXP = 2,
    /* Not the paper's: the free vertices nearest their start in the sum
     * of squares such that every facet is planar, the planes free
     * (least_norm.h); Gauss–Newton steps, each one sparse factorisation,
     * until S2 < eps_final (at most max_steps, capped at 50). A move is
     * taken up by the planes wherever they can turn, so it stays local
     * where the alternating schedules spread it along slivers. No penalty:
     * the log's k is 0. The default of facet move and the move op. */
    GEO_REPLANAR_LEAST_NORM = 3,
};

/* Name "local-exp", "scaled", "global-exp", "least-norm"; parse returns -EINVAL for an
 * unknown name (ret untouched). */
const char *geo_replanar_schedule_name(enum geo_replanar_schedule s);
int geo_replanar_schedule_parse(const char *name,
                                enum geo_replanar_schedule *ret);

/* How the planes of facets through fixed vertices are fitted (step (a)). */
enum geo_replanar_fit {
    /* §4.2.1: the moved vertex lies in its facets exactly: the plane is
     * fitted through it (through the line of two, or to three or more
     * alone). The result is planar at the fixed vertices. */
    GEO_REPLANAR_FIT_THROUGH_FIXED = 0,
    /* The paper's §4.3 runs as their logs show them: every plane is the
     * plain least-squares plane of all its vertices, fixed ones included,
     * so the planes reach the fixed vertex only gradually. Reproduces the
     * tables' shapes (see README); the result leaves each fixed vertex
     * off its planes by ret->fixed_resid (up to ~1e-7 mm on the sample
     * stones), more than the planarity tolerance. */
    GEO_REPLANAR_FIT_ALL = 1,
};

/* The scaled schedule's penalty after each step. */
enum geo_replanar_scaled_k {
    /* K = S1 / S2sum: the two terms of J of one order; independent of the
     * move's scale. */
    GEO_REPLANAR_SCALED_K_S2SUM = 0,
    /* K = S1 / S2, the rule of the paper's §4.3.2 and §4.3.5 tables (each
     * row's K is the previous row's S1/S2 to all printed digits). K then
     * scales with the move, so small moves take thousands of steps. */
    GEO_REPLANAR_SCALED_K_S2 = 1,
};

/* Names "through-fixed", "all", "s2sum", "s2"; parse returns -EINVAL for
 * an unknown name (ret untouched). */
const char *geo_replanar_fit_name(enum geo_replanar_fit f);
int geo_replanar_fit_parse(const char *name, enum geo_replanar_fit *ret);
const char *geo_replanar_scaled_k_name(enum geo_replanar_scaled_k k);
int geo_replanar_scaled_k_parse(const char *name,
                                enum geo_replanar_scaled_k *ret);

typedef struct geo_replanar_opts {
    double k0;           /* first penalty K [100] */
    double k_factor;     /* local-exp: K × per round [2]; global-exp: K × per
                            step [2] (the paper also uses 1.005) */
    double eps0;         /* local-exp: first inner bound on S2, mm [1e-7] */
    double eps_factor;   /* local-exp: ε × per round [0.5] */
    uint32_t outer_rounds; /* local-exp: rounds [10] */
    double eps_final;    /* scaled, global-exp: stop when S2 < this, mm
                            [1e-10] */
    uint32_t max_steps;  /* step budget; beyond it "did not converge" [2000] */
    double wake_tol;     /* a vertex moving more than wake_tol · geo_poly_eps
                            from its start activates its facets [1e-2] */
    bool count_selfint;  /* count self-intersections after every step (log
                            column; also gives first_selfint_step) */
    bool check;          /* inspect the result (self-intersections,
                            orientation) [true] */
    enum geo_replanar_fit fit; /* [GEO_REPLANAR_FIT_THROUGH_FIXED] */
    enum geo_replanar_scaled_k scaled_k; /* scaled: the rule for K
                            [GEO_REPLANAR_SCALED_K_S2SUM] */
} geo_replanar_opts;

/* The paper's defaults for schedule s (k_factor 2 for global-exp). */
void geo_replanar_opts_default(geo_replanar_opts *o,
                               enum geo_replanar_schedule s);

/* One row of the iteration log (the paper's tables). */
typedef struct geo_replanar_step {
    uint32_t step;    /* 0-based step number (the paper's "цикл 2") */
    uint32_t outer;   /* local-exp round; least-norm: the region's rings;
                         for the others equal to step */
    uint32_t inner;   /* step within the round (local-exp) or the region
                         (least-norm), else step */
    double delta;     /* Δ, mm² */
    double s1;        /* S1, mm² */
    double s2;        /* S2, mm */
    double s2sum;     /* S2sum, mm² */
    double eps0;      /* the bound S2 was tested against, mm */
    double k;         /* the penalty of this step */
    int64_t nselfint; /* self-intersecting facet pairs after the step, or −1
                         when not counted */
    uint32_t active_vertices, active_facets;
} geo_replanar_step;

/* A growing array of rows; zero-initialise, release with
 * geo_replanar_log_clear. */
typedef struct geo_replanar_log {
    geo_replanar_step *rows;
    size_t n, cap;
} geo_replanar_log;

void geo_replanar_log_clear(geo_replanar_log *log);

/* What a run did and what its result is. */
typedef struct geo_replanar_result {
    bool converged;         /* every stopping bound met within the budget */
    uint32_t steps;         /* steps run */
    double s1, s2;          /* of the last step */
    double k;               /* of the last step */
    uint32_t active_vertices, active_facets;
    /* Inspection (opts.check): −1 when not inspected. */
    int64_t nselfint;       /* facet pairs intersecting other than along
                               shared edges/vertices, incl. a facet with
                               itself when its polygon self-intersects;
                               pairs with an active facet only */
    int64_t ninverted;      /* facets whose plane turned by more than 90°
                               from its start, or whose polygon winds
                               against its plane (Newell · n ≤ 0) */
    double volume;          /* signed volume of the result */
    int64_t first_selfint_step; /* with count_selfint: the first step
                                   with a self-intersection, else −1 */
    double fixed_resid;     /* max |n·x + d| of a fixed vertex against the
                               planes of its facets, mm: rounding with
                               GEO_REPLANAR_FIT_THROUGH_FIXED */
} geo_replanar_result;

/* True when the result is usable: converged, no self-intersection, no
 * inverted facet and positive volume (all inspected). */
bool geo_replanar_result_valid(const geo_replanar_result *r);

/* Precomputed, read-only data of a model for many solves: vertex → facet
 * incidences, the least-squares planes of the start (normal oriented like
 * the facet's Newell vector), each facet's residual against it, the
 * facets' bounding-volume hierarchy, the volume. */
typedef struct geo_replanar_prep geo_replanar_prep;

/* Builds the prep of p (copied: p may change or go afterwards). p must
 * have valid indices. NULL on error (err set; -ENOMEM or -EINVAL). */
geo_replanar_prep *geo_replanar_prepare(const geo_poly *p, geo_err *err);

/* Releases; accepts NULL; returns NULL. */
geo_replanar_prep *geo_replanar_prep_free(geo_replanar_prep *prep);


/* Re-planarises the prepared model after placing fixed[i] at targets[i]
 * (nfixed ≥ 0 distinct vertex indices; targets NULL keeps them where they
 * are). opts NULL means geo_replanar_opts_default(schedule). log may be
 * NULL; rows are appended. ret receives the summary (required). If
 * ret_poly is non-NULL it must have the prep's facets (a copy of
 * geo_replanar_prep_poly): its vertices and planes receive the result.
 *
 * Facets through fixed vertices (opts.fit = GEO_REPLANAR_FIT_THROUGH_FIXED,
 * the default): with one, the plane is the least-squares plane through it (smallest eigenvector of Σ (x − p)(x − p)ᵀ); with two,
 * the least-squares plane through the line of both; with three or more,
 * the least-squares plane of the fixed vertices alone, and the call fails
 * with -EINVAL when they are not coplanar within geo_poly_eps. With
 * GEO_REPLANAR_FIT_ALL every plane is the plain least-squares plane.
 *
 * Returns 0 (also when the run did not converge: see ret->converged),
 * -EINVAL (bad index, duplicate fixed vertex, non-finite target,
 * overdetermined facet), -ENOMEM, or -ECANCELED (ctx). Thread-safe for
 * distinct ret/log/ret_poly. */
int geo_replanar_solve(const geo_replanar_prep *prep, uint32_t nfixed,
                       const uint32_t *fixed, const double (*targets)[3],
                       enum geo_replanar_schedule schedule,
                       const geo_replanar_opts *opts, const geo_ctx *ctx,
                       geo_replanar_log *log, geo_replanar_result *ret,
                       geo_poly *ret_poly, geo_err *err);

/* geo_replanar_prepare + geo_replanar_solve in place: the fixed vertices
 * keep their current positions, every other vertex and every plane of p
 * may change. p is unchanged on error. */
int geo_replanarize(geo_poly *p, const uint32_t *fixed, uint32_t nfixed,
                    enum geo_replanar_schedule schedule,
                    const geo_replanar_opts *opts, const geo_ctx *ctx,
                    geo_replanar_log *log, geo_replanar_result *ret,
                    geo_err *err);

/* Moves vertex v of p to target, fixes it there and re-planarises
 * (geo_replanarize with one fixed vertex); ret tells whether the result
 * converged and is valid (opts.check). p is unchanged on error. */
int geo_move(geo_poly *p, uint32_t v, const double target[3],
                    enum geo_replanar_schedule schedule,
                    const geo_replanar_opts *opts, const geo_ctx *ctx,
                    geo_replanar_log *log, geo_replanar_result *ret,
                    geo_err *err);

#endif
