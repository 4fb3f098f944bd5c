/* test_frep.c — F-rep objects: each shape's function and gradient, the
 * interval bound encloses every sampled value, a specialised program
 * agrees with the whole one inside its box, smooth pieces, projection, and
 * the frep-object/1 reader's errors naming their place. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "frep.h"
#include "frep_json.h"
#include "gen_frep.h"
#include "vec.h"

static const double LO[3] = {-1, -1, -1}, HI[3] = {1, 1, 1};

static geo_frep *from_json(json_t *j)
{
    geo_err err = {{0}};
    geo_frep *f = proto_frep_from_json(j, NULL, NULL, &err);
    if (!f)
        fail_msg("%s", err.msg);
    json_decref(j);
    return f;
}

static void test_shapes_evaluate_their_formulas(void **state)
{
    (void)state;
    geo_frep *f = geo_frep_new();
    double c[3] = {0.1, 0.2, 0.3}, r[3] = {0.5, 0.4, 0.3};
    double q[10] = {1, 2, 3, 0.5, -0.25, 0.125, 1, -1, 2, -0.5};
    double pl[4] = {0, 0, 2, -1};
    int64_t s = geo_frep_sphere(f, c, 0.5, NULL);
    int64_t e = geo_frep_ellipsoid(f, c, r, NULL);
    int64_t qd = geo_frep_quadric(f, q, NULL);
    int64_t h = geo_frep_halfspace(f, pl, NULL);
    uint32_t ids[2] = {(uint32_t)s, (uint32_t)h};
    double p[3] = {0.3, -0.1, 0.45}, d[3];
    geo_vsub(p, c, d);
    struct {
        int64_t id;
        double want;
    } cases[] = {
        {s, 0.25 - geo_vdot(d, d)},
        {e, 1 - (d[0] / 0.5) * (d[0] / 0.5) - (d[1] / 0.4) * (d[1] / 0.4) -
                (d[2] / 0.3) * (d[2] / 0.3)},
        {qd, q[0] * p[0] * p[0] + q[1] * p[1] * p[1] + q[2] * p[2] * p[2] +
                 q[3] * p[0] * p[1] + q[4] * p[1] * p[2] + q[5] * p[0] * p[2] +
                 q[6] * p[0] + q[7] * p[1] + q[8] * p[2] + q[9]},
        {h, -(2 * p[2] - 1)},
        {geo_frep_union(f, 2, ids, NULL), 0},
        {geo_frep_intersection(f, 2, ids, NULL), 0},
        {geo_frep_difference(f, ids[0], ids[1], NULL), 0},
    };
    double fs = cases[0].want, fh = cases[3].want;
    cases[4].want = fmax(fs, fh);
    cases[5].want = fmin(fs, fh);
    cases[6].want = fmin(fs, -fh);
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        assert_true(cases[k].id >= 0);
        assert_int_equal(geo_frep_finish(f, (uint32_t)cases[k].id, LO, HI,
                                         NULL),
                         0);
        assert_true(fabs(geo_frep_eval(f, p) - cases[k].want) < 1e-14);
    }
    geo_frep_free(f);
}

static void test_perturbation_adds_cubed_positive_part(void **state)
{
    (void)state;
    geo_frep *f = geo_frep_new();
    double c0[3] = {0, 0, 0}, c1[3] = {0.5, 0, 0};
    int64_t base = geo_frep_sphere(f, c0, 0.6, NULL);
    int64_t bump = geo_frep_sphere(f, c1, 0.3, NULL);
    uint32_t t = (uint32_t)bump;
    double amp = 40.0;
    int64_t pt = geo_frep_perturbed(f, (uint32_t)base, 1, &t, &amp, NULL);
    assert_int_equal(geo_frep_finish(f, (uint32_t)pt, LO, HI, NULL), 0);
    double in[3] = {0.55, 0.05, 0}, out[3] = {-0.55, 0.05, 0};
    double qin = 0.09 - (0.05 * 0.05 + 0.05 * 0.05);
    assert_true(fabs(geo_frep_eval(f, in) -
                     (0.36 - (0.55 * 0.55 + 0.0025) + amp * qin * qin * qin)) <
                1e-14);
    /* outside the term's support R = 0: the base alone */
    assert_true(fabs(geo_frep_eval(f, out) - (0.36 - 0.3025 - 0.0025)) <
                1e-14);
    geo_frep_free(f);
}

