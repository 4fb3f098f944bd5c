/* test_json_pull.c — the JSON pull tokenizer (proto/json_pull.h): every
 * grammar corner, escapes, UTF-8, numbers, duplicate keys, nesting limits,
 * large inputs, value spans and skipping; and, over hundreds of thousands
 * of generated and mutated texts, the same verdict, error text, line and
 * column as jansson (json_loadb with JSON_REJECT_DUPLICATES) and the same
 * values for accepted texts. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "json_pull.h"

static uint64_t rng = 12345;

static uint64_t rnd(void)
{
    return geo_rand_next(&rng);
}

/* The value at the tokenizer's position as a jansson value (NULL after an
 * error), built from the tokens alone. */
static json_t *build(proto_jpull *j, proto_jtok t)
{
    switch (t) {
    case PROTO_JT_OBJECT: {
        json_t *o = json_object();
        for (;;) {
            proto_jtok k = proto_jpull_next(j);
            if (k == PROTO_JT_OBJECT_END)
                return o;
            if (k != PROTO_JT_KEY) {
                json_decref(o);
                return NULL;
            }
            char *key = strdup(j->str);
            json_t *v = build(j, proto_jpull_next(j));
            if (!v) {
                free(key);
                json_decref(o);
                return NULL;
            }
            json_object_set_new(o, key, v);
            free(key);
        }
    }
    case PROTO_JT_ARRAY: {
        json_t *a = json_array();
        for (;;) {
            proto_jtok e = proto_jpull_next(j);
            if (e == PROTO_JT_ARRAY_END)
                return a;
            json_t *v = build(j, e);
            if (!v) {
                json_decref(a);
                return NULL;
            }
            json_array_append_new(a, v);
        }
    }
    case PROTO_JT_STRING:
        return json_stringn(j->str, j->str_len);
    case PROTO_JT_INTEGER:
        return json_integer(j->integer);
    case PROTO_JT_REAL:
        return json_real(j->real);
    case PROTO_JT_TRUE:
        return json_true();
    case PROTO_JT_FALSE:
        return json_false();
    case PROTO_JT_NULL:
        return json_null();
    default:
        return NULL;
    }
}

static void show(char *out, size_t cap, const char *d, size_t n)
{
    size_t o = 0;
    for (size_t i = 0; i < n && o + 5 < cap; i++) {
        unsigned char c = (unsigned char)d[i];
        o += (size_t)snprintf(out + o, cap - o, c >= 32 && c < 127 ? "%c"
                                                                  : "\\x%02x",
                              c);
    }
}

/* Compares with jansson; fails the test on any difference. */
static void same_as_jansson(const char *d, size_t n)
{
    json_error_t je;
    json_t *want = json_loadb(d, n, JSON_REJECT_DUPLICATES, &je);
    proto_jpull j;
    proto_jpull_init(&j, d, n);
    json_t *got = build(&j, proto_jpull_next(&j));
    proto_jtok end = got ? proto_jpull_next(&j) : PROTO_JT_ERROR;
    char s[400] = "";
    if (want) {
        if (!got || end != PROTO_JT_END || !json_equal(want, got)) {
            show(s, sizeof s, d, n);
            fail_msg("accepted by jansson, not here (%s): %s", j.error.text,
                     s);
        }
    } else if (end != PROTO_JT_ERROR || j.error.line != je.line ||
               j.error.column != je.column ||
               strcmp(j.error.text, je.text) != 0) {
        show(s, sizeof s, d, n);
        fail_msg("%s\n  jansson: %d:%d %s\n  here:    %d:%d %s", s, je.line,
                 je.column, je.text, j.error.line, j.error.column,
                 j.error.text);
    }
    json_decref(want);
    json_decref(got);
    proto_jpull_clear(&j);
}

/* Reads a whole text; returns the error text ("" when accepted). */
static const char *error_of(const char *text)
{
    static char msg[200];
    proto_jpull j;
    proto_jpull_init(&j, text, strlen(text));
    proto_jtok t;
    while ((t = proto_jpull_next(&j)) != PROTO_JT_END && t != PROTO_JT_ERROR)
        ;
    if (t == PROTO_JT_END)
        msg[0] = '\0';
    else
        snprintf(msg, sizeof msg, "%d:%d %s", j.error.line, j.error.column,
                 j.error.text);
    proto_jpull_clear(&j);
    return msg;
}

/* A NUL byte right after a number or a literal: the one case where
 * jansson is lenient (it drops the byte), so the comparison skips it. */
