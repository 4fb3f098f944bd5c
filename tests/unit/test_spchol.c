/* test_spchol.c — the sparse Cholesky solver, in both orderings:
 * solutions of grid Laplacians and bi-Laplacians (connected, split into
 * pieces, a single unknown) and of a polyhedron's plane system meet
 * A·x = b to rounding level, each ordering keeps its factor far below
 * dense size, and a matrix that is not positive definite, a bound on the
 * factor and a bad index are reported as errors. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "spchol.h"

/* A symmetric matrix in compressed rows, built entry by entry. */
typedef struct csr {
    uint32_t n, nz, cap;
    uint32_t *rp, *ci;
    double *v;
    double *dense; /* n × n, for building and checking */
} csr;

static void csr_init(csr *m, uint32_t n)
{
    memset(m, 0, sizeof *m);
    m->n = n;
    m->dense = calloc((size_t)n * n, sizeof *m->dense);
    assert_non_null(m->dense);
}

static void add(csr *m, uint32_t i, uint32_t j, double x)
{
    m->dense[(size_t)i * m->n + j] += x;
    if (i != j)
        m->dense[(size_t)j * m->n + i] += x;
}

/* Compresses the dense entries (only nonzeros, diagonal always). */
static void csr_pack(csr *m)
{
    uint32_t n = m->n;
    m->rp = malloc((n + 1) * sizeof *m->rp);
    m->ci = malloc((size_t)n * n * sizeof *m->ci);
    m->v = malloc((size_t)n * n * sizeof *m->v);
    assert_non_null(m->rp);
    m->rp[0] = 0;
    for (uint32_t i = 0; i < n; i++) {
        for (uint32_t j = 0; j < n; j++) {
            double x = m->dense[(size_t)i * n + j];
            if (x != 0 || i == j) {
                m->ci[m->nz] = j;
                m->v[m->nz++] = x;
            }
        }
        m->rp[i + 1] = m->nz;
    }
}

static void csr_free(csr *m)
{
    free(m->rp), free(m->ci), free(m->v), free(m->dense);
}

/* Grid graph Laplacian (w × h) plus shift·I: the 5-point stencil. */
static void grid_laplacian(csr *m, uint32_t w, uint32_t h, double shift,
                           bool cut)
{
    csr_init(m, w * h);
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            uint32_t i = y * w + x;
            add(m, i, i, shift);
            /* cut: no edges across the middle column (two pieces) */
            if (x + 1 < w && !(cut && x + 1 == w / 2)) {
                add(m, i, i, 1), add(m, i + 1, i + 1, 1), add(m, i, i + 1, -1);
            }
            if (y + 1 < h) {
                add(m, i, i, 1), add(m, i + w, i + w, 1), add(m, i, i + w, -1);
            }
        }
}

/* max |A·x − b| / max |b| over the three right-hand sides. */
static double residual(const csr *m, const double (*x)[3],
                       const double (*b)[3])
{
    double worst = 0, bmax = 0;
    for (uint32_t i = 0; i < m->n; i++)
        for (int c = 0; c < 3; c++) {
            double s = 0;
            for (uint32_t q = m->rp[i]; q < m->rp[i + 1]; q++)
                s += m->v[q] * x[m->ci[q]][c];
            worst = fmax(worst, fabs(s - b[i][c]));
            bmax = fmax(bmax, fabs(b[i][c]));
        }
    return worst / bmax;
}

static const geo_spchol_order orders[] = {GEO_SPCHOL_DISSECTION,
                                          GEO_SPCHOL_MIN_DEGREE};

static void solve_and_check(const csr *m, geo_spchol_order order, double tol)
{
    uint64_t seed = 7;
    double(*b)[3] = malloc(m->n * sizeof *b);
    double(*x)[3] = malloc(m->n * sizeof *x);
    for (uint32_t i = 0; i < m->n; i++)
        for (int c = 0; c < 3; c++)
            b[i][c] = x[i][c] = geo_rand_unit(&seed) - 0.5;
    geo_spchol *f = NULL;
    assert_int_equal(geo_spchol_factor(m->n, m->rp, m->ci, m->v, order, 0,
                                       NULL, &f),
                     0);
    assert_non_null(f);
    assert_int_equal(geo_spchol_solve3(f, x), 0);
    assert_true(residual(m, (const double(*)[3])x, (const double(*)[3])b) <
                tol);
    geo_spchol_free(f);
    free(b), free(x);
}

static void test_grid_laplacian_is_solved_to_rounding(void **state)
{
    (void)state;
    csr m;
    grid_laplacian(&m, 30, 20, 1e-3, false);
    csr_pack(&m);
    for (int o = 0; o < 2; o++)
        solve_and_check(&m, orders[o], 1e-10);
    csr_free(&m);
}

