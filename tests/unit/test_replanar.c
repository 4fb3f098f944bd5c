/* test_replanar.c — vertex move and re-planarisation (Palachev 2012, §4): the
 * invariants of every converged result (each vertex within the final bound
 * of each of its facets' planes, the fixed vertex exactly where it was
 * put, the planes through it passing through it), the schedules' K and ε
 * sequences, the local (active-region) run agreeing with the global one,
 * failures reported as such, and bad input rejected with its place. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "correct.h"
#include "cut_shapes.h"
#include "gen_garbage.h"
#include "replanar.h"
#include "tu_load.h"
#include "vec.h"

/* The bound S2 must meet at the end of schedule s (default options). */
static double final_bound(enum geo_replanar_schedule s)
{
    geo_replanar_opts o;
    geo_replanar_opts_default(&o, s);
    if (s != GEO_REPLANAR_LOCAL_EXP)
        return o.eps_final;
    return o.eps0 * pow(o.eps_factor, o.outer_rounds - 1);
}

static void assert_invariants(const geo_poly *p, uint32_t v,
                              const double target[3], double bound)
{
    assert_memory_equal(p->verts[v], target, 3 * sizeof(double));
    for (uint32_t f = 0; f < p->nfacets; f++) {
        const double *pl = p->planes[f];
        assert_true(fabs(geo_vlen(pl) - 1) < 1e-12);
        const uint32_t *idx = geo_poly_facet(p, f);
        for (uint32_t i = 0; i < geo_poly_facet_size(p, f); i++) {
            double e = fabs(geo_plane_eval(pl, p->verts[idx[i]]));
            if (idx[i] == v)
                assert_true(e <= 1e-14 * (1 + geo_vlen(target)));
            else
                assert_true(e < bound);
        }
    }
}

/* The nearest other vertex's distance, by brute force (tests only). */
static double nearest(const geo_poly *p, uint32_t v)
{
    double best = INFINITY;
    for (uint32_t i = 0; i < p->nverts; i++)
        if (i != v && geo_vdist(p->verts[i], p->verts[v]) < best)
            best = geo_vdist(p->verts[i], p->verts[v]);
    return best;
}

static void move_target(const geo_poly *p, uint32_t v, double m,
                        double ret[3])
{
    double dir[3] = {0.36, -0.48, 0.8};
    geo_vmadd(p->verts[v], m * nearest(p, v), dir, ret);
}

static void test_box_corner_move_converges_with_invariants(void **state)
{
    (void)state;
    static const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    for (int s = 0; s <= GEO_REPLANAR_LEAST_NORM; s++) {
        geo_poly *p = tu_box(lo, hi);
        double t[3] = {1.01, 0.995, 1.002};
        geo_replanar_result res;
        geo_err err = {{0}};
        assert_int_equal(geo_move(p, 7, t, (enum geo_replanar_schedule)s,
                                         NULL, NULL, NULL, &res, &err),
                         0);
        assert_true(res.converged);
        assert_true(geo_replanar_result_valid(&res));
        assert_int_equal(res.nselfint, 0);
        assert_int_equal(res.ninverted, 0);
        assert_true(fabs(res.volume - geo_poly_volume(p)) < 1e-12);
        assert_invariants(p, 7, t, final_bound((enum geo_replanar_schedule)s));
        geo_poly_free(p);
    }
}

