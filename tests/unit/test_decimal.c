/* test_decimal.c — proto/decimal.h against the C library: parsing equals
 * strtod bit for bit, formatting equals the "%.15g/%.16g/%.17g, first
 * that reads back" loop byte for byte, over random and constructed hard
 * cases (halfway points, ties, powers of two and ten, range edges). */
#include "testutil.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "decimal.h"

static uint64_t rng = 0x9E3779B97F4A7C15u;

static uint64_t next64(void)
{
    return geo_rand_next(&rng);
}

static double bits_to_double(uint64_t b)
{
    double d;
    memcpy(&d, &b, sizeof d);
    return d;
}

static uint64_t double_to_bits(double d)
{
    uint64_t b;
    memcpy(&b, &d, sizeof b);
    return b;
}

/* The reference: what the writers printed before proto/decimal.c. */
static void reference_format(char *out, double x)
{
    if (x == 0) {
        strcpy(out, signbit(x) ? "-0.0" : "0");
        return;
    }
    for (int prec = 15; prec <= 17; prec++) {
        snprintf(out, 40, "%.*g", prec, x);
        if (prec == 17 || strtod(out, NULL) == x)
            break;
    }
}

static void check_format(double x)
{
    char want[40], got[PROTO_DECIMAL_MAX];
    reference_format(want, x);
    size_t n = proto_decimal_format(got, x);
    if (strcmp(want, got) != 0 || n != strlen(got))
        fail_msg("format %a: want \"%s\", got \"%s\"", x, want, got);
}

/* Parses s both ways and compares the bits (and the overflow verdict). */
static void check_parse(const char *s)
{
    errno = 0;
    double want = strtod(s, NULL);
    bool overflow = (want == HUGE_VAL || want == -HUGE_VAL) && errno == ERANGE;
    double got = 12345;
    int r = proto_decimal_parse(s, strlen(s), &got);
    if (overflow) {
        if (r != -ERANGE)
            fail_msg("parse \"%s\": overflow not reported (%d)", s, r);
        return;
    }
    if (r != 0 || double_to_bits(want) != double_to_bits(got))
        fail_msg("parse \"%s\": want %a, got %a (r %d)", s, want, got, r);
}

static void test_format_matches_the_libc_loop_on_random_bits(void **state)
{
    (void)state;
    for (int i = 0; i < 200000; i++) {
        double x = bits_to_double(next64());
        if (isfinite(x))
            check_format(x);
    }
}

static void test_format_matches_on_scanner_like_values(void **state)
{
    (void)state;
    /* coordinates of a 10 mm stone, plane normals and offsets, and every
     * decade of the fast range */
    for (int i = 0; i < 300000; i++) {
        double u = (double)(next64() >> 11) / 9007199254740992.0;
        int dec = (int)(next64() % 34) - 14;
        double x = (u * 9 + 1) * pow(10, dec);
        check_format(next64() & 1 ? -x : x);
        check_format(u * 20 - 10);
    }
}

static void test_format_matches_on_short_and_boundary_values(void **state)
{
    (void)state;
    static const double fixed[] = {
        0.0, -0.0, 1, -1, 0.1, 0.2, 0.3, 1.5, 100, 1e15, 1e16, 1e17, 1e-5,
        1e-4, 1.23e-4, 9.999e-5, 123456789012345678.0, 1e22, 1e23, 5e-324,
        DBL_MIN, DBL_MAX, -DBL_MAX, 2.2250738585072009e-308,
        9007199254740993.0, 0.30000000000000004, 1e-11, 9.99999999999e-12,
        99999999999999999.0, 9999999999999998.0, 1e-310,
    };
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++)
        check_format(fixed[i]);
    /* powers of two and ten and their neighbours */
    for (int e = -1074; e <= 1023; e++) {
        double x = ldexp(1, e);
        check_format(x);
        check_format(nextafter(x, 0));
        check_format(nextafter(x, INFINITY));
    }
    for (int e = -30; e <= 30; e++) {
        double x = pow(10, e);
        check_format(x);
        check_format(nextafter(x, 0));
        check_format(nextafter(x, INFINITY));
    }
    /* short decimals: k·10^e for small k, whose %.15g is exact */
    for (int k = 1; k < 2000; k++)
        for (int e = -14; e <= 14; e++)
            check_format(k * pow(10, e));
    /* integers near 2^53, where ties between 16-digit neighbours occur */
    for (int64_t v = (INT64_C(1) << 53) - 2000; v < (INT64_C(1) << 53) + 2000;
         v++)
        check_format((double)v);
    for (int64_t v = 99999999999999000; v < 100000000000001000; v += 7)
        check_format((double)v);
}

