/* test_stats_golden.c — the statistics JSON of geo_inspect is byte for
 * byte the recorded one (tests/data/stats/) for every sample model and
 * for derived models that reach the other paths: vertices pushed through
 * the surface (self-intersections of every kind), flipped facets, holes,
 * a cavity shell, a doubled facet (non-manifold, coplanar overlap),
 * random convex polyhedra and random garbage. Doubles are printed with
 * 17 significant digits, so any change in a sum's order shows. On 1 and
 * on 2 threads.
 *
 * The references were written by the inspection code before its speed-up,
 * except garbage.stats.jsonl: its facets are mostly not planar, where the
 * pair test is not symmetric, and the search now tests each pair with the
 * lower facet first instead of in the BVH's visit order (so the answer no
 * longer depends on the tree); every other reference is unchanged.
 * FACET_STATS_WRITE=1 rewrites them (only after a deliberate change of a
 * statistic's definition). FACET_STATS overrides the directory. */
#include "testutil.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gen_convex.h"
#include "gen_garbage.h"
#include "gen_sphere.h"
#include "model_io.h"
#include "parallel.h"
#include "stats.h"
#include "stats_json.h"
#include "vec.h"

static const char *stats_dir(void)
{
    const char *env = getenv("FACET_STATS");
    return env && *env ? env : "tests/data/stats";
}

static bool writing(void)
{
    const char *env = getenv("FACET_STATS_WRITE");
    return env && strcmp(env, "1") == 0;
}

static geo_poly *load(const char *name)
{
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(tu_model_path(name), PROTO_FMT_UNKNOWN,
                                        NULL, &err);
    if (!p)
        fail_msg("%s: %s", name, err.msg);
    return p;
}

/* The statistics JSON of p, as `facet inspect` prints it (flags 0: one
 * line), computed with `threads` threads (0: no parallel loop). */
static char *stats_text(const geo_poly *p, int threads, size_t flags)
{
    par_pool *pool = threads ? par_pool_new(threads) : NULL;
    geo_ctx ctx = {0};
    if (pool) {
        ctx.parallel_for = par_for;
        ctx.pf_user = pool;
    }
    geo_stats s;
    geo_err err = {{0}};
    if (geo_inspect(p, NULL, pool ? &ctx : NULL, &s, &err) != 0)
        fail_msg("inspect: %s", err.msg);
    par_pool_free(pool);
    json_t *j = proto_stats_to_json(&s);
    geo_stats_clear(&s);
    assert_non_null(j);
    char *text = json_dumps(j, flags | JSON_PRESERVE_ORDER);
    json_decref(j);
    assert_non_null(text);
    return text;
}

static char *read_all(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    size_t cap = 4096, n = 0;
    char *buf = malloc(cap);
    size_t k;
    while (buf && (k = fread(buf + n, 1, cap - n - 1, f)) > 0) {
        n += k;
        if (n + 1 == cap) {
            char *nb = realloc(buf, cap *= 2);
            if (!nb)
                free(buf);
            buf = nb;
        }
    }
    fclose(f);
    if (buf)
        buf[n] = '\0';
    return buf;
}

/* Compares text (plus a final newline) with the reference `name`, or
 * writes it there in write mode. */
static void check_text(const char *name, const char *text)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", stats_dir(), name);
    if (writing()) {
        FILE *f = fopen(path, "wb");
        if (!f || fputs(text, f) == EOF || fputc('\n', f) == EOF ||
            fclose(f) != 0)
            fail_msg("%s: cannot write", path);
        return;
    }
    char *want = read_all(path);
    if (!want)
        fail_msg("%s: no reference (FACET_STATS_WRITE=1 records one)", path);
    size_t n = strlen(want);
    if (n && want[n - 1] == '\n')
        want[--n] = '\0';
    if (strcmp(want, text) != 0) {
        size_t i = 0;
        while (want[i] && want[i] == text[i])
            i++;
        size_t from = i > 60 ? i - 60 : 0;
        print_error("%s differs at byte %zu:\nwant ...%.120s\ngot  ...%.120s\n",
                    path, i, want + from, text + from);
        free(want);
        fail();
    }
    free(want);
}

/* Whether every facet of p is a triangle. */
static bool all_triangles(const geo_poly *p)
{
    for (uint32_t f = 0; f < p->nfacets; f++)
        if (geo_poly_facet_size(p, f) != 3)
            return false;
    return true;
}