static void test_scan_move_converges_with_invariants_all_schedules(
    void **state)
{
    (void)state;
    geo_poly *orig = tu_load_model("brilliant.scan-k100.json");
    assert_non_null(orig);
    static const uint32_t verts[] = {5, 700, 1500};
    for (int s = 0; s <= GEO_REPLANAR_LEAST_NORM; s++) {
        for (size_t i = 0; i < sizeof verts / sizeof verts[0]; i++) {
            geo_poly *p = geo_poly_copy(orig);
            double t[3];
            move_target(p, verts[i], 0.001, t);
            geo_replanar_result res;
            geo_err err = {{0}};
            geo_replanar_opts o;
            geo_replanar_opts_default(&o, (enum geo_replanar_schedule)s);
            o.max_steps = 3000;
            assert_int_equal(geo_move(p, verts[i], t,
                                             (enum geo_replanar_schedule)s,
                                             &o, NULL, NULL, &res, &err),
                             0);
            assert_true(res.converged);
            assert_true(res.s2 < final_bound((enum geo_replanar_schedule)s));
            assert_true(geo_replanar_result_valid(&res));
            assert_invariants(p, verts[i], t,
                              final_bound((enum geo_replanar_schedule)s));
            /* the move reaches only part of the stone */
            assert_true(res.active_vertices < orig->nverts);
            geo_poly_free(p);
        }
    }
    geo_poly_free(orig);
}

static void test_local_exp_log_doubles_k_and_halves_eps_per_round(
    void **state)
{
    (void)state;
    geo_poly *p = tu_load_model("brilliant.truth.json");
    assert_non_null(p);
    double t[3];
    move_target(p, 100, 0.01, t);
    geo_replanar_log log = {0};
    geo_replanar_result res;
    assert_int_equal(geo_move(p, 100, t, GEO_REPLANAR_LOCAL_EXP, NULL,
                                     NULL, &log, &res, NULL),
                     0);
    assert_true(res.converged);
    assert_int_equal(log.n, res.steps);
    uint32_t rounds[10] = {0};
    for (size_t i = 0; i < log.n; i++) {
        const geo_replanar_step *r = &log.rows[i];
        assert_int_equal(r->step, i);
        assert_true(r->outer < 10);
        rounds[r->outer]++;
        assert_true(r->k == 100.0 * ldexp(1.0, (int)r->outer));
        assert_true(r->eps0 == 1e-7 * ldexp(1.0, -(int)r->outer));
        assert_int_equal(r->nselfint, -1);
        /* a round ends exactly when S2 drops below its bound */
        bool last = i + 1 == log.n || log.rows[i + 1].outer != r->outer;
        assert_true(last == (r->s2 < r->eps0));
    }
    /* the paper's shape on a clean stone: several steps in the first
     * round, then one per round */
    assert_true(rounds[0] > 1);
    for (int k = 1; k < 10; k++)
        assert_int_equal(rounds[k], 1);
    geo_replanar_log_clear(&log);
    geo_poly_free(p);
}

/* The last S2 of each local-exp round of a run of vertex 100 of the clean
 * stone (m = 0.01) with plane fit fit; rounds[] receives the step counts. */
static geo_replanar_result local_exp_rounds(enum geo_replanar_fit fit,
                                            uint32_t rounds[10],
                                            double last_s2[10])
{
    geo_poly *p = tu_load_model("brilliant.truth.json");
    assert_non_null(p);
    double t[3];
    move_target(p, 100, 0.01, t);
    geo_replanar_opts o;
    geo_replanar_opts_default(&o, GEO_REPLANAR_LOCAL_EXP);
    o.fit = fit;
    geo_replanar_log log = {0};
    geo_replanar_result res;
    assert_int_equal(geo_move(p, 100, t, GEO_REPLANAR_LOCAL_EXP, &o,
                                     NULL, &log, &res, NULL),
                     0);
    assert_true(res.converged);
    memset(rounds, 0, 10 * sizeof *rounds);
    for (size_t i = 0; i < log.n; i++) {
        assert_true(log.rows[i].outer < 10);
        rounds[log.rows[i].outer]++;
        last_s2[log.rows[i].outer] = log.rows[i].s2;
    }
    assert_memory_equal(p->verts[100], t, sizeof t);
    geo_replanar_log_clear(&log);
    geo_poly_free(p);
    return res;
}

/* The paper's §4.3.1 table falls by a steady ×0.33–0.38 per round (one
 * step each) to 4.4e-12: a decay that does not speed up as K doubles.
 * Plain least-squares planes (the moved vertex pulls them only part of
 * the way each step) give that; planes through the moved vertex converge
 * ever faster (×~0.1 per round, to rounding) and leave no residual. */