static bool nul_after_word(const char *d, size_t n)
{
    for (size_t i = 1; i < n; i++) {
        unsigned char p = (unsigned char)d[i - 1];
        if (d[i] == 0 && ((p >= '0' && p <= '9') || ((p | 0x20) >= 'a' &&
                                                      (p | 0x20) <= 'z')))
            return true;
    }
    return false;
}

static const char *const frags[] = {
    "{", "}", "[", "]", ":", ",", "\"a\"", "\"b\"", "\"\\u0061\"",
    "\"\\u0000\"", "\"\\ud800\"", "\"\\ud800\\udc00\"", "\"\\udc00\"",
    "\"\\ud800\\u0041\"", "\"\\uDBFF\\uDFFF\"", "\"\\x\"", "\"\\u12g4\"",
    "\"\\u12", "1", "-", "-0", "01", "1.", "1.5", "1e", "1e+", "1e5", "1E-5",
    "-1.5e300", "1e999", "-1e999", "1e-999", "12345678901234567890",
    "-9223372036854775808", "-9223372036854775809", "9223372036854775807",
    "9223372036854775808", "true", "false", "null", "tru", "nul", "NaN",
    "Infinity", "-Infinity", " ", "\n", "\t", "\r", "\xc3\xa9", "\xff",
    "\xc3", "\xe2\x82", "\xed\xa0\x80", "\xf4\x90\x80\x80", "\xc0\x80",
    "\xe0\x80\x80", "\xf0\x80\x80\x80", "\"\xc3\xa9\"", "\"\xff\"", "\"",
    "\\", "\x01", "\x7f", "x", "+", "/", "\"abcdefghijklmnopqrstuvwxyz\"",
    "0", "\"a\\nb\\t\\\\\\/\\b\\f\\r\\\"\"", "\"\n\"", "\"\t\"", "\"\\\n\"",
    "\"\\\xc3\xa9\"", "\"\\u00\xff\"", "0.000001", "-0.0", "1.7976931348623157e308",
};

static void test_fragments_give_jansson_verdicts(void **state)
{
    (void)state;
    size_t nf = sizeof frags / sizeof frags[0];
    char buf[1024];
    for (int it = 0; it < 150000; it++) {
        size_t n = 0;
        if (rnd() & 1)
            buf[n++] = rnd() & 1 ? '{' : '[';
        int k = 1 + (int)(rnd() % 10);
        for (int i = 0; i < k; i++) {
            const char *f = frags[rnd() % nf];
            size_t l = strlen(f);
            memcpy(buf + n, f, l);
            n += l;
        }
        if (rnd() % 8 == 0)
            buf[n++] = 0;
        if (!nul_after_word(buf, n))
            same_as_jansson(buf, n);
    }
}

/* A random valid document with nested objects (some keys repeated across
 * objects, a few escaped), arrays and every kind of scalar. */
static void gen_value(char *b, size_t *n, size_t cap, int depth)
{
    static const char *const scalars[] = {
        "0", "-0", "1", "-17", "3.25", "-0.0", "1e-7", "6.02e23",
        "9223372036854775807", "0.1", "true", "false", "null", "\"\"",
        "\"x\"", "\"\\u00e9\\n\"", "\"\\ud83d\\ude00\"", "\"\xe2\x82\xac\"",
        "0.08233250756672848", "-3.2493988215991300e+00",
    };
    static const char *const keys[] = {"a", "b", "vertices", "facets",
                                       "plane", "\\u0061", "\xc3\xa9"};
    if (*n + 64 > cap)
        return;
    int kind = depth > 6 ? 2 : (int)(rnd() % 3);
    if (kind == 0) {
        b[(*n)++] = '{';
        int m = (int)(rnd() % 5);
        /* distinct keys: an unescaped "a" and "\u0061" never together */
        int used = 0;
        for (int i = 0; i < m; i++) {
            int k = (int)(rnd() % 7);
            int id = k == 5 ? 0 : k;
            if (used & 1 << id)
                continue;
            used |= 1 << id;
            if (*n + 64 > cap)
                break;
            if (b[*n - 1] != '{')
                b[(*n)++] = ',';
            *n += (size_t)snprintf(b + *n, cap - *n, "\"%s\"%s:", keys[k],
                                   rnd() % 4 ? "" : " ");
            gen_value(b, n, cap, depth + 1);
        }
        b[(*n)++] = '}';
    } else if (kind == 1) {
        b[(*n)++] = '[';
        int m = (int)(rnd() % 5);
        for (int i = 0; i < m && *n + 64 < cap; i++) {
            if (i)
                b[(*n)++] = rnd() % 4 ? ',' : ',';
            if (rnd() % 5 == 0)
                b[(*n)++] = '\n';
            gen_value(b, n, cap, depth + 1);
        }
        b[(*n)++] = ']';
    } else {
        const char *s = scalars[rnd() % (sizeof scalars / sizeof scalars[0])];
        size_t l = strlen(s);
        memcpy(b + *n, s, l);
        *n += l;
    }
}

