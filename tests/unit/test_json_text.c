/* test_json_text.c — proto_json_dumps writes what json_dumps writes, byte
 * for byte: reals over the whole range of doubles (random bit patterns,
 * integral values, powers of two, subnormals, exponents of every size),
 * strings with every escape, nested and empty containers, each flag the
 * writer takes; and a real report and statistics document. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "json_text.h"

static const size_t FLAGS[] = {
    0, JSON_COMPACT, JSON_INDENT(2) | JSON_PRESERVE_ORDER, JSON_INDENT(1),
    JSON_INDENT(4) | JSON_COMPACT, JSON_PRESERVE_ORDER,
};

static void same_text(const json_t *j)
{
    for (size_t k = 0; k < sizeof FLAGS / sizeof FLAGS[0]; k++) {
        char *a = json_dumps(j, FLAGS[k]), *b = proto_json_dumps(j, FLAGS[k]);
        assert_non_null(a);
        assert_non_null(b);
        if (strcmp(a, b) != 0)
            fail_msg("flags %zu:\njansson: %.300s\nours:    %.300s", FLAGS[k], a, b);
        free(a);
        free(b);
    }
}

static uint64_t rng = 0x9E3779B97F4A7C15u;
static uint64_t next(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

static void reals(void **state)
{
    (void)state;
    json_t *a = json_array();
    double fixed[] = {0.0, -0.0, 1.0, -1.0, 0.1, 1e300, 1e-300, 5e-324,
                      2.2250738585072014e-308, 1.7976931348623157e308,
                      123456789012345678.0, 1e15, 1e16, 1e17, 1e21, 1e-5,
                      1e-4, 0.5, 3.0, 100.0, 34.5, 40.75, 0.0001234};
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++)
        json_array_append_new(a, json_real(fixed[i]));
    for (int i = -1074; i <= 1023; i += 7)
        json_array_append_new(a, json_real(ldexp(1.0, i)));
    for (int i = 0; i < 200000; i++) {
        uint64_t bits = next();
        double x;
        memcpy(&x, &bits, sizeof x);
        if (!isfinite(x))
            continue;
        json_array_append_new(a, json_real(x));
        /* numbers as models and reports hold them: mm, degrees, percent */
        json_array_append_new(a, json_real((double)(next() % 2000000) / 997.0 - 1000));
        json_array_append_new(a, json_real(round((double)(next() % 100000)) / 1000.0));
    }
    same_text(a);
    json_decref(a);
}

static void strings_and_shapes(void **state)
{
    (void)state;
    json_t *o = json_object();
    json_object_set_new(o, "plain", json_string("table"));
    json_object_set_new(o, "escapes", json_string("\"q\" \\ / \b\f\n\r\t \x01\x1f\x7f end"));
    json_object_set_new(o, "utf8", json_string("\xc3\xa9\xe2\x82\xac\xf0\x9f\x92\x8e"));
    json_object_set_new(o, "key \"with\"\n escapes", json_integer(-42));
    json_object_set_new(o, "big", json_integer(INT64_MAX));
    json_object_set_new(o, "empty_array", json_array());
    json_object_set_new(o, "empty_object", json_object());
    json_object_set_new(o, "t", json_true());
    json_object_set_new(o, "f", json_false());
    json_object_set_new(o, "n", json_null());
    json_t *nest = json_array();
    json_array_append_new(nest, json_array());
    json_t *inner = json_object();
    json_object_set_new(inner, "x", json_real(1.5));
    json_object_set_new(inner, "list", json_pack("[i, f, s, [], {}]", 1, 2.25, "s"));
    json_array_append_new(nest, inner);
    json_object_set_new(o, "nest", nest);
    same_text(o);
    /* a string with an embedded NUL */
    json_object_set_new(o, "nul", json_stringn("a\0b", 3));
    same_text(o);
    json_decref(o);
    /* scalars at the top go to jansson */
    json_t *r = json_real(2.5);
    char *a = json_dumps(r, JSON_ENCODE_ANY), *b = proto_json_dumps(r, JSON_ENCODE_ANY);
    assert_string_equal(a, b);
    free(a);
    free(b);
    json_decref(r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(reals),
        cmocka_unit_test(strings_and_shapes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