static void test_gradient_matches_finite_differences(void **state)
{
    (void)state;
    geo_frep *f = from_json(gf_blob(7, 20));
    uint64_t rng = 5;
    for (int it = 0; it < 200; it++) {
        double p[3], g[3];
        for (int k = 0; k < 3; k++)
            p[k] = 0.9 * (2 * geo_rand_unit(&rng) - 1) * 0.6;
        geo_frep_eval_grad(f, p, g);
        for (int k = 0; k < 3; k++) {
            double h = 1e-6, a[3] = {p[0], p[1], p[2]}, b[3] = {p[0], p[1], p[2]};
            a[k] += h;
            b[k] -= h;
            double fd = (geo_frep_eval(f, a) - geo_frep_eval(f, b)) / (2 * h);
            assert_true(fabs(fd - g[k]) <= 1e-5 * (1 + fabs(g[k])));
        }
    }
    geo_frep_free(f);
}

static void test_interval_encloses_samples_and_pruning_agrees(void **state)
{
    (void)state;
    json_t *objs[] = {gf_blob(3, 83), gf_gem(), gf_two_spheres(), gf_torus()};
    for (size_t o = 0; o < 4; o++) {
        geo_frep *f = from_json(objs[o]);
        uint32_t n;
        const geo_frep_op *prog = geo_frep_program(f, &n);
        geo_frep_op *pr = malloc(n * sizeof *pr);
        double *scratch = malloc(2 * n * sizeof *scratch);
        uint64_t rng = 11 + o;
        uint32_t shorter = 0;
        for (int it = 0; it < 300; it++) {
            double lo[3], hi[3], r[2];
            double size = it % 2 ? 0.05 : 0.4;
            for (int k = 0; k < 3; k++) {
                lo[k] = (2 * geo_rand_unit(&rng) - 1) * 0.7;
                hi[k] = lo[k] + size * geo_rand_unit(&rng);
            }
            uint32_t m = geo_frep_specialize(f, prog, n, lo, hi, r, pr,
                                             scratch);
            assert_true(m >= 1 && m <= n);
            shorter += m < n;
            for (int s = 0; s < 20; s++) {
                double p[3];
                for (int k = 0; k < 3; k++)
                    p[k] = lo[k] + (hi[k] - lo[k]) * geo_rand_unit(&rng);
                double v = geo_frep_eval(f, p);
                double tol = 1e-12 * (1 + fabs(v));
                assert_true(v >= r[0] - tol && v <= r[1] + tol);
                assert_true(fabs(geo_frep_run(f, pr, m, p) - v) <= tol);
            }
        }
        /* small boxes see few terms: the point of specialising */
        assert_true(shorter > 100);
        free(pr), free(scratch);
        geo_frep_free(f);
    }
}

static void test_pieces_meet_at_gem_edges_and_projection_lands(void **state)
{
    (void)state;
    json_t *j = gf_gem();
    double *planes;
    int np = gf_halfspaces(j, &planes);
    geo_frep *f = from_json(j);
    double *segs;
    int ns = gf_polytope_edges((const double(*)[4])planes, np, &segs);
    assert_true(ns > 100);
    for (int s = 0; s < ns; s++) {
        double mid[3];
        for (int k = 0; k < 3; k++)
            mid[k] = 0.5 * (segs[6 * s + k] + segs[6 * s + 3 + k]);
        uint32_t pc[4];
        /* an edge's midpoint lies on exactly two facet planes */
        assert_int_equal(geo_frep_pieces_at(f, mid, 1e-9, pc, 4), 2);
        double p[3] = {mid[0] * 0.97, mid[1] * 0.97, mid[2] * 0.97};
        double dev = geo_frep_project(f, p, 1e-13, 0.1);
        assert_true(dev <= 1e-13);
        assert_true(fabs(geo_frep_eval(f, p)) <= 1e-13);
    }
    free(segs), free(planes);
    geo_frep_free(f);
}

static void expect_error(const char *json, const char *want)
{
    geo_err err = {{0}};
    geo_frep *f = proto_frep_read_mem(json, strlen(json), NULL, &err);
    assert_null(f);
    if (!strstr(err.msg, want))
        fail_msg("got \"%s\", want \"%s\"", err.msg, want);
}