static void test_mutated_documents_give_jansson_verdicts(void **state)
{
    (void)state;
    static const char interesting[] = "{}[]:,\"\\u01e.-+ \n\x00\xff\xc3";
    char buf[4096];
    for (int it = 0; it < 40000; it++) {
        size_t n = 0;
        buf[n++] = rnd() & 1 ? '[' : '{';
        if (buf[0] == '{') {
            n += (size_t)snprintf(buf + n, sizeof buf - n, "\"k\":");
            gen_value(buf, &n, sizeof buf - 16, 1);
            buf[n++] = '}';
        } else {
            gen_value(buf, &n, sizeof buf - 16, 1);
            buf[n++] = ']';
        }
        same_as_jansson(buf, n);
        int muts = 1 + (int)(rnd() % 3);
        for (int m = 0; m < muts && n > 1; m++) {
            size_t at = rnd() % n;
            switch (rnd() % 4) {
            case 0: /* substitute */
                buf[at] = interesting[rnd() % (sizeof interesting - 1)];
                break;
            case 1: /* delete */
                memmove(buf + at, buf + at + 1, n - at - 1);
                n--;
                break;
            case 2: /* insert */
                if (n + 1 < sizeof buf) {
                    memmove(buf + at + 1, buf + at, n - at);
                    buf[at] = interesting[rnd() % (sizeof interesting - 1)];
                    n++;
                }
                break;
            default: /* truncate */
                n = at + 1;
                break;
            }
        }
        if (!nul_after_word(buf, n))
            same_as_jansson(buf, n);
    }
}

static void test_grammar_corners(void **state)
{
    (void)state;
    assert_string_equal(error_of("{}"), "");
    assert_string_equal(error_of("[]"), "");
    assert_string_equal(error_of(" \t\r\n[ 1 , 2 ]\n\n"), "");
    assert_string_equal(error_of(""), "1:0 '[' or '{' expected near end "
                                      "of file");
    assert_string_equal(error_of("  "), "1:2 '[' or '{' expected near end "
                                        "of file");
    assert_string_equal(error_of("1"), "1:1 '[' or '{' expected near '1'");
    assert_string_equal(error_of("\"s\""),
                        "1:3 '[' or '{' expected near '\"s\"'");
    assert_string_equal(error_of("[1,]"), "1:4 unexpected token near ']'");
    assert_string_equal(error_of("[,1]"), "1:2 unexpected token near ','");
    assert_string_equal(error_of("[1 2]"), "1:4 ']' expected near '2'");
    assert_string_equal(error_of("[1,"), "1:3 ']' expected near end of file");
    assert_string_equal(error_of("["), "1:1 ']' expected near end of file");
    assert_string_equal(error_of("{\"a\":1,}"),
                        "1:8 string or '}' expected near '}'");
    assert_string_equal(error_of("{\"a\" 1}"), "1:6 ':' expected near '1'");
    assert_string_equal(error_of("{\"a\":}"), "1:6 unexpected token near '}'");
    assert_string_equal(error_of("{1:2}"),
                        "1:2 string or '}' expected near '1'");
    assert_string_equal(error_of("{\"a\":1"),
                        "1:6 '}' expected near end of file");
    assert_string_equal(error_of("{\"a\":1]"), "1:7 '}' expected near ']'");
    assert_string_equal(error_of("[}"), "1:2 unexpected token near '}'");
    assert_string_equal(error_of("[1]]"), "1:4 end of file expected near ']'");
    assert_string_equal(error_of("[1] x"), "1:5 end of file expected near 'x'");
    assert_string_equal(error_of("[tru]"), "1:4 invalid token near 'tru'");
    assert_string_equal(error_of("[True]"), "1:5 invalid token near 'True'");
    assert_string_equal(error_of("[NaN]"), "1:4 invalid token near 'NaN'");
    assert_string_equal(error_of("[-Infinity]"),
                        "1:2 invalid token near '-'");
    assert_string_equal(error_of("[+1]"), "1:2 invalid token near '+'");
    assert_string_equal(error_of("[01]"), "1:2 invalid token near '0'");
    assert_string_equal(error_of("[1.]"), "1:3 invalid token near '1.'");
    assert_string_equal(error_of("[.5]"), "1:2 invalid token near '.'");
    assert_string_equal(error_of("[1e]"), "1:3 invalid token near '1e'");
    assert_string_equal(error_of("[1e+]"), "1:4 invalid token near '1e+'");
    assert_string_equal(error_of("[1,\n2,\n  x]"),
                        "3:3 invalid token near 'x'");
    assert_string_equal(error_of("[\"\xc3\xa9\xc3\xa9\", x]"),
                        "1:8 invalid token near 'x'");
    assert_string_equal(error_of("[\xc3\xa9]"),
                        "1:2 invalid token near '\xc3\xa9'");
    assert_string_equal(error_of("[\"a\"\"b\"]"),
                        "1:7 ']' expected near '\"b\"'");
}