static void test_parse_matches_strtod_on_random_decimals(void **state)
{
    (void)state;
    char s[80];
    for (int i = 0; i < 300000; i++) {
        int nd = 1 + (int)(next64() % 22);
        char *o = s;
        if (next64() & 1)
            *o++ = '-';
        int point = (int)(next64() % (unsigned)(nd + 1));
        for (int k = 0; k < nd; k++) {
            if (k == point && k > 0)
                *o++ = '.';
            int d = (int)(next64() % 10);
            if (k == 0 && d == 0 && point != 1)
                d = 1 + (int)(next64() % 9);
            *o++ = (char)('0' + d);
        }
        if (next64() % 3 == 0)
            o += sprintf(o, "e%d", (int)(next64() % 90) - 45);
        *o = '\0';
        check_parse(s);
    }
}

/* The Eisel–Lemire range: up to 19 significant digits times 10^q, q from
 * −27 to −1 (a scanner's 17-digit coordinates are all there), the
 * digits random in value and in length. */
static void test_parse_matches_strtod_on_digits_times_negative_powers(void **state)
{
    (void)state;
    char s[48];
    for (int i = 0; i < 400000; i++) {
        uint64_t w = next64() % UINT64_C(10000000000000000000);
        w >>= next64() % 64;
        if (w == 0)
            w = 1;
        int q = -1 - (int)(next64() % 27);
        snprintf(s, sizeof s, "%llue%d", (unsigned long long)w, q);
        check_parse(s);
    }
}

static void test_parse_matches_on_printed_doubles(void **state)
{
    (void)state;
    char s[40];
    for (int i = 0; i < 200000; i++) {
        double x = bits_to_double(next64());
        if (!isfinite(x))
            continue;
        snprintf(s, sizeof s, "%.17g", x);
        check_parse(s);
        snprintf(s, sizeof s, "%.16g", x);
        check_parse(s);
        snprintf(s, sizeof s, "%.15e", x);
        check_parse(s);
    }
}

/* Decimals exactly halfway between two doubles and one unit of the last
 * digit either side: the cases a wrong rounding gets wrong. */