static void test_paper_fit_gives_the_steady_decay_of_the_paper_table(
    void **state)
{
    (void)state;
    uint32_t rounds[10];
    double s2[10];
    geo_replanar_result all = local_exp_rounds(GEO_REPLANAR_FIT_ALL, rounds,
                                               s2);
    assert_true(rounds[0] >= 20 && rounds[0] <= 45);
    for (int k = 1; k < 10; k++) {
        assert_int_equal(rounds[k], 1);
        if (k >= 2) {
            double q = s2[k] / s2[k - 1];
            assert_true(q > 0.3 && q < 0.5);
        }
    }
    assert_true(s2[9] > 1e-12);
    /* the moved vertex is left off its planes, and that is reported */
    assert_true(all.fixed_resid > 1e-9 && all.fixed_resid < 1e-6);

    geo_replanar_result fixed = local_exp_rounds(
        GEO_REPLANAR_FIT_THROUGH_FIXED, rounds, s2);
    for (int k = 1; k < 10; k++)
        assert_int_equal(rounds[k], 1);
    assert_true(pow(s2[9] / s2[5], 0.25) < 0.2);
    assert_true(fixed.fixed_resid < 1e-14);
}

/* Scaled schedule: each step's K is the previous step's S1/S2sum, or with
 * GEO_REPLANAR_SCALED_K_S2 its S1/S2 (as every row of the paper's §4.3.2
 * and §4.3.5 tables). */