static void test_strings_escapes_and_utf8(void **state)
{
    (void)state;
    static const char *const ok[] = {
        "[\"\\\"\\\\\\/\\b\\f\\n\\r\\t\"]", "[\"\\u0041\\u00e9\\u20AC\"]",
        "[\"\\ud83d\\ude00\"]", "[\"\xf0\x9f\x98\x80\"]", "[\"\x7f\"]",
        "[\"\xef\xbf\xbf\xf4\x8f\xbf\xbf\"]", "[\"\"]",
    };
    for (size_t i = 0; i < sizeof ok / sizeof ok[0]; i++)
        assert_string_equal(error_of(ok[i]), "");
    assert_string_equal(error_of("[\"a\\x\"]"),
                        "1:5 invalid escape near '\"a\\x'");
    assert_string_equal(error_of("[\"\\u12G4\"]"),
                        "1:7 invalid escape near '\"\\u12G'");
    assert_string_equal(error_of("[\"\\u12"), "1:6 invalid escape near "
                                              "'\"\\u12'");
    assert_string_equal(error_of("[\"abc"),
                        "1:5 premature end of input near '\"abc'");
    assert_string_equal(error_of("[\"a\nb\"]"),
                        "1:3 unexpected newline near '\"a'");
    assert_string_equal(error_of("[\"a\tb\"]"),
                        "1:3 control character 0x9 near '\"a'");
    assert_string_equal(error_of("[\"\\ud800\"]"),
                        "1:9 invalid Unicode '\\uD800' near '\"\\ud800\"'");
    assert_string_equal(error_of("[\"\\ud800x\"]"),
                        "1:10 invalid Unicode '\\uD800' near '\"\\ud800x\"'");
    assert_string_equal(error_of("[\"\\udc00\"]"),
                        "1:9 invalid Unicode '\\uDC00' near '\"\\udc00\"'");
    assert_string_equal(error_of("[\"\\ud800\\u0041\"]"),
                        "1:15 invalid Unicode '\\uD800\\u0041' near "
                        "'\"\\ud800\\u0041\"'");
    assert_string_equal(error_of("[\"a\\u0000\"]"),
                        "1:10 \\u0000 is not allowed without JSON_ALLOW_NUL "
                        "near '\"a\\u0000\"'");
    assert_string_equal(error_of("{\"a\\u0000\":1}"),
                        "1:10 NUL byte in object key not supported near "
                        "'\"a\\u0000\"'");
    /* invalid UTF-8: the message names the first byte of the sequence and
     * the column stops before it */
    assert_string_equal(error_of("[\"\xff\"]"),
                        "1:2 unable to decode byte 0xff near '\"'");
    assert_string_equal(error_of("[\"\xc0\x80\"]"),
                        "1:2 unable to decode byte 0xc0 near '\"'");
    assert_string_equal(error_of("[\"\xe0\x80\x80\"]"),
                        "1:2 unable to decode byte 0xe0 near '\"'");
    assert_string_equal(error_of("[\"\xed\xa0\x80\"]"),
                        "1:2 unable to decode byte 0xed near '\"'");
    assert_string_equal(error_of("[\"\xf4\x90\x80\x80\"]"),
                        "1:2 unable to decode byte 0xf4 near '\"'");
    assert_string_equal(error_of("[\"\xc3\"]"),
                        "1:2 unable to decode byte 0xc3 near '\"'");
    assert_string_equal(error_of("[\"\x80\"]"),
                        "1:2 unable to decode byte 0x80 near '\"'");
    assert_string_equal(error_of("[\xff]"), "1:1 unable to decode byte 0xff");
    assert_string_equal(error_of("[1\xff]"),
                        "1:2 unable to decode byte 0xff near '1'");
    assert_string_equal(error_of("[\"abcdefghijklmnopqrstuvwxyz\xff\"]"),
                        "1:28 unable to decode byte 0xff");
}