static void test_grid_bilaplacian_is_solved_with_little_fill(void **state)
{
    (void)state;
    /* K = L·L + 1e-6·I on a 40 × 40 grid: each row reaches two rings, as
     * a fairing system does */
    csr l, k;
    uint32_t w = 40, n = w * w;
    grid_laplacian(&l, w, w, 0, false);
    csr_pack(&l);
    csr_init(&k, n);
    for (uint32_t i = 0; i < n; i++) {
        k.dense[(size_t)i * n + i] += 1e-6;
        for (uint32_t p = l.rp[i]; p < l.rp[i + 1]; p++)
            for (uint32_t q = l.rp[l.ci[p]]; q < l.rp[l.ci[p] + 1]; q++)
                k.dense[(size_t)i * n + l.ci[q]] += l.v[p] * l.v[q];
    }
    csr_pack(&k);
    for (int o = 0; o < 2; o++) {
        solve_and_check(&k, orders[o], 1e-6);
        geo_spchol *f = NULL;
        assert_int_equal(
            geo_spchol_factor(n, k.rp, k.ci, k.v, orders[o], 0, NULL, &f), 0);
        /* nested dissection: 72,775 entries, below the 128,000 of the
         * natural (banded, width 2·40) order and far below dense 1.28 M */
        if (orders[o] == GEO_SPCHOL_DISSECTION)
            assert_true(geo_spchol_nnz(f) < 100000);
        else
            assert_true(geo_spchol_nnz(f) < 128000);
        geo_spchol_free(f);
    }
    csr_free(&l), csr_free(&k);
}

static void test_disconnected_and_tiny_systems_are_solved(void **state)
{
    (void)state;
    csr m;
    grid_laplacian(&m, 200, 3, 0.5, true);
    csr_pack(&m);
    for (int o = 0; o < 2; o++)
        solve_and_check(&m, orders[o], 1e-12);
    csr_free(&m);
    csr_init(&m, 1);
    add(&m, 0, 0, 4.0);
    csr_pack(&m);
    for (int o = 0; o < 2; o++)
        solve_and_check(&m, orders[o], 1e-15);
    csr_free(&m);
}

static void test_bad_input_and_limits_are_reported(void **state)
{
    (void)state;
    for (int o = 0; o < 2; o++) {
        csr m;
        grid_laplacian(&m, 10, 10, 0, false); /* singular: constants */
        csr_pack(&m);
        geo_spchol *f = (geo_spchol *)&m; /* must be reset to NULL */
        assert_int_equal(
            geo_spchol_factor(m.n, m.rp, m.ci, m.v, orders[o], 0, NULL, &f),
            -EDOM);
        assert_null(f);
        csr_free(&m);
        grid_laplacian(&m, 10, 10, 1, false);
        csr_pack(&m);
        assert_int_equal(
            geo_spchol_factor(m.n, m.rp, m.ci, m.v, orders[o], 50, NULL, &f),
            -ERANGE);
        assert_null(f);
        m.ci[3] = m.n;
        assert_int_equal(
            geo_spchol_factor(m.n, m.rp, m.ci, m.v, orders[o], 0, NULL, &f),
            -EINVAL);
        assert_null(f);
        csr_free(&m);
    }
    assert_null(geo_spchol_free(NULL));
}

/* The system of a polyhedron's planes once its vertices are eliminated:
 * three unknowns a plane (the cells of a w × h grid), every vertex (a
 * grid corner) coupling all the planes around it, a random positive
 * semidefinite term of rank two per vertex plus a small shift. Minimum
 * degree (the three unknowns of a plane one supervariable) must solve
 * to rounding and give a smaller factor than nested dissection. */
static void test_plane_system_is_ordered_by_minimum_degree(void **state)
{
    (void)state;
    uint32_t w = 16, h = 14, n = 3 * w * h;
    csr m;
    csr_init(&m, n);
    uint64_t seed = 11;
    for (uint32_t i = 0; i < n; i++)
        add(&m, i, i, 1e-3);
    for (uint32_t y = 0; y <= h; y++)
        for (uint32_t x = 0; x <= w; x++) {
            uint32_t cells[4], nc = 0, idx[12];
            for (uint32_t dy = 0; dy < 2; dy++)
                for (uint32_t dx = 0; dx < 2; dx++)
                    if (x + dx >= 1 && x + dx <= w && y + dy >= 1 &&
                        y + dy <= h)
                        cells[nc++] = (y + dy - 1) * w + (x + dx - 1);
            uint32_t ni = 0;
            for (uint32_t c = 0; c < nc; c++)
                for (uint32_t k = 0; k < 3; k++)
                    idx[ni++] = 3 * cells[c] + k;
            for (int r = 0; r < 2; r++) {
                double g[12];
                for (uint32_t i = 0; i < ni; i++)
                    g[i] = geo_rand_unit(&seed) - 0.5;
                for (uint32_t i = 0; i < ni; i++)
                    for (uint32_t j = 0; j <= i; j++)
                        add(&m, idx[i], idx[j], g[i] * g[j]);
            }
        }
    csr_pack(&m);
    uint64_t nnz[2];
    for (int o = 0; o < 2; o++) {
        solve_and_check(&m, orders[o], 1e-9);
        geo_spchol *f = NULL;
        assert_int_equal(
            geo_spchol_factor(m.n, m.rp, m.ci, m.v, orders[o], 0, NULL, &f),
            0);
        nnz[o] = geo_spchol_nnz(f);
        geo_spchol_free(f);
    }
    /* the minimum-degree ordering counts L's entries as it goes: its
     * count is the factor's, so a bound of exactly that passes */
    geo_spchol *f = NULL;
    assert_int_equal(geo_spchol_factor(m.n, m.rp, m.ci, m.v,
                                       GEO_SPCHOL_MIN_DEGREE, nnz[1], NULL,
                                       &f),
                     0);
    geo_spchol_free(f);
    assert_int_equal(geo_spchol_factor(m.n, m.rp, m.ci, m.v,
                                       GEO_SPCHOL_MIN_DEGREE, nnz[1] - 1, NULL,
                                       &f),
                     -ERANGE);
    assert_null(f);
    print_message("plane system n=%u: L entries %llu (dissection), %llu "
                  "(minimum degree)\n",
                  n, (unsigned long long)nnz[0], (unsigned long long)nnz[1]);
    assert_true(nnz[1] < nnz[0]);
    csr_free(&m);
}

