/* test_points_json.c — point lists read in both JSON forms with exact
 * doubles, every malformed input rejected with its place named, the count
 * limit checked before allocating, and answers written as JSON text. */
#include "testutil.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "inside.h"
#include "points_json.h"

static int read_str(const char *s, size_t max, double (**pts)[3], size_t *n,
                    geo_err *err)
{
    return proto_points_read_mem(s, strlen(s), max, pts, n, err);
}

static void test_both_forms_read_exact_doubles(void **state)
{
    (void)state;
    double(*pts)[3] = NULL;
    size_t n = 0;
    geo_err err = {{0}};
    assert_int_equal(read_str("[[1, 2.5, -3], [0.1, 1e-300, 7]]", 0, &pts, &n,
                              &err),
                     0);
    assert_int_equal(n, 2);
    assert_true(pts[0][1] == 2.5 && pts[0][2] == -3);
    assert_true(pts[1][0] == 0.1 && pts[1][1] == 1e-300);
    free(pts);
    assert_int_equal(read_str("{\"points\": [[4, 5, 6]], \"units\": \"mm\"}", 0,
                              &pts, &n, &err),
                     0);
    assert_int_equal(n, 1);
    assert_true(pts[0][0] == 4 && pts[0][2] == 6);
    free(pts);
    double dummy[1][3];
    pts = dummy; /* an empty list sets it to NULL */
    assert_int_equal(read_str("[]", 0, &pts, &n, &err), 0);
    assert_int_equal(n, 0);
    assert_null(pts);
}

static void test_errors_name_the_place(void **state)
{
    (void)state;
    static const struct {
        const char *text, *msg;
        int code;
    } cases[] = {
        {"[[1,2,3],[1,\"x\",3]]", "points[1][1]: expected a number", -EINVAL},
        {"[[1,2,3],[1,2]]", "points[1]: expected 3 numbers, got 2", -EINVAL},
        {"[[1,2,3,4]]", "points[0]: expected 3 numbers, got 4", -EINVAL},
        {"[5]", "points[0]: expected an array of 3 numbers", -EINVAL},
        {"{\"pts\": []}", "points: missing", -EINVAL},
        {"{\"points\": {}}", "points: expected an array", -EINVAL},
        {"[[1,2,null]]", "points[0][2]: expected a number", -EINVAL},
        {"[[1,2,1e999]]", "line 1", -EINVAL},
        {"[[1,2,NaN]]", "line 1", -EINVAL},
        {"{\"points\": [], \"points\": []}", "line 1", -EINVAL},
        {"[[1,2,3],", "line 1", -EINVAL},
        {"[[1,[2],3]]", "points[0][1]: expected a number", -EINVAL},
        {"[[1,{\"a\":2},3,4]]", "points[0]: expected 3 numbers, got 4",
         -EINVAL},
        /* a syntax error after a bad value is the error reported */
        {"[[1,2],[1,2,3] x", "line 1", -EINVAL},
        {"{\"points\": 5, \"b\": [}", "line 1", -EINVAL},
        {"{\"a\": [[1]], \"points\": [[1,2,true]]}",
         "points[0][2]: expected a number", -EINVAL},
        {"7", "line 1", -EINVAL},
        {"", "line 1", -EINVAL},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        double(*pts)[3] = NULL;
        size_t n = 12345;
        geo_err err = {{0}};
        assert_int_equal(read_str(cases[i].text, 0, &pts, &n, &err),
                         cases[i].code);
        if (!strstr(err.msg, cases[i].msg))
            print_error("%s -> %s\n", cases[i].text, err.msg);
        assert_non_null(strstr(err.msg, cases[i].msg));
        assert_null(pts);
        assert_int_equal(n, 12345);
    }
}

static void test_limit_rejects_long_lists(void **state)
{
    (void)state;
    double(*pts)[3] = NULL;
    size_t n = 0;
    geo_err err = {{0}};
    assert_int_equal(read_str("[[1,2,3],[4,5,6],[7,8,9]]", 2, &pts, &n, &err),
                     -ERANGE);
    assert_non_null(strstr(err.msg, "exceed the limit of 2"));
    /* the limit is named before a bad element past it or before it */
    assert_int_equal(read_str("[[1,2,3],[4,5,6],[7,8]]", 2, &pts, &n, &err),
                     -ERANGE);
    assert_non_null(strstr(err.msg, "3 points exceed the limit of 2"));
    assert_int_equal(read_str("[[1,2],[4,5,6],[7,8,9]]", 2, &pts, &n, &err),
                     -ERANGE);
    /* lists longer than the first allocation grow */
    size_t many = 5000, len = 0;
    char *text = malloc(many * 12 + 4);
    assert_non_null(text);
    text[len++] = '[';
    for (size_t i = 0; i < many; i++)
        len += (size_t)sprintf(text + len, "%s[%zu,1,2]", i ? "," : "", i);
    text[len++] = ']';
    text[len] = '\0';
    assert_int_equal(read_str(text, 0, &pts, &n, &err), 0);
    assert_int_equal(n, many);
    assert_true(pts[many - 1][0] == (double)(many - 1) && pts[17][2] == 2);
    free(pts);
    free(text);
    assert_int_equal(read_str("[[1,2,3],[4,5,6]]", 2, &pts, &n, &err), 0);
    free(pts);
}

static void test_file_errors_carry_the_path(void **state)
{
    (void)state;
    double(*pts)[3] = NULL;
    size_t n = 0;
    geo_err err = {{0}};
    assert_true(proto_points_read_file("/nonexistent/p.json", 0, &pts, &n,
                                       &err) < 0);
    assert_non_null(strstr(err.msg, "/nonexistent/p.json: "));
    char path[] = "/tmp/points-XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    const char *text = "{\"points\": [[1, 2, 3], [4, 5]]}";
    assert_int_equal(write(fd, text, strlen(text)), (ssize_t)strlen(text));
    close(fd);
    assert_int_equal(proto_points_read_file(path, 0, &pts, &n, &err), -EINVAL);
    assert_non_null(strstr(err.msg, path));
    assert_non_null(strstr(err.msg, "points[1]: expected 3 numbers"));
    unlink(path);
}

static void test_answers_as_json_text(void **state)
{
    (void)state;
    int8_t loc[4] = {GEO_LOC_INSIDE, GEO_LOC_OUTSIDE, GEO_LOC_BOUNDARY,
                     GEO_LOC_INSIDE};
    size_t len;
    char *s = proto_locs_to_text(loc, 4, &len);
    assert_string_equal(s, "[\"inside\",\"outside\",\"boundary\",\"inside\"]\n");
    assert_int_equal(len, strlen(s));
    free(s);
    s = proto_locs_to_text(loc, 0, NULL);
    assert_string_equal(s, "[]\n");
    free(s);
    assert_string_equal(proto_loc_name(7), "invalid");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_both_forms_read_exact_doubles),
        cmocka_unit_test(test_errors_name_the_place),
        cmocka_unit_test(test_limit_rejects_long_lists),
        cmocka_unit_test(test_file_errors_carry_the_path),
        cmocka_unit_test(test_answers_as_json_text),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