/* The decoded text of the one string in text. */
static void decodes_to(const char *text, const char *want, size_t want_len)
{
    proto_jpull j;
    proto_jpull_init(&j, text, strlen(text));
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_ARRAY);
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_STRING);
    assert_int_equal(j.str_len, want_len);
    assert_memory_equal(j.str, want, want_len);
    assert_int_equal(j.str[want_len], '\0');
    proto_jpull_clear(&j);
}

static void test_escapes_decode_to_utf8(void **state)
{
    (void)state;
    decodes_to("[\"\\\"\\\\\\/\\b\\f\\n\\r\\t\"]", "\"\\/\b\f\n\r\t", 8);
    decodes_to("[\"\\u0041\\u00e9\\u20AC\"]", "A\xc3\xa9\xe2\x82\xac", 6);
    decodes_to("[\"\\ud83d\\ude00!\"]", "\xf0\x9f\x98\x80!", 5);
    decodes_to("[\"\\uDBFF\\uDFFF\"]", "\xf4\x8f\xbf\xbf", 4);
    decodes_to("[\"plain \xc3\xa9\"]", "plain \xc3\xa9", 8);
}

static void test_numbers(void **state)
{
    (void)state;
    const char *text = "[0,-0,9223372036854775807,-9223372036854775808,1.5,"
                       "-0.0,1e2,2E-3,0.1,1e-400]";
    proto_jpull j;
    proto_jpull_init(&j, text, strlen(text));
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_ARRAY);
    static const int64_t ints[] = {0, 0, INT64_MAX, INT64_MIN};
    for (int i = 0; i < 4; i++) {
        assert_int_equal(proto_jpull_next(&j), PROTO_JT_INTEGER);
        assert_true(j.integer == ints[i]);
    }
    static const double reals[] = {1.5, -0.0, 100, 0.002, 0.1, 0};
    for (int i = 0; i < 6; i++) {
        assert_int_equal(proto_jpull_next(&j), PROTO_JT_REAL);
        assert_true(j.real == reals[i]);
        assert_true(!!signbit(j.real) == !!signbit(reals[i]));
    }
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_ARRAY_END);
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_END);
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_END);
    proto_jpull_clear(&j);
    assert_string_equal(error_of("[9223372036854775808]"),
                        "1:20 too big integer near '9223372036854775808'");
    assert_string_equal(error_of("[-9223372036854775809]"),
                        "1:21 too big negative integer near "
                        "'-9223372036854775809'");
    assert_string_equal(error_of("[123456789012345678901]"),
                        "1:22 too big integer");
    assert_string_equal(error_of("[1e309]"),
                        "1:6 real number overflow near '1e309'");
    assert_string_equal(error_of("[-1.5e400]"),
                        "1:9 real number overflow near '-1.5e400'");
}

/* Every number the tokenizer reads is strtod's double, bit for bit
 * (integers: strtoll's value), over random digit strings with fractions
 * of every length, leading zeros and exponents. */
static void test_numbers_read_like_strtod(void **state)
{
    (void)state;
    char s[96];
    for (int it = 0; it < 300000; it++) {
        char *o = s;
        *o++ = '[';
        char *num = o;
        if (rnd() & 1)
            *o++ = '-';
        int ni = (int)(rnd() % 21);
        if (ni == 0 || rnd() % 3 == 0) {
            *o++ = '0';
        } else {
            *o++ = (char)('1' + rnd() % 9);
            for (int k = 1; k < ni; k++)
                *o++ = (char)('0' + rnd() % 10);
        }
        if (rnd() % 4) {
            *o++ = '.';
            int zeros = rnd() % 3 ? 0 : (int)(rnd() % 12);
            for (int k = 0; k < zeros; k++)
                *o++ = '0';
            int nf = 1 + (int)(rnd() % 24);
            for (int k = 0; k < nf; k++)
                *o++ = (char)('0' + rnd() % 10);
        }
        if (rnd() % 4 == 0)
            o += sprintf(o, "%s%d", rnd() & 1 ? "e" : "E-",
                         (int)(rnd() % 40));
        *o = '\0';
        size_t nlen = (size_t)(o - num);
        *o++ = ']';
        proto_jpull j;
        proto_jpull_init(&j, s, (size_t)(o - s));
        assert_int_equal(proto_jpull_next(&j), PROTO_JT_ARRAY);
        proto_jtok t = proto_jpull_next(&j);
        s[nlen + 1] = '\0';
        if (t == PROTO_JT_INTEGER) {
            long long want = strtoll(num, NULL, 10);
            if (j.integer != want)
                fail_msg("%s: %lld, want %lld", num, (long long)j.integer,
                         want);
        } else if (t == PROTO_JT_REAL) {
            double want = strtod(num, NULL);
            if (memcmp(&want, &j.real, sizeof want) != 0)
                fail_msg("%s: %a, want %a", num, j.real, want);
        } else {
            /* only integers beyond int64 are refused */
            assert_int_equal(t, PROTO_JT_ERROR);
            assert_non_null(strstr(j.error.text, "too big"));
        }
        proto_jpull_clear(&j);
    }
}

