/* test_model_off.c — the OFF reader and writer: exact round trips of the
 * sample models, the header variants (COFF, NOFF, 4OFF, nOFF, counts on
 * the keyword's line), comments, polygons of any size, colours after the
 * indices, errors that name the line and place, counts that lie, and
 * mutated inputs that must give an error or a valid model. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model_cmp.h"
#include "model_io.h"

static geo_poly *load(const char *name)
{
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(tu_model_path(name), PROTO_FMT_UNKNOWN,
                                        NULL, &err);
    if (!p)
        fail_msg("%s: %s", name, err.msg);
    return p;
}

static geo_poly *text_ok(const char *text)
{
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_mem(text, strlen(text), PROTO_FMT_OFF,
                                       NULL, &err);
    if (!p)
        fail_msg("reading OFF: %s", err.msg);
    return p;
}

static const char *read_err(const void *data, size_t len,
                            const proto_limits *lim)
{
    static geo_err err;
    memset(&err, 0, sizeof err);
    geo_poly *p = proto_model_read_mem(data, len, PROTO_FMT_OFF, lim, &err);
    if (p) {
        geo_poly_free(p);
        fail_msg("OFF input accepted");
    }
    assert_true(err.msg[0] != '\0');
    return err.msg;
}

static const char *text_err(const char *text)
{
    return read_err(text, strlen(text), NULL);
}

static void test_round_trip_is_exact(void **state)
{
    (void)state;
    static const char *const models[] = {"brilliant.scan-k400.json",
                                         "notch-cube.json", "l-prism.json"};
    for (size_t m = 0; m < sizeof models / sizeof models[0]; m++) {
        geo_poly *a = load(models[m]);
        char *buf;
        size_t len;
        geo_err err = {{0}};
        assert_int_equal(proto_model_write_mem(a, PROTO_FMT_OFF, &buf, &len,
                                               &err), 0);
        assert_memory_equal(buf, "OFF\n", 4);
        geo_poly *b = proto_model_read_mem(buf, len, PROTO_FMT_OFF, NULL,
                                           &err);
        if (!b)
            fail_msg("%s: %s", models[m], err.msg);
        char why[256];
        /* positions and polygons bit for bit; planes are refitted */
        if (!tu_poly_same(a, b, 0, -1, why, sizeof why))
            fail_msg("%s: %s", models[m], why);
        free(buf);
        geo_poly_free(b);
        geo_poly_free(a);
    }
    assert_int_equal(proto_format_from_path("a/b.OFF"), PROTO_FMT_OFF);
    assert_int_equal(proto_format_from_name("off"), PROTO_FMT_OFF);
    assert_string_equal(proto_format_name(PROTO_FMT_OFF), "off");
}