/* A cube [-0.5, 0.5]³ as six half-spaces: pieces are its faces. */
static geo_frep *cube(void)
{
    geo_frep *f = geo_frep_new();
    uint32_t ids[6];
    for (int k = 0; k < 6; k++) {
        double pl[4] = {0, 0, 0, -0.5};
        pl[k / 2] = k % 2 ? -1 : 1;
        ids[k] = (uint32_t)geo_frep_halfspace(f, pl, NULL);
    }
    int64_t root = geo_frep_intersection(f, 6, ids, NULL);
    assert_int_equal(geo_frep_finish(f, (uint32_t)root, LO, HI, NULL), 0);
    return f;
}

static void test_projection_onto_pieces_lands_on_faces_edges_corners(void **state)
{
    (void)state;
    geo_frep *f = cube();
    uint32_t px[4], py[4], pz[4];
    double on_x[3] = {0.5, 0.1, 0.2}, on_y[3] = {0.1, 0.5, 0.2},
           on_z[3] = {0.1, 0.2, 0.5};
    assert_int_equal(geo_frep_pieces_at(f, on_x, 1e-12, px, 4), 1);
    assert_int_equal(geo_frep_pieces_at(f, on_y, 1e-12, py, 4), 1);
    assert_int_equal(geo_frep_pieces_at(f, on_z, 1e-12, pz, 4), 1);
    /* one piece: straight onto the face x = 0.5 */
    double p[3] = {0.3, 0.1, 0.2};
    assert_true(geo_frep_project_pieces(f, px, 1, p, 1e-12, 1.0));
    assert_true(fabs(p[0] - 0.5) < 1e-12 && fabs(p[1] - 0.1) < 1e-12);
    /* two: onto the edge x = y = 0.5 */
    uint32_t two[2] = {px[0], py[0]}, three[3] = {px[0], py[0], pz[0]};
    double q[3] = {0.4, 0.45, 0.1};
    assert_true(geo_frep_project_pieces(f, two, 2, q, 1e-12, 1.0));
    assert_true(fabs(q[0] - 0.5) < 1e-12 && fabs(q[1] - 0.5) < 1e-12 &&
                fabs(q[2] - 0.1) < 1e-12);
    /* three: the corner */
    double r[3] = {0.3, 0.35, 0.4};
    assert_true(geo_frep_project_pieces(f, three, 3, r, 1e-12, 1.0));
    for (int k = 0; k < 3; k++)
        assert_true(fabs(r[k] - 0.5) < 1e-12);
    /* a part of the face's plane that another face cuts away is refused,
     * and so is a step longer than allowed; p stays where it was */
    double far[3] = {0.3, 0.9, 0.2}, keep[3] = {0.3, 0.9, 0.2};
    assert_false(geo_frep_project_pieces(f, px, 1, far, 1e-12, 1.0));
    assert_memory_equal(far, keep, sizeof far);
    double near[3] = {0.3, 0.1, 0.2};
    assert_false(geo_frep_project_pieces(f, px, 1, near, 1e-12, 0.1));
    /* parallel faces have no common point */
    double on_mx[3] = {-0.5, 0.1, 0.2};
    uint32_t par[2] = {px[0], 0};
    assert_int_equal(geo_frep_pieces_at(f, on_mx, 1e-12, par + 1, 1), 1);
    assert_true(par[1] != par[0]);
    assert_false(geo_frep_project_pieces(f, par, 2, near, 1e-12, 1.0));
    geo_frep_free(f);
}

