/* test_weld.c — lib/mesh/weld.h: seams of repeated vertices welded, and
 * the welds that would make the mesh worse refused whole. */
#include "testutil.h"

#include <stdlib.h>
#include <string.h>

#include "fill.h"
#include "stats.h"
#include "weld.h"

/* geo_weld_boundary with p's own topology. */
static int weld(geo_poly *p, uint32_t *ret_welded)
{
    geo_topo *t = geo_topo_build(p, NULL);
    assert_non_null(t);
    int r = geo_weld_boundary(p, t, ret_welded, NULL);
    geo_topo_free(t);
    return r;
}

/* The unit box with the two vertices of its edge x = 1, y = 0 repeated
 * for the front facet (y = 0): a seam along that edge, which reads as a
 * hole of two coinciding sides. */
static geo_poly *box_with_seam(void)
{
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    geo_poly *p = tu_box(lo, hi);
    uint32_t a = 0, b = 0;
    for (uint32_t v = 0; v < p->nverts; v++) {
        const double *x = p->verts[v];
        if (x[0] == 1 && x[1] == 0)
            *(x[2] == 0 ? &a : &b) = v;
    }
    int64_t a2 = geo_poly_add_vertex(p, p->verts[a]);
    int64_t b2 = geo_poly_add_vertex(p, p->verts[b]);
    assert_true(a2 >= 0 && b2 >= 0);
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        uint32_t *fv = p->fidx + p->fstart[f];
        bool front = true; /* the facet y = 0 */
        for (uint32_t i = 0; i < n; i++)
            front &= p->verts[fv[i]][1] == 0;
        for (uint32_t i = 0; front && i < n; i++)
            fv[i] = fv[i] == a ? (uint32_t)a2 : fv[i] == b ? (uint32_t)b2 : fv[i];
    }
    return p;
}

static void test_seam_is_welded_and_the_box_is_closed(void **s)
{
    (void)s;
    geo_poly *p = box_with_seam();
    assert_false(tu_is_valid(p));
    uint32_t welded = 0;
    assert_int_equal(weld(p, &welded), 0);
    assert_int_equal(welded, 2);
    assert_int_equal(p->nverts, 8);
    assert_int_equal(p->nfacets, 6);
    assert_true(tu_is_valid(p));
    geo_poly_free(p);

    /* fill welds first: no hole is left to fill */
    p = box_with_seam();
    geo_mesh_fill_report rep;
    assert_int_equal(geo_fill(p, NULL, NULL, &rep, NULL), 0);
    assert_int_equal(rep.nwelded, 2);
    assert_int_equal(rep.nloops, 0);
    assert_true(tu_is_valid(p));
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(p);
}

/* Two triangles that touch only at one point, each with its own vertex
 * there: welding it closes no edge and would join two fans at one
 * vertex. Refused, p unchanged. */
static void test_weld_at_a_single_point_is_refused(void **s)
{
    (void)s;
    const double v[6][3] = {{0, 0, 0},  {1, 0, 0},     {0, 1, 0},
                            {0, 0, 0},  {-1, 0, 0.5},  {0, -1, 0.5}};
    geo_poly *p = geo_poly_new();
    for (int i = 0; i < 6; i++)
        assert_true(geo_poly_add_vertex(p, v[i]) >= 0);
    const uint32_t t1[3] = {0, 1, 2}, t2[3] = {3, 4, 5};
    assert_true(geo_poly_add_facet(p, t1, 3) >= 0);
    assert_true(geo_poly_add_facet(p, t2, 3) >= 0);
    geo_poly *q = geo_poly_copy(p);
    uint32_t welded = 7;
    assert_int_equal(weld(p, &welded), 0);
    assert_int_equal(welded, 0);
    assert_int_equal(p->nverts, q->nverts);
    assert_memory_equal(p->fidx, q->fidx, 6 * sizeof *p->fidx);
    geo_poly_free(q);
    geo_poly_free(p);
}

/* A facet whose own two vertices coincide would list one vertex twice
 * once welded: refused, p unchanged. */
static void test_weld_inside_one_facet_is_refused(void **s)
{
    (void)s;
    const double v[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    geo_poly *p = geo_poly_new();
    for (int i = 0; i < 4; i++)
        assert_true(geo_poly_add_vertex(p, v[i]) >= 0);
    const uint32_t q4[4] = {0, 1, 2, 3};
    assert_true(geo_poly_add_facet(p, q4, 4) >= 0);
    uint32_t welded = 7;
    assert_int_equal(weld(p, &welded), 0);
    assert_int_equal(welded, 0);
    assert_int_equal(p->nverts, 4);
    assert_int_equal(p->fidx[2], 2);
    geo_poly_free(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_seam_is_welded_and_the_box_is_closed),
        cmocka_unit_test(test_weld_at_a_single_point_is_refused),
        cmocka_unit_test(test_weld_inside_one_facet_is_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
