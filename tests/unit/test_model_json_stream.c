/* test_model_json_stream.c — the streaming facet-model/1 reader (text →
 * geo_poly through proto/json_pull.h) against the tree reader (jansson
 * value → proto_model_from_json): for generated documents with members in
 * any order, every kind of structural error, tight limits and byte
 * mutations, both give the same model and report, or the same error
 * message. A third of the documents are in the layout facet writes, which
 * the streaming reader reads by its fast path (and leaves to the token
 * reader at the first thing outside it). Also the embedded form
 * (proto_model_from_jpull) with a path prefix, as the daemon reads a job
 * body. */
#include "testutil.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "model_cmp.h"
#include "model_io.h"

static uint64_t rng = 77;

static unsigned rnd(unsigned n)
{
    return (unsigned)(geo_rand_next(&rng) % n);
}

/* The reference: jansson's tree, then proto_model_from_json_ex. */
static geo_poly *tree_read(const char *d, size_t n, const proto_limits *lim,
                           proto_read_report *rep, geo_err *err)
{
    proto_limits dl;
    if (!lim) {
        proto_limits_default(&dl);
        lim = &dl;
    }
    if (n > lim->max_bytes) {
        geo_err_set(err, -ERANGE, "%zu bytes exceed the limit of %zu", n,
                    lim->max_bytes);
        return NULL;
    }
    json_error_t je;
    json_t *root = json_loadb(d, n, JSON_REJECT_DUPLICATES, &je);
    if (!root) {
        geo_err_set(err, -EINVAL, "line %d, column %d: %s", je.line,
                    je.column, je.text);
        return NULL;
    }
    geo_poly *p = proto_model_from_json_ex(root, lim, NULL, rep, err);
    json_decref(root);
    return p;
}

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

static int compared, accepted;

static void same_as_tree(const char *d, size_t n, const proto_limits *lim)
{
    if (nul_after_word(d, n))
        return;
    geo_err e1 = {{0}}, e2 = {{0}};
    proto_read_report r1, r2;
    memset(&r1, 0, sizeof r1);
    memset(&r2, 0, sizeof r2);
    geo_poly *want = tree_read(d, n, lim, &r1, &e1);
    geo_poly *got = proto_model_read_mem_ex(d, n, PROTO_FMT_JSON, lim, &r2,
                                            &e2);
    compared++;
    if (!want != !got || (!want && strcmp(e1.msg, e2.msg) != 0))
        fail_msg("tree: %s\nstream: %s\ntext: %.*s", want ? "ok" : e1.msg,
                 got ? "ok" : e2.msg, (int)(n < 600 ? n : 600), d);
    if (want) {
        accepted++;
        char why[256];
        if (!tu_poly_same(want, got, 0, 0, why, sizeof why))
            fail_msg("models differ: %s", why);
        if (r1.planes_given != r2.planes_given ||
            r1.plane_mismatches != r2.plane_mismatches ||
            r1.worst_facet != r2.worst_facet ||
            r1.worst_deviation != r2.worst_deviation ||
            strcmp(r1.first, r2.first) != 0)
            fail_msg("reports differ: %s / %s", r1.first, r2.first);
    }
    geo_poly_free(want);
    geo_poly_free(got);
}

