/* test_fill_json.c — why a result is not a valid solid, as `facet fill`,
 * `facet stitch` and their ops say it (proto/fill_json.h,
 * proto_validity_to_json): each of the three causes of an inconsistent
 * orientation (lib/inspect/orient.h) is named as itself, never as
 * "inconsistent (0 inconsistent facets)". */
#include "testutil.h"

#include <string.h>

#include "fill_json.h"
#include "stats.h"

/* Two unit cubes 3 apart; flip_b turns the second inside out, flip_face
 * reverses one facet of the first. */
static geo_poly *two_cubes(bool flip_b, bool flip_face)
{
    static const uint32_t quad[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7},
                                        {0, 1, 5, 4}, {2, 3, 7, 6},
                                        {1, 2, 6, 5}, {0, 4, 7, 3}};
    double xyz[16][3];
    for (int c = 0; c < 2; c++)
        for (int i = 0; i < 8; i++) {
            xyz[8 * c + i][0] = ((i & 1) ^ ((i >> 1) & 1)) + 3.0 * c;
            xyz[8 * c + i][1] = (i >> 1) & 1;
            xyz[8 * c + i][2] = (i >> 2) & 1;
        }
    uint32_t start[13], idx[48];
    for (int f = 0; f < 12; f++) {
        int c = f / 6;
        bool rev = (c == 1 && flip_b) || (f == 0 && flip_face);
        start[f] = 4 * (uint32_t)f;
        for (int k = 0; k < 4; k++)
            idx[4 * f + k] = 8 * (uint32_t)c + quad[f % 6][rev ? 3 - k : k];
    }
    start[12] = 48;
    geo_poly *p = geo_poly_from_arrays(16, &xyz[0][0], 12, start, idx, NULL,
                                       NULL);
    assert_non_null(p);
    return p;
}

/* The reasons proto_validity_to_json gives for p, joined by '|'. */
static void reasons_of(const geo_poly *p, char *out, size_t len)
{
    geo_stats st;
    assert_int_equal(geo_inspect(p, NULL, NULL, &st, NULL), 0);
    json_t *v = proto_validity_to_json(&st);
    assert_non_null(v);
    json_t *a = json_object_get(v, "reasons");
    out[0] = 0;
    for (size_t i = 0; i < json_array_size(a); i++) {
        if (i)
            strncat(out, "|", len - strlen(out) - 1);
        strncat(out, json_string_value(json_array_get(a, i)),
                len - strlen(out) - 1);
    }
    json_decref(v);
    geo_stats_clear(&st);
}

static void test_valid_model_has_no_reason(void **state)
{
    (void)state;
    geo_poly *p = two_cubes(false, false);
    char r[512];
    reasons_of(p, r, sizeof r);
    assert_string_equal(r, "");
    geo_poly_free(p);
}

static void test_a_shell_turned_inside_out_is_named(void **state)
{
    (void)state;
    geo_poly *p = two_cubes(true, false);
    char r[512];
    reasons_of(p, r, sizeof r);
    assert_string_equal(r, "orientation inconsistent: of its 2 shells some "
                           "face outward, some inward");
    geo_poly_free(p);
}

static void test_a_reversed_facet_is_counted(void **state)
{
    (void)state;
    geo_poly *p = two_cubes(false, true);
    char r[512];
    reasons_of(p, r, sizeof r);
    assert_non_null(strstr(r, "orientation inconsistent (1 inconsistent "
                              "facets)"));
    geo_poly_free(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_valid_model_has_no_reason),
        cmocka_unit_test(test_a_shell_turned_inside_out_is_named),
        cmocka_unit_test(test_a_reversed_facet_is_counted),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