/* proto_json_number (the model reader's number) agrees with the
 * tokenizer on short byte strings of digits, signs, points, exponents,
 * ends and bytes of 0x80 and above, at every distance from the end of the
 * data: true exactly where the tokenizer reads a number whose next byte
 * is below 0x80, with its end, kind and value. */
static void test_json_number_agrees_with_the_tokenizer(void **state)
{
    (void)state;
    static const char alphabet[] = "0123456789000111-.eE+,] \x80\xfa\xff";
    unsigned char s[24];
    for (int it = 0; it < 400000; it++) {
        size_t len = 1 + rnd() % 12, pre = 1 + rnd() % 10;
        s[0] = '[';
        for (size_t k = 1; k < pre + len; k++)
            s[k] = k < pre && rnd() % 2 ? ' '
                                        : (unsigned char)
                                              alphabet[rnd() % (sizeof alphabet - 1)];
        size_t n = pre + len, start = pre;
        if (s[start] != '-' && (s[start] < '0' || s[start] > '9'))
            s[start] = (unsigned char)('1' + rnd() % 9);
        size_t end;
        bool is_int;
        int64_t integer = 0;
        double real = 0;
        bool ok = proto_json_number(s, n, start, &end, &is_int, &integer,
                                    &real);
        /* the tokenizer on the same bytes as an array's first element */
        s[start - 1] = '[';
        proto_jpull j;
        proto_jpull_init(&j, s + start - 1, n - start + 1);
        assert_int_equal(proto_jpull_next(&j), PROTO_JT_ARRAY);
        proto_jtok t = proto_jpull_next(&j);
        size_t tend = start - 1 + j.tok_end;
        bool tok_number = (t == PROTO_JT_INTEGER || t == PROTO_JT_REAL) &&
                          (tend >= n || s[tend] < 0x80);
        if (ok != tok_number)
            fail_msg("'%.*s': number %d, tokenizer %d", (int)(n - start),
                     (const char *)s + start, ok, (int)t);
        if (ok) {
            assert_int_equal(end, tend);
            assert_int_equal(is_int, t == PROTO_JT_INTEGER);
            if (is_int)
                assert_true(integer == j.integer);
            else
                assert_memory_equal(&real, &j.real, sizeof real);
        }
        proto_jpull_clear(&j);
    }
}