/* For a model of triangles whose planes are its own fitted ones, the
 * statistics of its copy with implicit planes (planes NULL, as `facet
 * inspect` reads a mesh without planes) are the same text. Counts the
 * models so compared in implicit_checked. */
static unsigned implicit_checked;

static void check_implicit(const geo_poly *p, const char *text, size_t flags)
{
    if (!all_triangles(p))
        return;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        double pl[4];
        geo_poly_facet_fit_plane(p, f, GEO_PLANE_UNWEIGHTED, pl);
        for (int k = 0; k < 4; k++)
            if (pl[k] != p->planes[f][k])
                return; /* planes of its own: not what a reader leaves out */
    }
    implicit_checked++;
    geo_poly *q = geo_poly_copy(p);
    assert_non_null(q);
    free(q->planes);
    q->planes = NULL;
    char *t = stats_text(q, 0, flags);
    assert_string_equal(t, text);
    free(t);
    geo_poly_free(q);
}

/* p's statistics on 1 thread (no pool) and on 2 threads, each equal to
 * the reference `name`, and with implicit planes where p allows; frees p. */
static void check_model(const char *name, geo_poly *p)
{
    assert_non_null(p);
    char *one = stats_text(p, 0, JSON_INDENT(2));
    check_text(name, one);
    char *two = stats_text(p, 2, JSON_INDENT(2));
    assert_string_equal(one, two);
    check_implicit(p, one, JSON_INDENT(2));
    free(one);
    free(two);
    geo_poly_free(p);
}

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static void test_every_sample_model_matches_its_reference(void **state)
{
    (void)state;
    DIR *d = opendir(tu_models_dir());
    assert_non_null(d);
    char *names[256];
    size_t n = 0;
    struct dirent *e;
    while ((e = readdir(d)) && n < 256) {
        size_t len = strlen(e->d_name);
        if (len > 5 && strcmp(e->d_name + len - 5, ".json") == 0)
            names[n++] = strdup(e->d_name);
    }
    closedir(d);
    assert_true(n >= 9);
    qsort(names, n, sizeof *names, cmp_str);
    for (size_t i = 0; i < n; i++) {
        char ref[512];
        snprintf(ref, sizeof ref, "%.*s.stats.json",
                 (int)(strlen(names[i]) - 5), names[i]);
        check_model(ref, load(names[i]));
        free(names[i]);
    }
}

/* Pushes `count` vertices (every nverts/count-th) by random vectors of
 * length up to frac × the model's size; planes kept (non-planarity) or
 * refitted. */
static geo_poly *pushed(geo_poly *p, uint64_t seed, uint32_t count,
                        double frac, bool refit)
{
    double size = geo_poly_size(p);
    uint64_t rng = seed;
    for (uint32_t k = 0; k < count; k++) {
        uint32_t v = (uint32_t)((uint64_t)k * p->nverts / count);
        for (int i = 0; i < 3; i++)
            p->verts[v][i] += (2 * geo_rand_unit(&rng) - 1) * frac * size;
    }
    if (refit)
        geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    return p;
}

static void test_pushed_vertices_match_their_references(void **state)
{
    (void)state;
    check_model("k400.nudged.stats.json",
                pushed(load("brilliant.scan-k400.json"), 1, 40, 1e-5, false));
    check_model("k400.pushed.stats.json",
                pushed(load("brilliant.scan-k400.json"), 2, 25, 0.03, true));
    check_model("k100.pushed.stats.json",
                pushed(load("brilliant.scan-k100.json"), 3, 60, 0.08, true));
    geo_poly *s = gs_sphere(12, 1.0);
    assert_non_null(s);
    /* through the centre and beyond: crossing pairs far and near */
    for (uint32_t k = 0; k < 6; k++) {
        uint32_t v = k * s->nverts / 6 + 3;
        geo_vscale(s->verts[v], -0.2 - 0.3 * k, s->verts[v]);
    }
    geo_poly_compute_planes(s, GEO_PLANE_UNWEIGHTED);
    unsigned before = implicit_checked;
    check_model("sphere12.pushed.stats.json", s);
    assert_int_equal(implicit_checked, before + 1);
}