static void test_reads_variants_comments_and_colours(void **state)
{
    (void)state;
    /* a square and a triangle, written in several dialects */
    geo_poly *p = text_ok("# a comment before the keyword\n"
                          "OFF\n"
                          "\n"
                          "5 2 0   # counts\n"
                          "0 0 0\n"
                          "1 0 0\n"
                          "1 1 0 # third\n"
                          "0 1 0\n"
                          "0 0 1\n"
                          "4 0 1 2 3 255 0 0\n"
                          "3 0 4 1 0.5 0.5 0.5 1\n");
    assert_int_equal(p->nverts, 5);
    assert_int_equal(p->nfacets, 2);
    assert_int_equal(geo_poly_facet_size(p, 0), 4);
    const uint32_t want[] = {0, 1, 2, 3, 0, 4, 1};
    assert_memory_equal(p->fidx, want, sizeof want);
    assert_true(p->planes[0][2] == 1);
    geo_poly_free(p);

    p = text_ok("COFF 3 1 3\n0 0 0 1 0 0 1\n1 0 0 0 1 0 1\n0 1 0 0 0 1 1\n"
                "3 0 1 2\n");
    assert_int_equal(p->nfacets, 1);
    geo_poly_free(p);
    p = text_ok("NOFF\n3 1\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n"
                "3 0 1 2\n");
    assert_int_equal(p->nverts, 3);
    geo_poly_free(p);
    p = text_ok("STCNOFF\n3 1 0\n0 0 0 0 0 1 1 1 1 1 0 0\n"
                "1 0 0 0 0 1 1 1 1 1 1 0\n0 1 0 0 0 1 1 1 1 1 0 1\n"
                "3 0 1 2 7\n");
    assert_int_equal(p->nfacets, 1);
    geo_poly_free(p);
    /* homogeneous: w is divided out */
    p = text_ok("4OFF\n3 1 0\n0 0 0 2\n4 0 0 2\n0 4 0 2\n3 0 1 2\n");
    assert_true(p->verts[1][0] == 2 && p->verts[2][1] == 2);
    geo_poly_free(p);
    p = text_ok("nOFF\n3\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    assert_int_equal(p->nverts, 3);
    geo_poly_free(p);
    /* a polygon of many vertices, CRLF line ends */
    char text[4096];
    int n = snprintf(text, sizeof text, "OFF\r\n40 1 0\r\n");
    for (int i = 0; i < 40; i++)
        n += snprintf(text + n, sizeof text - (size_t)n, "%.17g %.17g 0\r\n",
                      cos(i * 2 * M_PI / 40), sin(i * 2 * M_PI / 40));
    n += snprintf(text + n, sizeof text - (size_t)n, "40");
    for (int i = 0; i < 40; i++)
        n += snprintf(text + n, sizeof text - (size_t)n, " %d", i);
    snprintf(text + n, sizeof text - (size_t)n, "\r\n");
    p = text_ok(text);
    assert_int_equal(geo_poly_facet_size(p, 0), 40);
    geo_poly_free(p);
}

static void test_errors_name_line_and_place(void **state)
{
    (void)state;
    const char *v4 = "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n";
    char text[256];
    snprintf(text, sizeof text, "%s3 0 1 4\n", v4);
    assert_string_equal(text_err(text),
                        "line 7: facets[0].vertices[2]: index 4 out of range "
                        "(4 vertices, 0-based)");
    snprintf(text, sizeof text, "%s4 0 1 1 2\n", v4);
    assert_string_equal(text_err(text),
                        "line 7: facets[0].vertices[2]: index 1 repeated "
                        "consecutively");
    snprintf(text, sizeof text, "%s2 0 1\n", v4);
    assert_string_equal(text_err(text),
                        "line 7: facets[0]: 2 vertices, a facet needs at "
                        "least 3");
    snprintf(text, sizeof text, "%s4 0 1 2\n", v4);
    assert_string_equal(text_err(text),
                        "line 7: facets[0]: 4 vertices announced, 3 given");
    snprintf(text, sizeof text, "%s3 0 1 2 red\n", v4);
    assert_string_equal(text_err(text),
                        "line 7: facets[0].colour: expected a number "
                        "(colour, normal or texture coordinate), found "
                        "\"red\"");
    snprintf(text, sizeof text, "%s3 0 1 2\n3 0 2 3\n", v4);
    assert_string_equal(text_err(text),
                        "line 8: unexpected \"3 0 2 3\" after the last facet "
                        "(1 announced)");
    assert_string_equal(text_err("OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n"),
                        "line 4: vertices[1]: expected 3 numbers");
    assert_string_equal(text_err("OFF\n3 1 0\n0 0 0\n1 0 nan\n0 1 0\n"
                                 "3 0 1 2\n"),
                        "line 4: vertices[1][2]: expected a number, found "
                        "\"nan\"");
    assert_string_equal(text_err("PLY\n"),
                        "line 1: expected the OFF keyword ([ST][C][N][4][n]"
                        "OFF), found \"PLY\"");
    assert_string_equal(text_err("# nothing\n\n"),
                        "line 3: empty file, expected the OFF keyword");
    assert_string_equal(text_err("OFF BINARY\n"),
                        "line 1: binary OFF is not supported (convert it "
                        "to text)");
    assert_string_equal(text_err("nOFF 4\n"),
                        "line 1: dimension 4: only 3-dimensional OFF is "
                        "supported");
    assert_string_equal(text_err("OFF\n3 x 0\n"),
                        "line 2: facet count: expected a count, found \"x\"");
    assert_string_equal(text_err("OFF\n3 1 0 9\n"),
                        "line 2: unexpected \"9\" after the counts");
    assert_string_equal(text_err("4OFF\n3 1 0\n0 0 0 0\n1 0 0 1\n0 1 0 1\n"
                                 "3 0 1 2\n"),
                        "line 3: vertices[0][3]: the homogeneous coordinate "
                        "w is zero");
    assert_string_equal(text_err("OFF\n3 1 0\n0 0 0\n1 0 0\n# padding\n#\n\n"),
                        "line 8: vertices[2]: the file ends (3 vertices "
                        "announced)");
}

static void test_lying_counts_fail_before_allocating(void **state)
{
    (void)state;
    assert_string_equal(text_err("OFF\n4000000000 1 0\n"),
                        "vertices: 4000000000 exceed the limit of 2000000");
    assert_string_equal(text_err("OFF\n1000000 1000000 0\n0 0 0\n"),
                        "line 2: 1000000 vertices and 1000000 facets "
                        "announced, the 6 bytes left cannot hold them");
    assert_string_equal(text_err("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n"
                                 "4000000 0 1 2\n"),
                        "line 6: facets[0]: 4000000 vertices announced, the "
                        "line holds fewer");
    proto_limits lim;
    proto_limits_default(&lim);
    lim.max_corners = 5;
    const char *t = "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n"
                    "3 0 2 3\n";
    assert_string_equal(read_err(t, strlen(t), &lim),
                        "line 8: facets: 6 vertex indices in all exceed the "
                        "limit of 5");
}

/* Any bytes give an error message or a model that keeps geo_poly's
 * invariants. */
static void check_read(const void *data, size_t len)
{
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_mem(data, len, PROTO_FMT_OFF, NULL, &err);
    if (!p) {
        assert_true(err.msg[0] != '\0');
        return;
    }
    assert_int_equal(geo_poly_validate_indices(p, NULL), 0);
    for (uint32_t i = 0; i < p->nverts; i++)
        for (int k = 0; k < 3; k++)
            assert_true(isfinite(p->verts[i][k]));
    geo_poly_free(p);
}

static void test_mutated_inputs_give_errors_or_valid_models(void **state)
{
    (void)state;
    static const unsigned char subst[] = {0x00, 0xff, '9', '-', ' ', '\n',
                                          '#', 'e', '0', 0x80};
    geo_poly *a = load("notch-cube.json");
    char *buf;
    size_t len;
    geo_err err = {{0}};
    assert_int_equal(proto_model_write_mem(a, PROTO_FMT_OFF, &buf, &len,
                                           &err), 0);
    unsigned char *m = malloc(len);
    assert_non_null(m);
    for (size_t cut = 0; cut <= len; cut++)
        check_read(buf, cut);
    for (size_t pos = 0; pos < len; pos++)
        for (size_t s = 0; s < sizeof subst; s++) {
            memcpy(m, buf, len);
            m[pos] = subst[s];
            check_read(m, len);
        }
    uint64_t seed = 777;
    for (int r = 0; r < 500; r++) {
        memcpy(m, buf, len);
        for (int k = 0; k < 4; k++)
            m[geo_rand_next(&seed) % len] = (unsigned char)geo_rand_next(&seed);
        check_read(m, len);
    }
    free(m);
    free(buf);
    geo_poly_free(a);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip_is_exact),
        cmocka_unit_test(test_reads_variants_comments_and_colours),
        cmocka_unit_test(test_errors_name_line_and_place),
        cmocka_unit_test(test_lying_counts_fail_before_allocating),
        cmocka_unit_test(test_mutated_inputs_give_errors_or_valid_models),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