static void test_duplicate_keys_are_refused_per_object(void **state)
{
    (void)state;
    assert_string_equal(error_of("{\"a\":1,\"a\":2}"),
                        "1:10 duplicate object key near '\"a\"'");
    assert_string_equal(error_of("{\"a\":1,\"\\u0061\":2}"),
                        "1:15 duplicate object key near '\"\\u0061\"'");
    /* the same name in sibling and nested objects is fine */
    assert_string_equal(error_of("[{\"a\":1},{\"a\":2,\"b\":{\"a\":3}}]"), "");
    assert_string_equal(error_of("{\"a\":{\"a\":{\"a\":1}},\"b\":{\"a\":2}}"),
                        "");
    assert_string_equal(error_of("{\"a\":{\"x\":1},\"b\":2,\"a\":3}"),
                        "1:22 duplicate object key near '\"a\"'");
    assert_string_equal(error_of("{\"\":1,\"\":2}"),
                        "1:8 duplicate object key near '\"\"'");
    /* an object's first name is only logged until a second comes: the
     * third repeating the first, and a one-member object inside the
     * first member, are still caught */
    assert_string_equal(error_of("{\"a\":1,\"b\":2,\"a\":3}"),
                        "1:16 duplicate object key near '\"a\"'");
    assert_string_equal(error_of("{\"a\":{\"a\":1},\"a\":2}"),
                        "1:16 duplicate object key near '\"a\"'");
    assert_string_equal(error_of("{\"a\":{\"a\":1},\"b\":{\"a\":1,\"a\":2}}"),
                        "1:27 duplicate object key near '\"a\"'");
    /* an empty first name, before anything was stored for names */
    assert_string_equal(error_of("{\"\":1,\"a\":2}"), "");
    /* many keys in one object */
    size_t cap = 200000 * 16;
    char *s = malloc(cap);
    assert_non_null(s);
    size_t n = (size_t)snprintf(s, cap, "{");
    for (int i = 0; i < 200000; i++)
        n += (size_t)snprintf(s + n, cap - n, "%s\"k%d\":%d", i ? "," : "", i,
                              i);
    n += (size_t)snprintf(s + n, cap - n, "}");
    assert_string_equal(error_of(s), "");
    snprintf(s + n - 1, cap - n + 1, ",\"k123456\":0}");
    assert_non_null(strstr(error_of(s), "duplicate object key near "
                                        "'\"k123456\"'"));
    /* an object's names are forgotten when it ends: the outer names,
     * mixed in the table with thousands of inner ones dropped since, are
     * all still found, and the inner names may come back in siblings */
    n = (size_t)snprintf(s, cap, "{");
    for (int i = 0; i < 300; i++) {
        n += (size_t)snprintf(s + n, cap - n, "%s\"o%d\":{", i ? "," : "", i);
        /* one inner object large enough to grow (rehash) the table
         * while the outer names are in it */
        for (int k = 0; k < (i == 150 ? 3000 : 20); k++)
            n += (size_t)snprintf(s + n, cap - n, "%s\"o%d\":%d", k ? "," : "",
                                  (i * 7 + k * 13) % 3001, k);
        n += (size_t)snprintf(s + n, cap - n, "}");
    }
    n += (size_t)snprintf(s + n, cap - n, "}");
    assert_string_equal(error_of(s), "");
    for (int i = 0; i < 300; i++) {
        char want[64];
        snprintf(s + n - 1, cap - n + 1, ",\"o%d\":0}", i);
        snprintf(want, sizeof want, "duplicate object key near '\"o%d\"'", i);
        if (!strstr(error_of(s), want))
            fail_msg("o%d repeated in the outer object is not refused", i);
    }
    free(s);
}

/* depth nested arrays around inner. */
static char *nested(int depth, const char *inner)
{
    size_t n = strlen(inner);
    char *s = malloc(2 * (size_t)depth + n + 1);
    memset(s, '[', (size_t)depth);
    memcpy(s + depth, inner, n);
    memset(s + depth + n, ']', (size_t)depth);
    s[2 * depth + n] = '\0';
    return s;
}

static void test_nesting_limit_is_janssons(void **state)
{
    (void)state;
    char *s = nested(PROTO_JSON_MAX_DEPTH, "");
    assert_string_equal(error_of(s), "");
    same_as_jansson(s, strlen(s));
    free(s);
    s = nested(PROTO_JSON_MAX_DEPTH + 1, "");
    assert_string_equal(error_of(s), "1:2049 maximum parsing depth reached "
                                     "near '['");
    same_as_jansson(s, strlen(s));
    free(s);
    /* a scalar counts as one level too */
    s = nested(PROTO_JSON_MAX_DEPTH, "1");
    assert_non_null(strstr(error_of(s), "maximum parsing depth reached "
                                        "near '1'"));
    same_as_jansson(s, strlen(s));
    free(s);
    s = nested(PROTO_JSON_MAX_DEPTH - 1, "{\"a\":1}");
    assert_non_null(strstr(error_of(s), "maximum parsing depth reached "
                                        "near '1'"));
    same_as_jansson(s, strlen(s));
    free(s);
    /* far deeper than the limit: refused at once, nothing grows */
    s = nested(1000000, "");
    assert_non_null(strstr(error_of(s), "maximum parsing depth reached"));
    free(s);
}