/* A refactored matrix of the same pattern gives the factor a fresh one
 * does, bit for bit (the same solution); a matrix of another pattern is
 * refused and the factor kept; one that is not positive definite is
 * reported. */
static void check_refactor(geo_spchol_order order)
{
    csr a, b;
    grid_laplacian(&a, 13, 11, 0.5, false);
    csr_pack(&a);
    grid_laplacian(&b, 13, 11, 0.5, false);
    csr_pack(&b);
    uint64_t seed = 3;
    for (uint32_t q = 0; q < b.rp[b.n]; q++)
        b.v[q] *= 1 + 0.1 * geo_rand_unit(&seed);
    /* symmetric again: the lower triangle copies the upper */
    for (uint32_t i = 0; i < b.n; i++)
        for (uint32_t q = b.rp[i]; q < b.rp[i + 1]; q++) {
            uint32_t j = b.ci[q];
            for (uint32_t t = b.rp[j]; t < b.rp[j + 1]; t++)
                if (b.ci[t] == i && j < i)
                    b.v[q] = b.v[t];
        }
    geo_spchol *fresh = NULL, *re = NULL;
    assert_int_equal(
        geo_spchol_factor(b.n, b.rp, b.ci, b.v, order, 0, NULL, &fresh), 0);
    assert_int_equal(geo_spchol_factor(a.n, a.rp, a.ci, a.v, order, 0, NULL, &re),
                     0);
    assert_int_equal(geo_spchol_refactor(re, b.n, b.rp, b.ci, b.v, NULL), 0);
    double(*x1)[3] = malloc(b.n * sizeof *x1), (*x2)[3] = malloc(b.n * sizeof *x2);
    assert_non_null(x1);
    assert_non_null(x2);
    for (uint32_t i = 0; i < b.n; i++)
        for (int c = 0; c < 3; c++)
            x1[i][c] = x2[i][c] = geo_rand_unit(&seed) - 0.5;
    assert_int_equal(geo_spchol_solve3(fresh, x1), 0);
    assert_int_equal(geo_spchol_solve3(re, x2), 0);
    assert_memory_equal(x1, x2, b.n * sizeof *x1);
    /* another pattern: refused, the factor still the one of b */
    csr c;
    grid_laplacian(&c, 13, 11, 0.5, true);
    csr_pack(&c);
    assert_int_equal(geo_spchol_refactor(re, c.n, c.rp, c.ci, c.v, NULL),
                     -EINVAL);
    for (uint32_t i = 0; i < b.n; i++)
        for (int c2 = 0; c2 < 3; c2++)
            x2[i][c2] = x1[i][c2];
    assert_int_equal(geo_spchol_solve3(fresh, x1), 0);
    assert_int_equal(geo_spchol_solve3(re, x2), 0);
    assert_memory_equal(x1, x2, b.n * sizeof *x1);
    /* not positive definite */
    for (uint32_t i = 0; i < b.n; i++)
        for (uint32_t q = b.rp[i]; q < b.rp[i + 1]; q++)
            if (b.ci[q] == i && i == b.n / 2)
                b.v[q] = -1;
    assert_int_equal(geo_spchol_refactor(re, b.n, b.rp, b.ci, b.v, NULL),
                     -EDOM);
    geo_spchol_free(fresh);
    geo_spchol_free(re);
    free(x1), free(x2);
    csr_free(&a), csr_free(&b), csr_free(&c);
}

static void test_refactor_reuses_the_analysis(void **state)
{
    (void)state;
    for (int o = 0; o < 2; o++)
        check_refactor(orders[o]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grid_laplacian_is_solved_to_rounding),
        cmocka_unit_test(test_grid_bilaplacian_is_solved_with_little_fill),
        cmocka_unit_test(test_disconnected_and_tiny_systems_are_solved),
        cmocka_unit_test(test_bad_input_and_limits_are_reported),
        cmocka_unit_test(test_plane_system_is_ordered_by_minimum_degree),
        cmocka_unit_test(test_refactor_reuses_the_analysis),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