static void test_orientation_and_topology_defects_match(void **state)
{
    (void)state;
    geo_poly *p = load("brilliant.scan-k800.json");
    for (uint32_t f = 0; f < p->nfacets; f += 7)
        geo_poly_flip_facet(p, f);
    check_model("k800.flipped.stats.json", p);

    p = load("brilliant.scan-k100.json");
    bool *keep = malloc(p->nfacets * sizeof *keep);
    assert_non_null(keep);
    for (uint32_t f = 0; f < p->nfacets; f++)
        keep[f] = f % 97 != 5;
    assert_int_equal(geo_poly_compact(p, keep, NULL, NULL), 0);
    free(keep);
    check_model("k100.holes.stats.json", p);

    /* the truth, and inside it a half-size copy turned inside out (a
     * cavity: rightly negative), and a third copy far away */
    geo_poly *t = load("brilliant.truth.json");
    p = geo_poly_copy(t);
    assert_non_null(p);
    double lo[3], hi[3], c[3];
    geo_poly_bbox(t, lo, hi);
    geo_vadd(lo, hi, c);
    geo_vscale(c, 0.5, c);
    for (int copy = 1; copy <= 2; copy++) {
        uint32_t base = p->nverts;
        for (uint32_t v = 0; v < t->nverts; v++) {
            double x[3];
            geo_vsub(t->verts[v], c, x);
            geo_vscale(x, copy == 1 ? 0.5 : 1.0, x);
            geo_vadd(x, c, x);
            if (copy == 2)
                x[0] += 3 * geo_poly_size(t);
            assert_true(geo_poly_add_vertex(p, x) >= 0);
        }
        for (uint32_t f = 0; f < t->nfacets; f++) {
            uint32_t idx[64], n = geo_poly_facet_size(t, f);
            assert_true(n <= 64);
            for (uint32_t i = 0; i < n; i++)
                idx[i] = base + geo_poly_facet(t, f)[i];
            int64_t g = geo_poly_add_facet(p, idx, n);
            assert_true(g >= 0);
            if (copy == 1)
                geo_poly_flip_facet(p, (uint32_t)g);
        }
    }
    geo_poly_free(t);
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    check_model("truth.shells.stats.json", p);

    /* a facet listed twice: non-manifold edges, coplanar overlap */
    p = load("brilliant.scan-k100.json");
    uint32_t idx[64], n = geo_poly_facet_size(p, 10);
    assert_true(n <= 64);
    memcpy(idx, geo_poly_facet(p, 10), n * sizeof *idx);
    assert_true(geo_poly_add_facet(p, idx, n) >= 0);
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    check_model("k100.doubled.stats.json", p);
}

static void test_convex_and_garbage_models_match(void **state)
{
    (void)state;
    const double c[3] = {1, 2, 3};
    for (uint64_t seed = 1; seed <= 3; seed++) {
        char name[64];
        snprintf(name, sizeof name, "convex%u.stats.json", (unsigned)seed);
        check_model(name, gen_convex_polyhedron(seed, 60, c, 5.0));
    }
    /* random facets over few vertices on a 3×3×3 grid: every defect at
     * once; one compact line per model */
    size_t cap = 1 << 16, len = 0;
    char *all = malloc(cap);
    assert_non_null(all);
    all[0] = '\0';
    uint64_t rng = 91;
    for (int trial = 0; trial < 80; trial++) {
        geo_poly *p = gen_garbage_model(&rng);
        assert_non_null(p);
        char *one = stats_text(p, 0, JSON_COMPACT);
        char *two = stats_text(p, 2, JSON_COMPACT);
        assert_string_equal(one, two);
        check_implicit(p, one, JSON_COMPACT);
        size_t k = strlen(one);
        while (len + k + 2 > cap) {
            char *na = realloc(all, cap *= 2);
            assert_non_null(na);
            all = na;
        }
        memcpy(all + len, one, k);
        len += k;
        all[len++] = '\n';
        all[len] = '\0';
        free(one);
        free(two);
        geo_poly_free(p);
    }
    assert_true(implicit_checked > 0);
    all[--len] = '\0'; /* check_text adds the last newline */
    check_text("garbage.stats.jsonl", all);
    free(all);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_sample_model_matches_its_reference),
        cmocka_unit_test(test_pushed_vertices_match_their_references),
        cmocka_unit_test(test_orientation_and_topology_defects_match),
        cmocka_unit_test(test_convex_and_garbage_models_match),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