static void test_huge_inputs(void **state)
{
    (void)state;
    /* 4 MB of numbers in one array */
    size_t cap = 4u << 20;
    char *s = malloc(cap + 64);
    assert_non_null(s);
    size_t n = 0;
    s[n++] = '[';
    int count = 0;
    while (n < cap) {
        n += (size_t)snprintf(s + n, 64, "%s%.17g", count ? "," : "",
                              (double)count * 0.001);
        count++;
    }
    s[n++] = ']';
    proto_jpull j;
    proto_jpull_init(&j, s, n);
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_ARRAY);
    int seen = 0;
    proto_jtok t;
    while ((t = proto_jpull_next(&j)) == PROTO_JT_REAL ||
           t == PROTO_JT_INTEGER)
        seen++;
    assert_int_equal(t, PROTO_JT_ARRAY_END);
    assert_int_equal(seen, count);
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_END);
    proto_jpull_clear(&j);
    /* one 4 MB string with escapes and multi-byte characters */
    n = 0;
    s[n++] = '[';
    s[n++] = '"';
    while (n < cap) {
        memcpy(s + n, "ab\\n\xc3\xa9\\u20ac", 12);
        n += 12;
    }
    s[n++] = '"';
    s[n++] = ']';
    size_t reps = (n - 4) / 12;
    proto_jpull_init(&j, s, n);
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_ARRAY);
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_STRING);
    assert_int_equal(j.str_len, reps * 8);
    assert_memory_equal(j.str + j.str_len - 8, "ab\n\xc3\xa9\xe2\x82\xac", 8);
    proto_jpull_clear(&j);
    /* an error at the end of a long multi-line text names the last line */
    n = 0;
    s[n++] = '[';
    for (int i = 0; i < 100000; i++)
        n += (size_t)snprintf(s + n, 64, "%d,\n", i);
    n += (size_t)snprintf(s + n, 64, "  x]");
    s[n] = '\0';
    assert_string_equal(error_of(s), "100001:3 invalid token near 'x'");
    free(s);
}

static void test_spans_and_skip(void **state)
{
    (void)state;
    const char *text = "{\"a\": [1, {\"b\": [2, 3]}, \"x\"], \"c\": 4.5, "
                       "\"d\": {\"e\": null}}";
    proto_jpull j;
    proto_jpull_init(&j, text, strlen(text));
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_OBJECT);
    assert_int_equal(j.depth, 1);
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_KEY);
    assert_string_equal(j.str, "a");
    assert_int_equal(j.tok_start, 1);
    assert_int_equal(j.tok_end, 4);
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_ARRAY);
    size_t start = j.tok_start;
    assert_int_equal(proto_jpull_skip(&j), PROTO_JT_ARRAY_END);
    assert_int_equal(j.depth, 1);
    assert_memory_equal(text + start, "[1, {\"b\": [2, 3]}, \"x\"]",
                        j.tok_end - start);
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_KEY);
    assert_string_equal(j.str, "c");
    /* after a key, skip reads the member's whole value */
    assert_int_equal(proto_jpull_skip(&j), PROTO_JT_REAL);
    assert_true(j.real == 4.5);
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_KEY);
    assert_int_equal(proto_jpull_skip(&j), PROTO_JT_OBJECT_END);
    assert_int_equal(j.depth, 1);
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_OBJECT_END);
    assert_int_equal(j.depth, 0);
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_END);
    assert_int_equal(proto_jpull_skip(&j), PROTO_JT_END);
    proto_jpull_clear(&j);
    /* skipping still checks everything */
    text = "[{\"a\":1,\"a\":2}]";
    proto_jpull_init(&j, text, strlen(text));
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_ARRAY);
    assert_int_equal(proto_jpull_skip(&j), PROTO_JT_ERROR);
    assert_string_equal(j.error.text, "duplicate object key near '\"a\"'");
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_ERROR);
    proto_jpull_clear(&j);
}

static void test_nul_after_a_number_is_an_error(void **state)
{
    (void)state;
    /* jansson drops this byte; it is not JSON */
    proto_jpull j;
    proto_jpull_init(&j, "[1\0]", 4);
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_ARRAY);
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_INTEGER);
    assert_int_equal(proto_jpull_next(&j), PROTO_JT_ERROR);
    assert_string_equal(j.error.text, "']' expected near end of file");
    proto_jpull_clear(&j);
    same_as_jansson("[\0]", 3);
    same_as_jansson("[\"a\0\"]", 5);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grammar_corners),
        cmocka_unit_test(test_strings_escapes_and_utf8),
        cmocka_unit_test(test_escapes_decode_to_utf8),
        cmocka_unit_test(test_numbers),
        cmocka_unit_test(test_numbers_read_like_strtod),
        cmocka_unit_test(test_json_number_agrees_with_the_tokenizer),
        cmocka_unit_test(test_duplicate_keys_are_refused_per_object),
        cmocka_unit_test(test_nesting_limit_is_janssons),
        cmocka_unit_test(test_huge_inputs),
        cmocka_unit_test(test_spans_and_skip),
        cmocka_unit_test(test_nul_after_a_number_is_an_error),
        cmocka_unit_test(test_fragments_give_jansson_verdicts),
        cmocka_unit_test(test_mutated_documents_give_jansson_verdicts),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