/* A cube of side 2 centred at the origin, with outward planes. */
static const int cube_f[6][4] = {
    {0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
    {2, 3, 7, 6}, {1, 2, 6, 5}, {0, 4, 7, 3},
};
static const double cube_pl[6][4] = {
    {0, 0, -1, -1}, {0, 0, 1, -1}, {0, -1, 0, -1},
    {0, 1, 0, -1},  {1, 0, 0, -1}, {-1, 0, 0, -1},
};

typedef struct text {
    char *s;
    size_t n, cap;
} text;

static void put(text *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static void put(text *t, const char *fmt, ...)
{
    va_list ap;
    for (;;) {
        va_start(ap, fmt);
        int k = vsnprintf(t->s + t->n, t->cap - t->n, fmt, ap);
        va_end(ap);
        if ((size_t)k < t->cap - t->n) {
            t->n += (size_t)k;
            return;
        }
        t->cap = t->cap * 2 + (size_t)k + 64;
        t->s = realloc(t->s, t->cap);
    }
}

/* One of several wrong values, or a valid-looking one. */
static void odd_value(text *t)
{
    static const char *const v[] = {"null", "1", "\"x\"", "[]", "{}", "[1,2]",
                                    "true", "1.5", "-1", "[[0,0,0]]"};
    put(t, "%s", v[rnd(10)]);
}

static void gen_vertices(text *t, bool errors)
{
    put(t, "[");
    for (int i = 0; i < 8; i++) {
        if (i)
            put(t, ",");
        if (errors && rnd(40) == 0) {
            odd_value(t);
            continue;
        }
        double x = i & 1 ? 1 : -1, y = i & 2 ? 1 : -1, z = i & 4 ? 1 : -1;
        /* vertex order matches cube_f: 0..3 bottom ring, 4..7 top ring */
        static const int ring[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
        x = ring[i % 4][0];
        y = ring[i % 4][1];
        z = i < 4 ? -1 : 1;
        if (errors && rnd(60) == 0)
            put(t, "[%g,%g]", x, y);
        else if (errors && rnd(60) == 0)
            put(t, "[%g,\"%g\",%g]", x, y, z);
        else if (errors && rnd(80) == 0)
            put(t, "[%g,%g,%g,%g]", x, y, z, x);
        else if (rnd(4) == 0)
            put(t, "[%g.0,%g,%.17g]", x, y, z + (errors && rnd(20) == 0 ? 1e-3 : 0));
        else
            put(t, "[%g,%g,%g]", x, y, z);
    }
    put(t, "]");
}

/* canonical: the layout facet writes (the reader's fast path) — facet
 * members "vertices" then "plane", no other member anywhere */
static void gen_facet(text *t, int f, bool errors, bool canonical)
{
    if (errors && rnd(50) == 0) {
        odd_value(t);
        return;
    }
    put(t, "{");
    bool plane_first = !canonical && rnd(2), any = false;
    for (int part = 0; part < 3; part++) {
        int what = plane_first ? (part == 0 ? 1 : part == 1 ? 0 : 2)
                               : part;
        if (what == 0) {
            if (errors && rnd(60) == 0)
                continue; /* vertices missing */
            put(t, "%s\"vertices\":", any ? "," : "");
            any = true;
            if (errors && rnd(60) == 0) {
                odd_value(t);
                continue;
            }
            put(t, "[");
            int n = errors && rnd(50) == 0 ? 2 : 4;
            for (int i = 0; i < n; i++) {
                int v = cube_f[f][i];
                if (errors && rnd(70) == 0)
                    v = (int)rnd(3) == 0 ? -1 - (int)rnd(3) : 8 + (int)rnd(9000);
                if (errors && rnd(120) == 0)
                    put(t, "%s%d.0", i ? "," : "", v);
                else if (errors && rnd(120) == 0)
                    put(t, "%s%d", i ? "," : "", cube_f[f][i ? i - 1 : 0]);
                else
                    put(t, "%s%d", i ? "," : "", v);
            }
            put(t, "]");
        } else if (what == 1) {
            if (rnd(5) == 0)
                continue; /* plane computed */
            put(t, "%s\"plane\":", any ? "," : "");
            any = true;
            if (errors && rnd(60) == 0) {
                odd_value(t);
                continue;
            }
            int n = errors && rnd(60) == 0 ? 3 : 4;
            put(t, "[");
            for (int k = 0; k < n; k++) {
                double c = cube_pl[f][k];
                if (errors && rnd(40) == 0)
                    c = -c; /* inward or off */
                if (errors && rnd(100) == 0)
                    put(t, "%snull", k ? "," : "");
                else
                    put(t, "%s%g", k ? "," : "", c * (k < 3 && rnd(4) == 0 ? 2 : 1));
            }
            put(t, "]");
        } else if (!canonical && rnd(4) == 0) {
            put(t, "%s\"colour\":[{\"r\":1},\"red\"]", any ? "," : "");
            any = true;
        }
    }
    put(t, "}");
}

static void gen_model(text *t, bool errors, bool canonical)
{
    t->n = 0;
    put(t, "{");
    int order[6] = {0, 1, 2, 3, 4, 5};
    for (int i = 5; i > 0; i--) {
        int k = (int)rnd((unsigned)i + 1), x = order[i];
        order[i] = order[k];
        order[k] = x;
    }
    bool any = false;
    for (int i = 0; i < 6; i++) {
        int m = order[i];
        if (errors && rnd(40) == 0)
            continue; /* member missing */
        if (m == 4 && rnd(2))
            continue; /* units is optional */
        if ((m == 5 || m == 3) && (canonical || rnd(2)))
            continue; /* an extra member, a name */
        put(t, "%s", any ? "," : "");
        any = true;
        switch (m) {
        case 0:
            put(t, "\"format\":");
            if (errors && rnd(40) == 0)
                odd_value(t);
            else
                put(t, errors && rnd(40) == 0 ? "\"facet-model/2\""
                                               : "\"facet-model/1\"");
            break;
        case 1:
            put(t, "\"vertices\":");
            if (errors && rnd(40) == 0)
                odd_value(t);
            else
                gen_vertices(t, errors);
            break;
        case 2:
            put(t, "\"facets\":");
            if (errors && rnd(40) == 0) {
                odd_value(t);
                break;
            }
            put(t, "[");
            for (int f = 0; f < 6; f++) {
                if (f)
                    put(t, ",");
                gen_facet(t, f, errors, canonical);
            }
            put(t, "]");
            break;
        case 3:
            put(t, "\"name\":\"cube \\u00e9\"");
            break;
        case 4:
            put(t, "\"units\":%s", errors && rnd(20) == 0 ? "\"in\"" : "\"mm\"");
            break;
        default:
            put(t, "\"extra\":{\"a\":[1,{\"b\":null}],\"format\":3}");
            break;
        }
    }
    put(t, "}");
}

static void test_generated_models_read_the_same(void **state)
{
    (void)state;
    text t = {0};
    for (int i = 0; i < 20000; i++) {
        gen_model(&t, i % 4 != 0, i % 3 == 0);
        same_as_tree(t.s, t.n, NULL);
    }
    /* valid ones are common enough to compare the models themselves */
    assert_true(accepted > 2000);
    free(t.s);
}

static void test_limits_are_checked_in_the_same_order(void **state)
{
    (void)state;
    text t = {0};
    for (int i = 0; i < 6000; i++) {
        gen_model(&t, i % 2 == 0, i % 3 == 0);
        proto_limits lim;
        proto_limits_default(&lim);
        switch (rnd(4)) {
        case 0:
            lim.max_vertices = rnd(10);
            break;
        case 1:
            lim.max_facets = rnd(7);
            break;
        case 2:
            lim.max_corners = rnd(26);
            break;
        default:
            lim.max_bytes = t.n - rnd(2);
            break;
        }
        same_as_tree(t.s, t.n, &lim);
    }
    free(t.s);
}

static void test_mutated_texts_read_the_same(void **state)
{
    (void)state;
    static const char interesting[] = "{}[]:,\"\\e.-0123456789 \n\xff";
    text t = {0};
    for (int i = 0; i < 20000; i++) {
        gen_model(&t, false, i % 2 == 0);
        int muts = 1 + (int)rnd(3);
        for (int m = 0; m < muts && t.n > 1; m++) {
            size_t at = rnd((unsigned)t.n);
            switch (rnd(3)) {
            case 0:
                t.s[at] = interesting[rnd(sizeof interesting - 1)];
                break;
            case 1:
                memmove(t.s + at, t.s + at + 1, t.n - at - 1);
                t.n--;
                break;
            default:
                t.n = at + 1;
                break;
            }
        }
        same_as_tree(t.s, t.n, NULL);
    }
    free(t.s);
}

static void test_sample_files_and_their_mutations(void **state)
{
    (void)state;
    const char *path = tu_model_path("brilliant.scan-k100.json");
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    static char buf[1 << 20];
    size_t n = fread(buf, 1, sizeof buf, f);
    fclose(f);
    same_as_tree(buf, n, NULL);
    static char mut[1 << 20];
    for (int i = 0; i < 600; i++) {
        memcpy(mut, buf, n);
        size_t at = rnd((unsigned)n);
        mut[at] = "]}x,:\"0-9"[rnd(9)];
        same_as_tree(mut, i % 10 == 0 ? at + 1 : n, NULL);
    }
}

/* A model inside a larger document, read in place with a path prefix. */
static void test_embedded_model_names_its_place(void **state)
{
    (void)state;
    text t = {0}, doc = {0};
    for (int i = 0; i < 3000; i++) {
        gen_model(&t, true, i % 2 == 0);
        doc.n = 0;
        put(&doc, "{\"pipeline\":[\"inspect\"],\"model\":%.*s,\"label\":\"x\"}",
            (int)t.n, t.s);
        json_error_t je;
        json_t *root = json_loadb(doc.s, doc.n, JSON_REJECT_DUPLICATES, &je);
        geo_err e1 = {{0}}, e2 = {{0}};
        geo_poly *want = root ? proto_model_from_json(json_object_get(root,
                                                                      "model"),
                                                      NULL, "model", &e1)
                              : NULL;
        proto_jpull j;
        proto_jpull_init(&j, doc.s, doc.n);
        assert_int_equal(proto_jpull_next(&j), PROTO_JT_OBJECT);
        proto_jtok k;
        geo_poly *got = NULL;
        bool syntax = false;
        while ((k = proto_jpull_next(&j)) == PROTO_JT_KEY) {
            if (strcmp(j.str, "model") == 0)
                got = proto_model_from_jpull(&j, proto_jpull_next(&j), NULL,
                                             "model", NULL, &syntax, &e2);
            else
                assert_int_not_equal(proto_jpull_skip(&j), PROTO_JT_ERROR);
            if (syntax)
                break;
        }
        if (!root) {
            assert_true(syntax);
            assert_null(got);
        } else {
            assert_false(syntax);
            assert_int_equal(k, PROTO_JT_OBJECT_END);
            if (!want != !got || (!want && strcmp(e1.msg, e2.msg) != 0))
                fail_msg("tree: %s\nstream: %s", want ? "ok" : e1.msg,
                         got ? "ok" : e2.msg);
        }
        json_decref(root);
        geo_poly_free(want);
        geo_poly_free(got);
        proto_jpull_clear(&j);
    }
    free(t.s);
    free(doc.s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_generated_models_read_the_same),
        cmocka_unit_test(test_limits_are_checked_in_the_same_order),
        cmocka_unit_test(test_mutated_texts_read_the_same),
        cmocka_unit_test(test_sample_files_and_their_mutations),
        cmocka_unit_test(test_embedded_model_names_its_place),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