static void test_scaled_k_follows_the_chosen_rule(void **state)
{
    (void)state;
    for (int rule = 0; rule < 2; rule++) {
        geo_poly *p = tu_load_model("brilliant.truth.json");
        assert_non_null(p);
        double t[3];
        move_target(p, 100, 0.01, t);
        geo_replanar_opts o;
        geo_replanar_opts_default(&o, GEO_REPLANAR_SCALED);
        o.scaled_k = (enum geo_replanar_scaled_k)rule;
        geo_replanar_log log = {0};
        geo_replanar_result res;
        assert_int_equal(geo_move(p, 100, t, GEO_REPLANAR_SCALED, &o,
                                         NULL, &log, &res, NULL),
                         0);
        assert_true(res.converged);
        assert_true(log.n > 2);
        assert_true(log.rows[0].k == o.k0);
        for (size_t i = 1; i < log.n; i++) {
            const geo_replanar_step *a = &log.rows[i - 1];
            double want = rule == GEO_REPLANAR_SCALED_K_S2 ? a->s1 / a->s2
                                                            : a->s1 / a->s2sum;
            assert_true(log.rows[i].k == want);
        }
        geo_replanar_log_clear(&log);
        geo_poly_free(p);
    }
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

/* local-exp on 20 vertices of p (m = 0.01): the median of the round-0
 * step counts and the most steps any later round took. */
static void local_exp_profile(const geo_poly *p, uint32_t *ret_median0,
                              uint32_t *ret_max_later)
{
    uint32_t r0[20];
    *ret_max_later = 0;
    for (uint32_t i = 0; i < 20; i++) {
        uint32_t v = 5 + (uint32_t)((uint64_t)i * (p->nverts - 10) / 20);
        geo_poly *q = geo_poly_copy(p);
        double t[3];
        move_target(q, v, 0.01, t);
        geo_replanar_opts o;
        geo_replanar_opts_default(&o, GEO_REPLANAR_LOCAL_EXP);
        o.max_steps = 5000;
        geo_replanar_log log = {0};
        geo_replanar_result res;
        assert_int_equal(geo_move(q, v, t, GEO_REPLANAR_LOCAL_EXP, &o,
                                         NULL, &log, &res, NULL),
                         0);
        assert_true(res.converged);
        uint32_t rounds[10] = {0};
        for (size_t j = 0; j < log.n; j++)
            rounds[log.rows[j].outer]++;
        r0[i] = rounds[0];
        for (int k = 1; k < 10; k++)
            if (rounds[k] > *ret_max_later)
                *ret_max_later = rounds[k];
        geo_replanar_log_clear(&log);
        geo_poly_free(q);
    }
    qsort(r0, 20, sizeof r0[0], cmp_u32);
    *ret_median0 = r0[10];
}

/* The scanner's slivers (facets at hundredths of a degree) are what slows
 * local-exp on a raw scan: once the correction merges them, the scan
 * behaves as the paper's stones (a dozen steps, then a few per round:
 * 15 and 5 measured, where the adjusted planes meet four at a point),
 * the raw scan needs several times more in round 0 and many in later
 * rounds (60 and 56). */
static void test_corrected_scan_converges_like_the_paper_raw_scan_does_not(
    void **state)
{
    (void)state;
    geo_poly *raw = tu_load_model("brilliant.scan-k100.json");
    assert_non_null(raw);
    geo_poly *fixed = geo_poly_copy(raw);
    assert_int_equal(geo_correct(fixed, NULL, NULL, NULL, NULL), 0);
    assert_true(fixed->nverts < raw->nverts / 4);
    uint32_t raw0, raw_later, fix0, fix_later;
    local_exp_profile(raw, &raw0, &raw_later);
    local_exp_profile(fixed, &fix0, &fix_later);
    assert_true(fix0 <= 20);
    assert_true(fix_later <= 6);
    assert_true(raw0 >= 3 * fix0);
    assert_true(raw_later >= 5 * fix_later);
    geo_poly_free(fixed);
    geo_poly_free(raw);
}

static void test_global_exp_multiplies_k_each_step_and_keeps_s1_total(
    void **state)
{
    (void)state;
    geo_poly *p = tu_load_model("brilliant.truth.json");
    assert_non_null(p);
    geo_poly *start = geo_poly_copy(p);
    double t[3];
    move_target(p, 100, 0.01, t);
    geo_replanar_log log = {0};
    geo_replanar_result res;
    geo_replanar_opts o;
    geo_replanar_opts_default(&o, GEO_REPLANAR_GLOBAL_EXP);
    o.k_factor = 1.5;
    assert_int_equal(geo_move(p, 100, t, GEO_REPLANAR_GLOBAL_EXP, &o,
                                     NULL, &log, &res, NULL),
                     0);
    assert_true(res.converged);
    for (size_t i = 0; i < log.n; i++)
        assert_true(fabs(log.rows[i].k - 100.0 * pow(1.5, (double)i)) <
                    1e-9 * log.rows[i].k);
    /* S1 of the last row is the total displacement of the free vertices */
    double s1 = 0;
    for (uint32_t v = 0; v < p->nverts; v++)
        if (v != 100) {
            double d = geo_vdist(p->verts[v], start->verts[v]);
            s1 += d * d;
        }
    assert_true(fabs(s1 - log.rows[log.n - 1].s1) <= 1e-9 * s1);
    geo_replanar_log_clear(&log);
    geo_poly_free(start);
    geo_poly_free(p);
}

static void test_active_region_run_matches_global_run(void **state)
{
    (void)state;
    geo_poly *a = tu_load_model("brilliant.scan-k100.json");
    assert_non_null(a);
    geo_poly *b = geo_poly_copy(a);
    double t[3];
    move_target(a, 900, 0.01, t);
    double move = geo_vdist(t, a->verts[900]);
    geo_replanar_opts o;
    geo_replanar_opts_default(&o, GEO_REPLANAR_GLOBAL_EXP);
    geo_replanar_result ra, rb;
    assert_int_equal(geo_move(a, 900, t, GEO_REPLANAR_GLOBAL_EXP, &o,
                                     NULL, NULL, &ra, NULL),
                     0);
    o.wake_tol = 0; /* every rounding-level change wakes: all facets */
    assert_int_equal(geo_move(b, 900, t, GEO_REPLANAR_GLOBAL_EXP, &o,
                                     NULL, NULL, &rb, NULL),
                     0);
    assert_true(ra.converged && rb.converged);
    assert_true(ra.active_vertices < rb.active_vertices / 2);
    assert_int_equal(rb.active_vertices, a->nverts);
    assert_int_equal(ra.steps, rb.steps);
    /* the same solution up to the resolution of sliver vertices (a plane
     * residual r moves a vertex between planes at angle θ by r/θ) */
    double worst = 0;
    for (uint32_t v = 0; v < a->nverts; v++)
        worst = fmax(worst, geo_vdist(a->verts[v], b->verts[v]));
    assert_true(worst < 1e-3 * move);
    assert_invariants(a, 900, t, final_bound(GEO_REPLANAR_GLOBAL_EXP));
    assert_invariants(b, 900, t, final_bound(GEO_REPLANAR_GLOBAL_EXP));
    geo_poly_free(a);
    geo_poly_free(b);
}

static void test_two_fixed_vertices_of_one_facet_stay_on_its_plane(
    void **state)
{
    (void)state;
    static const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    geo_poly *p = tu_box(lo, hi);
    /* vertices 6 and 7 share the facets z = hi and y = hi */
    p->verts[6][2] += 0.01;
    p->verts[7][0] += 0.005;
    double v6[3], v7[3];
    memcpy(v6, p->verts[6], sizeof v6);
    memcpy(v7, p->verts[7], sizeof v7);
    uint32_t fixed[2] = {6, 7};
    geo_replanar_result res;
    assert_int_equal(geo_replanarize(p, fixed, 2, GEO_REPLANAR_GLOBAL_EXP,
                                     NULL, NULL, NULL, &res, NULL),
                     0);
    assert_true(res.converged);
    assert_memory_equal(p->verts[6], v6, sizeof v6);
    assert_memory_equal(p->verts[7], v7, sizeof v7);
    for (uint32_t f = 0; f < p->nfacets; f++) {
        const uint32_t *idx = geo_poly_facet(p, f);
        for (uint32_t i = 0; i < 4; i++) {
            double e = fabs(geo_plane_eval(p->planes[f], p->verts[idx[i]]));
            assert_true(e < (idx[i] == 6 || idx[i] == 7 ? 1e-14 : 1e-10));
        }
    }
    geo_poly_free(p);
}

static void test_three_noncoplanar_fixed_vertices_in_a_facet_rejected(
    void **state)
{
    (void)state;
    static const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    geo_poly *p = tu_box(lo, hi);
    p->verts[0][2] += 0.1; /* facet z = lo: 0 2 3 1 */
    uint32_t fixed[4] = {0, 1, 2, 3};
    geo_replanar_result res;
    geo_err err = {{0}};
    assert_int_equal(geo_replanarize(p, fixed, 4, GEO_REPLANAR_LOCAL_EXP,
                                     NULL, NULL, NULL, &res, &err),
                     -EINVAL);
    assert_non_null(strstr(err.msg, "facets[0]"));
    assert_true(p->verts[0][2] == 0.1); /* unchanged on error */
    geo_poly_free(p);
}

static void test_bad_input_rejected_naming_the_place(void **state)
{
    (void)state;
    static const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    geo_poly *p = tu_box(lo, hi);
    geo_replanar_result res;
    geo_err err = {{0}};
    double t[3] = {0, 0, 0};
    assert_int_equal(geo_move(p, 8, t, GEO_REPLANAR_LOCAL_EXP, NULL,
                                     NULL, NULL, &res, &err),
                     -EINVAL);
    assert_non_null(strstr(err.msg, "vertex 8"));
    t[1] = NAN;
    assert_int_equal(geo_move(p, 1, t, GEO_REPLANAR_LOCAL_EXP, NULL,
                                     NULL, NULL, &res, &err),
                     -EINVAL);
    assert_non_null(strstr(err.msg, "targets[0]"));
    uint32_t twice[2] = {3, 3};
    assert_int_equal(geo_replanarize(p, twice, 2, GEO_REPLANAR_LOCAL_EXP,
                                     NULL, NULL, NULL, &res, &err),
                     -EINVAL);
    assert_non_null(strstr(err.msg, "fixed[1]"));
    geo_replanar_opts o;
    geo_replanar_opts_default(&o, GEO_REPLANAR_LOCAL_EXP);
    o.k0 = -1;
    assert_int_equal(geo_replanarize(p, twice, 1, GEO_REPLANAR_LOCAL_EXP, &o,
                                     NULL, NULL, &res, &err),
                     -EINVAL);
    enum geo_replanar_schedule s;
    assert_int_equal(geo_replanar_schedule_parse("fast", &s), -EINVAL);
    for (int k = 0; k < 3; k++) {
        assert_int_equal(geo_replanar_schedule_parse(
                             geo_replanar_schedule_name(
                                 (enum geo_replanar_schedule)k),
                             &s),
                         0);
        assert_int_equal(s, k);
    }
    o.k0 = 100;
    o.fit = (enum geo_replanar_fit)7;
    assert_int_equal(geo_replanarize(p, twice, 1, GEO_REPLANAR_LOCAL_EXP, &o,
                                     NULL, NULL, &res, &err),
                     -EINVAL);
    o.fit = GEO_REPLANAR_FIT_ALL;
    o.scaled_k = (enum geo_replanar_scaled_k)7;
    assert_int_equal(geo_replanarize(p, twice, 1, GEO_REPLANAR_SCALED, &o,
                                     NULL, NULL, &res, &err),
                     -EINVAL);
    enum geo_replanar_fit f;
    enum geo_replanar_scaled_k sk;
    assert_int_equal(geo_replanar_fit_parse("loose", &f), -EINVAL);
    assert_int_equal(geo_replanar_scaled_k_parse("s3", &sk), -EINVAL);
    for (int k = 0; k < 2; k++) {
        assert_int_equal(geo_replanar_fit_parse(
                             geo_replanar_fit_name((enum geo_replanar_fit)k),
                             &f),
                         0);
        assert_int_equal(f, k);
        assert_int_equal(geo_replanar_scaled_k_parse(
                             geo_replanar_scaled_k_name(
                                 (enum geo_replanar_scaled_k)k),
                             &sk),
                         0);
        assert_int_equal(sk, k);
    }
    geo_poly_free(p);
}

static void test_budget_exhausted_reports_not_converged(void **state)
{
    (void)state;
    geo_poly *p = tu_load_model("brilliant.scan-k100.json");
    assert_non_null(p);
    double t[3];
    move_target(p, 700, 0.1, t);
    geo_replanar_opts o;
    geo_replanar_opts_default(&o, GEO_REPLANAR_LOCAL_EXP);
    o.max_steps = 3;
    geo_replanar_log log = {0};
    geo_replanar_result res;
    assert_int_equal(geo_move(p, 700, t, GEO_REPLANAR_LOCAL_EXP, &o,
                                     NULL, &log, &res, NULL),
                     0);
    assert_false(res.converged);
    assert_false(geo_replanar_result_valid(&res));
    assert_int_equal(res.steps, 3);
    assert_int_equal(log.n, 3);
    geo_replanar_log_clear(&log);
    geo_poly_free(p);
}

static void test_vertex_pushed_through_the_stone_is_invalid(void **state)
{
    (void)state;
    geo_poly *p = tu_load_model("brilliant.truth.json");
    assert_non_null(p);
    /* the lowest vertex (the culet) pushed up through the table */
    uint32_t low = 0;
    for (uint32_t v = 1; v < p->nverts; v++)
        if (p->verts[v][2] < p->verts[low][2])
            low = v;
    double lo[3], hi[3], t[3];
    geo_poly_bbox(p, lo, hi);
    memcpy(t, p->verts[low], sizeof t);
    t[2] = hi[2] + 0.5 * (hi[2] - lo[2]);
    geo_replanar_opts o;
    geo_replanar_opts_default(&o, GEO_REPLANAR_SCALED);
    o.count_selfint = true;
    geo_replanar_log log = {0};
    geo_replanar_result res;
    assert_int_equal(geo_move(p, low, t, GEO_REPLANAR_SCALED, &o,
                                     NULL, &log, &res, NULL),
                     0);
    assert_false(geo_replanar_result_valid(&res));
    assert_true(res.nselfint > 0);
    assert_true(res.first_selfint_step >= 0);
    /* the log counts self-intersections from that step on */
    assert_true(log.rows[res.first_selfint_step].nselfint > 0);
    for (int64_t i = 0; i < res.first_selfint_step; i++)
        assert_int_equal(log.rows[i].nselfint, 0);
    geo_replanar_log_clear(&log);
    geo_poly_free(p);
}

static int cancel_now(void *user, double fraction)
{
    (void)user;
    return fraction >= 0; /* always */
}

static void test_cancel_stops_with_ecanceled(void **state)
{
    (void)state;
    geo_poly *p = tu_load_model("brilliant.truth.json");
    assert_non_null(p);
    geo_poly *copy = geo_poly_copy(p);
    double t[3];
    move_target(p, 10, 0.1, t);
    geo_ctx ctx = {.progress = cancel_now};
    geo_replanar_result res;
    geo_err err = {{0}};
    assert_int_equal(geo_move(p, 10, t, GEO_REPLANAR_LOCAL_EXP, NULL,
                                     &ctx, NULL, &res, &err),
                     -ECANCELED);
    assert_memory_equal(p->verts, copy->verts,
                        p->nverts * sizeof p->verts[0]);
    geo_poly_free(copy);
    geo_poly_free(p);
}

/* The largest move of a vertex other than v between a and b. */
static double largest_other_move(const geo_poly *a, const geo_poly *b,
                                 uint32_t v)
{
    double m = 0;
    for (uint32_t i = 0; i < a->nverts; i++)
        if (i != v && geo_vdist(a->verts[i], b->verts[i]) > m)
            m = geo_vdist(a->verts[i], b->verts[i]);
    return m;
}

/* A vertex of the raw k400 scan moved by δ = 0.034 µm: least-norm moves
 * no other vertex by more than 2δ, where the alternating local-exp spreads
 * it along slivers (4.7δ, 7.9δ, 2.8δ for these three when written) — so
 * the bound is one the paper's schedule does not meet. */
static void test_least_norm_keeps_a_local_edit_local(void **state)
{
    (void)state;
    geo_poly *orig = tu_load_model("brilliant.scan-k400.json");
    assert_non_null(orig);
    static const uint32_t verts[] = {1000, 2000, 3000};
    const double delta = 3.4e-5;
    double worst_local_exp = 0;
    for (size_t i = 0; i < sizeof verts / sizeof verts[0]; i++) {
        uint32_t v = verts[i];
        double t[3];
        memcpy(t, orig->verts[v], sizeof t);
        t[0] += delta;
        geo_poly *p = geo_poly_copy(orig);
        geo_replanar_result res;
        geo_err err = {{0}};
        assert_int_equal(geo_move(p, v, t, GEO_REPLANAR_LEAST_NORM, NULL,
                                  NULL, NULL, &res, &err),
                         0);
        assert_true(geo_replanar_result_valid(&res));
        assert_invariants(p, v, t, final_bound(GEO_REPLANAR_LEAST_NORM));
        assert_true(largest_other_move(orig, p, v) <= 2 * delta);
        /* a vertex the move did not reach is exactly where it was */
        assert_true(res.active_vertices < orig->nverts);
        geo_poly_free(p);
        p = geo_poly_copy(orig);
        assert_int_equal(geo_move(p, v, t, GEO_REPLANAR_LOCAL_EXP, NULL,
                                  NULL, NULL, &res, &err),
                         0);
        double m = largest_other_move(orig, p, v);
        if (m > worst_local_exp)
            worst_local_exp = m;
        geo_poly_free(p);
    }
    assert_true(worst_local_exp > 2 * delta);
    geo_poly_free(orig);
}

/* A triangle is planar whatever its corners do: on a triangle mesh the
 * least-norm move leaves every other vertex where it was. */
static void test_least_norm_on_triangles_moves_nothing_else(void **state)
{
    (void)state;
    geo_poly *tri = cs_sphere(8, 12, 0);
    assert_non_null(tri);
    geo_poly *p = geo_poly_copy(tri);
    double t[3];
    geo_vadd(tri->verts[7], (const double[3]){0.01, -0.005, 0.002}, t);
    geo_replanar_result res;
    geo_err err = {{0}};
    assert_int_equal(geo_move(p, 7, t, GEO_REPLANAR_LEAST_NORM, NULL, NULL,
                              NULL, &res, &err),
                     0);
    assert_true(geo_replanar_result_valid(&res));
    assert_true(largest_other_move(tri, p, 7) == 0);
    geo_replanar_opts o;
    geo_replanar_opts_default(&o, GEO_REPLANAR_LEAST_NORM);
    o.fit = GEO_REPLANAR_FIT_ALL;
    assert_int_equal(geo_move(p, 7, t, GEO_REPLANAR_LEAST_NORM, &o, NULL,
                              NULL, &res, &err),
                     -EINVAL);
    assert_non_null(strstr(err.msg, "fit all"));
    geo_poly_free(p);
    geo_poly_free(tri);
}

/* Least-norm on random garbage (non-manifold edges, repeated and
 * collinear points, self-intersecting and non-planar facets): an answer
 * or a refusal, never a crash or a hang; a converged one has the moved
 * vertex where it was put. */
static void test_least_norm_on_garbage_answers_or_refuses(void **state)
{
    (void)state;
    uint64_t rng = 0x5eed1e55;
    for (int i = 0; i < 300; i++) {
        geo_poly *p = gen_garbage_model(&rng);
        assert_non_null(p);
        double t[3];
        geo_vadd(p->verts[0], (const double[3]){1e-3, -2e-3, 5e-4}, t);
        geo_replanar_result res;
        geo_err err = {{0}};
        int r = geo_move(p, 0, t, GEO_REPLANAR_LEAST_NORM, NULL, NULL, NULL,
                         &res, &err);
        if (r != 0 && r != -EINVAL && r != -EDOM && r != -ERANGE)
            fail_msg("model %d: %d (%s)", i, r, err.msg);
        if (r == 0 && res.converged)
            assert_memory_equal(p->verts[0], t, sizeof t);
        geo_poly_free(p);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_box_corner_move_converges_with_invariants),
        cmocka_unit_test(
            test_scan_move_converges_with_invariants_all_schedules),
        cmocka_unit_test(
            test_local_exp_log_doubles_k_and_halves_eps_per_round),
        cmocka_unit_test(
            test_global_exp_multiplies_k_each_step_and_keeps_s1_total),
        cmocka_unit_test(test_active_region_run_matches_global_run),
        cmocka_unit_test(
            test_paper_fit_gives_the_steady_decay_of_the_paper_table),
        cmocka_unit_test(test_scaled_k_follows_the_chosen_rule),
        cmocka_unit_test(
            test_corrected_scan_converges_like_the_paper_raw_scan_does_not),
        cmocka_unit_test(
            test_two_fixed_vertices_of_one_facet_stay_on_its_plane),
        cmocka_unit_test(
            test_three_noncoplanar_fixed_vertices_in_a_facet_rejected),
        cmocka_unit_test(test_bad_input_rejected_naming_the_place),
        cmocka_unit_test(test_budget_exhausted_reports_not_converged),
        cmocka_unit_test(test_vertex_pushed_through_the_stone_is_invalid),
        cmocka_unit_test(test_cancel_stops_with_ecanceled),
        cmocka_unit_test(test_least_norm_keeps_a_local_edit_local),
        cmocka_unit_test(test_least_norm_on_triangles_moves_nothing_else),
        cmocka_unit_test(test_least_norm_on_garbage_answers_or_refuses),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