static void test_reader_errors_name_the_place(void **state)
{
    (void)state;
    const char *head = "{\"format\":\"frep-object/1\","
                       "\"bounds\":[[-1,-1,-1],[1,1,1]],\"shape\":";
    char buf[1024];
    snprintf(buf, sizeof buf,
             "%s{\"perturbed\":{\"base\":{\"sphere\":{\"center\":[0,0,0],"
             "\"radius\":0.5}},\"perturbations\":["
             "{\"sphere\":{\"center\":[0,0,0],\"radius\":0.1},\"amplitude\":1},"
             "{\"sphere\":{\"center\":[0,0,0],\"radius\":0.1},\"amplitude\":1},"
             "{\"sphere\":{\"center\":[0,0,0],\"radius\":0.1},\"amplitude\":1},"
             "{\"sphere\":{\"center\":[0,0,0],\"radius\":0.1},"
             "\"amplitude\":\"big\"}]}}}",
             head);
    expect_error(buf, "shape.perturbed.perturbations[3].amplitude: expected "
                      "a number");
    snprintf(buf, sizeof buf,
             "%s{\"union\":[{\"sphere\":{\"center\":[0,0],\"radius\":1}}]}}",
             head);
    expect_error(buf, "shape.union[0].sphere.center: expected 3 numbers");
    snprintf(buf, sizeof buf,
             "%s{\"sphere\":{\"center\":[0,0,0],\"radius\":-1}}}", head);
    expect_error(buf, "shape.sphere.radius: must be > 0");
    snprintf(buf, sizeof buf,
             "%s{\"sphere\":{\"center\":[0,0,0],\"radius\":1},"
             "\"ellipsoid\":{}}}",
             head);
    expect_error(buf, "shape: two shapes in one object");
    snprintf(buf, sizeof buf, "%s{\"halfspace\":{\"plane\":[0,0,0,1]}}}",
             head);
    expect_error(buf, "shape.halfspace.plane: the normal (a, b, c) must not "
                      "be zero");
    snprintf(buf, sizeof buf, "%s{\"difference\":[{\"sphere\":{\"center\":"
                              "[0,0,0],\"radius\":1}}]}}",
             head);
    expect_error(buf, "shape.difference: expected exactly two shapes");
    expect_error("{\"format\":\"frep-object/1\",\"bounds\":[[1,0,0],[0,1,1]],"
                 "\"shape\":{}}",
                 "bounds: the first corner must be below the second");
    expect_error("{\"format\":\"frep-object/2\"}", "format: expected");
    expect_error("{\"format\":\"frep-object/1\",\"format\":\"x\"}",
                 "duplicate");
    expect_error("{\"format\": ", "line 1");
}

static void test_reader_limits_depth_and_count(void **state)
{
    (void)state;
    /* 40 nested unions: deeper than the default limit of 32 */
    char *buf = malloc(8192);
    size_t n = (size_t)sprintf(buf, "{\"format\":\"frep-object/1\","
                                    "\"bounds\":[[-1,-1,-1],[1,1,1]],"
                                    "\"shape\":");
    for (int i = 0; i < 40; i++)
        n += (size_t)sprintf(buf + n, "{\"union\":[");
    n += (size_t)sprintf(buf + n, "{\"sphere\":{\"center\":[0,0,0],"
                                  "\"radius\":0.5}}");
    for (int i = 0; i < 40; i++)
        n += (size_t)sprintf(buf + n, "]}");
    sprintf(buf + n, "}");
    geo_err err = {{0}};
    assert_null(proto_frep_read_mem(buf, strlen(buf), NULL, &err));
    assert_non_null(strstr(err.msg, "nested deeper than 32"));
    proto_frep_limits lim;
    proto_frep_limits_default(&lim);
    lim.max_depth = 64;
    lim.max_shapes = 20;
    assert_null(proto_frep_read_mem(buf, strlen(buf), &lim, &err));
    assert_non_null(strstr(err.msg, "more than 20 shapes"));
    lim.max_shapes = 100;
    geo_frep *f = proto_frep_read_mem(buf, strlen(buf), &lim, &err);
    assert_non_null(f);
    double p[3] = {0, 0, 0};
    assert_true(fabs(geo_frep_eval(f, p) - 0.25) < 1e-15);
    geo_frep_free(f);
    free(buf);
}

static void test_test_objects_parse(void **state)
{
    (void)state;
    const char *names[] = {"sphere", "ellipsoid", "blob83", "torus", "gem",
                           "two-spheres"};
    for (size_t i = 0; i < 6; i++) {
        char path[512];
        snprintf(path, sizeof path, "tests/data/frep/%s.json", names[i]);
        geo_err err = {{0}};
        geo_frep *f = proto_frep_read_file(path, NULL, &err);
        if (!f)
            fail_msg("%s", err.msg);
        double c[3] = {0, 0, 0};
        assert_true(geo_frep_eval(f, c) > 0 || i == 3); /* torus: a hole */
        geo_frep_free(f);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shapes_evaluate_their_formulas),
        cmocka_unit_test(test_perturbation_adds_cubed_positive_part),
        cmocka_unit_test(test_gradient_matches_finite_differences),
        cmocka_unit_test(test_interval_encloses_samples_and_pruning_agrees),
        cmocka_unit_test(test_pieces_meet_at_gem_edges_and_projection_lands),
        cmocka_unit_test(
            test_projection_onto_pieces_lands_on_faces_edges_corners),
        cmocka_unit_test(test_reader_errors_name_the_place),
        cmocka_unit_test(test_reader_limits_depth_and_count),
        cmocka_unit_test(test_test_objects_parse),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