static void test_parse_rounds_halfway_cases_to_even(void **state)
{
    (void)state;
    char s[80];
    for (int i = 0; i < 100000; i++) {
        /* m·2^e + 2^(e−1) with e ≤ 0 has an exact decimal expansion of at
         * most 19 significant digits when the magnitude is modest */
        uint64_t m = (next64() >> 11) | UINT64_C(1) << 52;
        int e = -(int)(next64() % 12) - 53;
        double lo = ldexp((double)m, e);
        long double mid = (long double)lo + ldexpl(1, e - 1);
        snprintf(s, sizeof s, "%.25Lg", mid);
        check_parse(s);
        snprintf(s, sizeof s, "%.19Lg", mid);
        check_parse(s);
        snprintf(s, sizeof s, "%.18Lg", mid);
        check_parse(s);
    }
    /* exact midpoints with at most 19 digits: (2m+1)·2^(e−1) for
     * e = −2 .. 11 (integers, or fractions of 1 to 3 binary places) */
    for (int i = 0; i < 100000; i++) {
        uint64_t odd = ((next64() >> 11) | UINT64_C(1) << 52) * 2 + 1;
        int e = (int)(next64() % 14) - 2;
        if (e >= 1) {
            snprintf(s, sizeof s, "%llu", (unsigned long long)(odd << (e - 1)));
        } else {
            int f = 1 - e;
            uint64_t frac = (odd & ((UINT64_C(1) << f) - 1)) * (f == 1 ? 5 : f == 2 ? 25 : 125);
            snprintf(s, sizeof s, "%llu.%0*llu", (unsigned long long)(odd >> f), f,
                     (unsigned long long)frac);
        }
        check_parse(s);
        size_t n = strlen(s);
        if (s[n - 1] != '0' && s[n - 1] != '9') {
            s[n - 1]++;
            check_parse(s);
            s[n - 1] -= 2;
            check_parse(s);
        }
    }
    static const char *const fixed[] = {
        "9007199254740993",            "9007199254740993.0",
        "9007199254740995.0",          "9007199254740992.9999999999",
        "2.2250738585072011e-308",     "2.2250738585072012e-308",
        "4.9406564584124654e-324",     "2.4703282292062327e-324",
        "2.4703282292062328e-324",     "1.7976931348623157e308",
        "1.7976931348623158e308",      "1.7976931348623159e308",
        "1e309",                       "-1e309",
        "1e-400",                      "0.000000000000000000000000001",
        "123456789012345678901234567890", "0.1",
        "0.30000000000000004",         "1e23",
        "8.5e-323",                    "0e999999999999",
        "-0",                          "-0.0",
        "1e-7",                        "100000000000000000000000000e-27",
        "7.2057594037927933e16",       "1.00000000000000011102230246251565404236316680908203125",
        "1.00000000000000011102230246251565404236316680908203124",
        "1.00000000000000011102230246251565404236316680908203126",
        "0.08233250756672848",         "-3.24939882159913",
        "99999999999999999999",        "1.5e27",
        "1.5e28",                      "12345678901234567e-27",
        "12345678901234567e-28",
    };
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++)
        check_parse(fixed[i]);
}

static void test_negative_zero_and_overflow(void **state)
{
    (void)state;
    double d = 1;
    assert_int_equal(proto_decimal_parse("-0.0", 4, &d), 0);
    assert_true(d == 0 && signbit(d));
    assert_int_equal(proto_decimal_parse("-0e5", 4, &d), 0);
    assert_true(d == 0 && signbit(d));
    d = 7;
    assert_int_equal(proto_decimal_parse("1e400", 5, &d), -ERANGE);
    assert_true(d == 7);
    assert_int_equal(proto_decimal_parse("-1e400", 6, &d), -ERANGE);
    assert_int_equal(proto_decimal_parse("1e-400", 6, &d), 0);
    assert_true(d == 0);
    char out[PROTO_DECIMAL_MAX];
    assert_int_equal(proto_decimal_format(out, -0.0), 4);
    assert_string_equal(out, "-0.0");
    assert_int_equal(proto_decimal_format(out, 0.0), 1);
    assert_string_equal(out, "0");
}

static void test_a_long_number_is_parsed_exactly(void **state)
{
    (void)state;
    /* 100,000 digits: beyond any stack copy */
    size_t n = 100000;
    char *s = malloc(n + 8);
    assert_non_null(s);
    s[0] = '0';
    s[1] = '.';
    for (size_t i = 2; i < n; i++)
        s[i] = (char)('0' + i % 10);
    s[n] = '\0';
    check_parse(s);
    free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_format_matches_the_libc_loop_on_random_bits),
        cmocka_unit_test(test_format_matches_on_scanner_like_values),
        cmocka_unit_test(test_format_matches_on_short_and_boundary_values),
        cmocka_unit_test(test_parse_matches_strtod_on_random_decimals),
        cmocka_unit_test(test_parse_matches_strtod_on_digits_times_negative_powers),
        cmocka_unit_test(test_parse_matches_on_printed_doubles),
        cmocka_unit_test(test_parse_rounds_halfway_cases_to_even),
        cmocka_unit_test(test_negative_zero_and_overflow),
        cmocka_unit_test(test_a_long_number_is_parsed_exactly),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
