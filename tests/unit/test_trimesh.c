/* test_trimesh.c — the dynamic triangle mesh's contact probe
 * (geo_tmesh_clashes): splits and moves that keep a flat grid a simple
 * surface pass, those that fold it over its neighbours, lay a triangle
 * onto another or make a degenerate one are caught, and the mesh is left
 * unchanged by the question. */
#include "testutil.h"

#include <string.h>

#include "trimesh.h"

enum { N = 5 }; /* N × N vertices, grid spacing 1, plane z = 0 */

static void grid(geo_tmesh *m)
{
    double xyz[N * N][3];
    for (int j = 0; j < N; j++)
        for (int i = 0; i < N; i++) {
            xyz[j * N + i][0] = i;
            xyz[j * N + i][1] = j;
            xyz[j * N + i][2] = 0;
        }
    assert_int_equal(geo_tmesh_init(m, &xyz[0][0], N * N), 0);
    for (int j = 0; j + 1 < N; j++)
        for (int i = 0; i + 1 < N; i++) {
            uint32_t a = j * N + i, b = a + 1, c = a + N + 1, d = a + N;
            assert_true(geo_tmesh_add(m, a, b, c, 0) >= 0);
            assert_true(geo_tmesh_add(m, a, c, d, 0) >= 0);
        }
}

/* The id of the live triangle with directed edge a→b. */
static uint32_t tri_of(const geo_tmesh *m, uint32_t a, uint32_t b)
{
    uint32_t h = geo_tmesh_find(m, a, b);
    assert_true(h != UINT32_MAX);
    return h / 3;
}

static void test_centroid_split_is_clear_and_far_point_clashes(void **state)
{
    (void)state;
    geo_tmesh m;
    geo_tmesh_probe pr = {0};
    grid(&m);
    uint32_t a = 2 * N + 2, b = a + 1, c = a + N + 1; /* interior */
    uint32_t t = tri_of(&m, a, b), X = GEO_TMESH_NEWV;
    const uint32_t nt[3][3] = {{a, b, X}, {b, c, X}, {c, a, X}};
    double in[3] = {2.7, 2.3, 0.0}, lifted[3] = {2.7, 2.3, 0.2};
    assert_int_equal(geo_tmesh_clashes(&m, &pr, &t, 1, nt, 3, UINT32_MAX, in,
                                       2), 0);
    /* a lifted point makes a tent over t: still a simple surface */
    assert_int_equal(geo_tmesh_clashes(&m, &pr, &t, 1, nt, 3, UINT32_MAX,
                                       lifted, 2), 0);
    /* a point beyond the neighbours lays the new triangles over them */
    double out[3] = {3.5, 1.2, 0.0};
    assert_int_equal(geo_tmesh_clashes(&m, &pr, &t, 1, nt, 3, UINT32_MAX,
                                       out, 2), 1);
    /* on the edge a–b: (a, b, X) is degenerate */
    double on_edge[3] = {2.5, 2.0, 0.0};
    assert_int_equal(geo_tmesh_clashes(&m, &pr, &t, 1, nt, 3, UINT32_MAX,
                                       on_edge, 2), 1);
    /* asking changed nothing */
    assert_int_equal(m.nv, N * N);
    assert_int_equal(m.nt, 2 * (N - 1) * (N - 1));
    assert_int_equal(tri_of(&m, a, b), t);
    geo_tmesh_probe_destroy(&pr);
    geo_tmesh_destroy(&m);
}

static void test_moving_a_vertex_over_its_ring_clashes(void **state)
{
    (void)state;
    geo_tmesh m;
    geo_tmesh_probe pr = {0};
    grid(&m);
    uint32_t v = 2 * N + 2, old[16], nt[16][3], n = 0, w = v + 1;
    do { /* v's fan, counter-clockwise */
        uint32_t h = geo_tmesh_find(&m, v, w);
        assert_true(h != UINT32_MAX);
        old[n] = h / 3;
        memcpy(nt[n], m.t[h / 3], sizeof nt[n]);
        n++;
        w = geo_tmesh_opposite(&m, h);
    } while (w != v + 1 && n < 16);
    assert_int_equal(n, 6);
    double small[3] = {2.2, 1.9, 0.1}, across[3] = {3.6, 2.1, 0.0};
    assert_int_equal(geo_tmesh_clashes(&m, &pr, old, n,
                                       (const uint32_t(*)[3])nt, n, v, small,
                                       2), 0);
    /* past the neighbour v + 1: its fan folds over the next ring */
    assert_int_equal(geo_tmesh_clashes(&m, &pr, old, n,
                                       (const uint32_t(*)[3])nt, n, v,
                                       across, 2), 1);
    /* the probe is reusable and the mesh unchanged */
    assert_int_equal(geo_tmesh_clashes(&m, &pr, old, n,
                                       (const uint32_t(*)[3])nt, n, v, small,
                                       2), 0);
    assert_true(m.v[v][0] == 2.0 && m.v[v][1] == 2.0);
    geo_tmesh_probe_destroy(&pr);
    geo_tmesh_destroy(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_centroid_split_is_clear_and_far_point_clashes),
        cmocka_unit_test(test_moving_a_vertex_over_its_ring_clashes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
