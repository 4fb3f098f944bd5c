/* test_model_formats.c — the model formats besides facet-model/1 (.poly,
 * OBJ, STL, PLY, FMB1, ASE): round trips (exact where the format allows),
 * the readers' grammar and their error messages, counts that lie or
 * exceed the limits, and mutated inputs that must give an error or a
 * valid model, never a crash. */
#include "testutil.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "model_cmp.h"
#include "model_codec.h"
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

static char *write_fmt(const geo_poly *p, proto_format fmt, size_t *ret_len)
{
    char *buf = NULL;
    geo_err err = {{0}};
    if (proto_model_write_mem(p, fmt, &buf, ret_len, &err) < 0)
        fail_msg("writing %s: %s", proto_format_name(fmt), err.msg);
    return buf;
}

static geo_poly *read_ok(const void *data, size_t len, proto_format fmt,
                         proto_read_report *rep)
{
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_mem_ex(data, len, fmt, NULL, rep, &err);
    if (!p)
        fail_msg("reading %s: %s", proto_format_name(fmt), err.msg);
    return p;
}

/* Reads expecting failure; returns the message (static). */
static const char *read_err(const void *data, size_t len, proto_format fmt,
                            const proto_limits *lim)
{
    static geo_err err;
    memset(&err, 0, sizeof err);
    geo_poly *p = proto_model_read_mem(data, len, fmt, lim, &err);
    if (p) {
        geo_poly_free(p);
        fail_msg("%s input accepted", proto_format_name(fmt));
    }
    assert_true(err.msg[0] != '\0');
    return err.msg;
}

static geo_poly *text_ok(const char *text, proto_format fmt)
{
    return read_ok(text, strlen(text), fmt, NULL);
}

static const char *text_err(const char *text, proto_format fmt)
{
    return read_err(text, strlen(text), fmt, NULL);
}

static const char *const MODELS[] = {"brilliant.scan-k400.json",
                                     "brilliant.truth.json", "notch-cube.json",
                                     "l-prism.json", "brilliant.selfint.json"};
enum { NMODELS = sizeof MODELS / sizeof MODELS[0] };

static void test_exact_round_trip_through_poly_ply_fmb1(void **state)
{
    (void)state;
    const proto_format fmts[] = {PROTO_FMT_JSON, PROTO_FMT_POLY, PROTO_FMT_PLY,
                                 PROTO_FMT_PLY_ASCII, PROTO_FMT_FMB1};
    for (size_t m = 0; m < NMODELS; m++) {
        geo_poly *a = load(MODELS[m]);
        for (size_t i = 0; i < sizeof fmts / sizeof fmts[0]; i++) {
            size_t len;
            char *buf = write_fmt(a, fmts[i], &len);
            geo_poly *b = read_ok(buf, len, fmts[i], NULL);
            char why[256];
            if (!tu_poly_same(a, b, 0, 0, why, sizeof why))
                fail_msg("%s via %s: %s", MODELS[m],
                         proto_format_name(fmts[i]), why);
            free(buf);
            geo_poly_free(b);
        }
        geo_poly_free(a);
    }
}

static void test_obj_round_trip_keeps_positions_and_polygons(void **state)
{
    (void)state;
    for (size_t m = 0; m < NMODELS; m++) {
        geo_poly *a = load(MODELS[m]);
        size_t len;
        char *buf = write_fmt(a, PROTO_FMT_OBJ, &len);
        proto_read_report rep;
        geo_poly *b = read_ok(buf, len, PROTO_FMT_OBJ, &rep);
        char why[256];
        if (!tu_poly_same(a, b, 0, -1, why, sizeof why))
            fail_msg("%s: %s", MODELS[m], why);
        /* OBJ carries no planes: they are refitted, outward */
        assert_int_equal(rep.planes_given, 0);
        /* the sample's planes are the scanner's cutting planes, exact to
         * 1e-15 mm at the vertices; a refit of a sliver facet turns its
         * normal by up to ~1e-11 */
        if (m != NMODELS - 1 &&
            !tu_poly_same(a, b, 0, 1e-9, why, sizeof why))
            fail_msg("%s: %s", MODELS[m], why);
        free(buf);
        geo_poly_free(a);
        geo_poly_free(b);
    }
}

static int cmp_point(const void *x, const void *y)
{
    const double *a = x, *b = y;
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k])
            return a[k] < b[k] ? -1 : 1;
    return 0;
}

/* The distinct points of p (rounded to float when to_float), sorted;
 * returns their number. *ret is malloc'd. */
static uint32_t sorted_points(const geo_poly *p, bool to_float,
                              double (**ret)[3])
{
    double (*v)[3] = malloc((p->nverts + 1) * sizeof *v);
    assert_non_null(v);
    for (uint32_t i = 0; i < p->nverts; i++)
        for (int k = 0; k < 3; k++)
            v[i][k] = (to_float ? (double)(float)p->verts[i][k]
                                : p->verts[i][k]) + 0.0;
    qsort(v, p->nverts, sizeof *v, cmp_point);
    uint32_t n = 0;
    for (uint32_t i = 0; i < p->nverts; i++)
        if (n == 0 || cmp_point(v[n - 1], v[i]) != 0)
            memcpy(v[n++], v[i], sizeof v[i]);
    *ret = v;
    return n;
}

static void check_triangulated(const geo_poly *a, const geo_poly *b,
                               bool to_float, double rel)
{
    assert_int_equal(b->nfacets,
                     geo_poly_ncorners(a) - 2 * a->nfacets);
    for (uint32_t f = 0; f < b->nfacets; f++)
        assert_int_equal(geo_poly_facet_size(b, f), 3);
    double (*va)[3], (*vb)[3];
    uint32_t na = sorted_points(a, to_float, &va);
    uint32_t nb = sorted_points(b, false, &vb);
    assert_int_equal(na, nb);
    assert_int_equal(nb, b->nverts);
    assert_memory_equal(va, vb, na * sizeof *va);
    free(va);
    free(vb);
    double v0 = geo_poly_volume(a), v1 = geo_poly_volume(b);
    assert_true(fabs(v0 - v1) <= rel * fabs(v0));
    assert_true(fabs(geo_poly_area(a) - geo_poly_area(b)) <=
                rel * geo_poly_area(a));
}

static void test_stl_ascii_round_trip_keeps_positions_exactly(void **state)
{
    (void)state;
    for (size_t m = 0; m < NMODELS - 1; m++) {
        geo_poly *a = load(MODELS[m]);
        size_t len;
        char *buf = write_fmt(a, PROTO_FMT_STL_ASCII, &len);
        assert_memory_equal(buf, "solid ", 6);
        geo_poly *b = read_ok(buf, len, PROTO_FMT_STL, NULL);
        check_triangulated(a, b, false, 1e-12);
        free(buf);
        geo_poly_free(a);
        geo_poly_free(b);
    }
}

static void test_stl_binary_round_trip_is_exact_in_float(void **state)
{
    (void)state;
    /* float-representable coordinates come back exactly */
    const double lo[3] = {-1.5, 0.25, 2}, hi[3] = {3, 4.125, 8};
    geo_poly *box = tu_box(lo, hi);
    size_t len;
    char *buf = write_fmt(box, PROTO_FMT_STL, &len);
    assert_int_equal(len, 84 + 50 * 12);
    assert_true(memcmp(buf, "solid", 5) != 0);
    geo_poly *b = read_ok(buf, len, PROTO_FMT_STL, NULL);
    assert_int_equal(b->nverts, 8);
    check_triangulated(box, b, false, 0);
    assert_true(geo_poly_volume(b) == 4.5 * 3.875 * 6);
    free(buf);
    geo_poly_free(b);
    geo_poly_free(box);
    /* others are rounded to the nearest float */
    for (size_t m = 0; m < NMODELS - 1; m++) {
        geo_poly *a = load(MODELS[m]);
        buf = write_fmt(a, PROTO_FMT_STL, &len);
        b = read_ok(buf, len, PROTO_FMT_STL, NULL);
        check_triangulated(a, b, true, 1e-5);
        free(buf);
        geo_poly_free(a);
        geo_poly_free(b);
    }
}

static char tmpdir[256];

static int make_tmpdir(void **state)
{
    (void)state;
    const char *base = getenv("TMPDIR");
    snprintf(tmpdir, sizeof tmpdir, "%s/facet-formats-XXXXXX",
             base && *base ? base : "/tmp");
    return mkdtemp(tmpdir) ? 0 : -1;
}

static int remove_tmpdir(void **state)
{
    (void)state;
    DIR *d = opendir(tmpdir);
    if (d) {
        struct dirent *e;
        char path[600];
        while ((e = readdir(d)))
            if (e->d_name[0] != '.') {
                snprintf(path, sizeof path, "%s/%s", tmpdir, e->d_name);
                unlink(path);
            }
        closedir(d);
    }
    return rmdir(tmpdir);
}

static char *slurp(const char *path, size_t *ret_len)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = malloc((size_t)n + 1);
    assert_non_null(buf);
    assert_int_equal(fread(buf, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *ret_len = (size_t)n;
    return buf;
}

/* The acceptance check: JSON → .ply file → JSON file gives back the same
 * model, bit for bit, and the same bytes as the original file. */
static void test_json_to_ply_to_json_gives_back_the_same_model(void **state)
{
    (void)state;
    const char *src = tu_model_path("brilliant.scan-k400.json");
    char ply[600], json[600];
    snprintf(ply, sizeof ply, "%s/x.ply", tmpdir);
    snprintf(json, sizeof json, "%s/y.json", tmpdir);
    geo_err err = {{0}};
    geo_poly *a = proto_model_read_file(src, PROTO_FMT_UNKNOWN, NULL, &err);
    assert_non_null(a);
    assert_int_equal(a->nfacets, 1808);
    assert_int_equal(a->nverts, 3612);
    assert_int_equal(proto_model_write_file(a, ply, PROTO_FMT_UNKNOWN, &err),
                     0);
    geo_poly *b = proto_model_read_file(ply, PROTO_FMT_UNKNOWN, NULL, &err);
    assert_non_null(b);
    assert_int_equal(proto_model_write_file(b, json, PROTO_FMT_UNKNOWN, &err),
                     0);
    geo_poly *c = proto_model_read_file(json, PROTO_FMT_UNKNOWN, NULL, &err);
    assert_non_null(c);
    char why[256];
    if (!tu_poly_same(a, c, 0, 0, why, sizeof why))
        fail_msg("%s", why);
    size_t n0, n1;
    char *b0 = slurp(src, &n0), *b1 = slurp(json, &n1);
    assert_int_equal(n0, n1);
    assert_memory_equal(b0, b1, n0);
    free(b0);
    free(b1);
    geo_poly_free(a);
    geo_poly_free(b);
    geo_poly_free(c);
}

/* ---- .poly ---- */

static const char TETRA_POLY[] =
    "# a tetrahedron\n"
    "4 4   # counts\n"
    "0 0 0   1 0 0\n"
    "0 1 0\n\t0 0 1\n"
    "3  0 0 -1 0   0 2 1\n"
    "3 0 -1 0 0\n 0 1 3 3 -1 0 0 0 0 3 2\n"
    "3 0.57735026918962573 0.57735026918962573 0.57735026918962573 "
    "-0.57735026918962573 1 2 3 # last\n";

static void test_poly_reads_free_layout_with_comments(void **state)
{
    (void)state;
    proto_read_report rep;
    geo_poly *p = read_ok(TETRA_POLY, strlen(TETRA_POLY), PROTO_FMT_POLY,
                          &rep);
    assert_int_equal(p->nverts, 4);
    assert_int_equal(p->nfacets, 4);
    assert_int_equal(rep.planes_given, 4);
    assert_int_equal(rep.plane_mismatches, 0);
    assert_int_equal(p->fidx[9], 1);
    assert_true(fabs(geo_poly_volume(p) - 1.0 / 6) < 1e-15);
    geo_poly_free(p);
}

static void test_poly_errors_name_line_and_place(void **state)
{
    (void)state;
    assert_string_equal(text_err("1 0\n0 0 # padding for the size check",
                                 PROTO_FMT_POLY),
                        "line 2: vertices[0][2]: unexpected end of file");
    assert_string_equal(text_err("1 0\n0 0 x\n", PROTO_FMT_POLY),
                        "line 2: vertices[0][2]: expected a number, found "
                        "\"x\"");
    assert_string_equal(text_err("1 0\nnan 0 0\n", PROTO_FMT_POLY),
                        "line 2: vertices[0][0]: expected a number, found "
                        "\"nan\"");
    assert_string_equal(text_err("1 0\n1e999 0 0\n", PROTO_FMT_POLY),
                        "line 2: vertices[0][0]: number out of range, found "
                        "\"1e999\"");
    assert_string_equal(text_err("-1 1\n", PROTO_FMT_POLY),
                        "line 1: number of vertices: expected a non-negative "
                        "integer, found \"-1\"");
    assert_string_equal(text_err("3 1\n0 0 0 1 0 0 0 1 0\n"
                                 "3 0 0 1 0\n0 1 9\n", PROTO_FMT_POLY),
                        "line 4: facets[0].vertices[2]: index 9 out of range "
                        "(3 vertices)");
    assert_string_equal(text_err("3 1\n0 0 0 1 0 0 0 1 0\n"
                                 "2 0 0 1 0 0 1\n", PROTO_FMT_POLY),
                        "line 3: facets[0]: 2 vertices, a facet needs at "
                        "least 3");
    assert_string_equal(text_err("3 1\n0 0 0 1 0 0 0 1 0\n"
                                 "3 0 0 1 0 0 1 1\n", PROTO_FMT_POLY),
                        "line 3: facets[0].vertices[2]: index 1 repeated "
                        "consecutively");
    assert_string_equal(text_err("3 1\n0 0 0 1 0 0 0 1 0\n"
                                 "3 0 0 1 0 0 1 2\njunk\n", PROTO_FMT_POLY),
                        "line 4: unexpected \"junk\" after the last facet "
                        "(the header declares 1 facets)");
    /* counts that lie: caught at the end of the data, or at once when
     * the data cannot hold them */
    assert_string_equal(text_err("3 2\n0 0 0 1 0 0 0 1 0\n"
                                 "3 0 0 1 0 0 1 2\n", PROTO_FMT_POLY),
                        "line 4: facets[1]: vertex count: unexpected end of "
                        "file");
    assert_string_equal(text_err("3 5\n0 0 0 1 0 0 0 1 0\n"
                                 "3 0 0 1 0 0 1 2\n", PROTO_FMT_POLY),
                        "line 1: 3 vertices and 5 facets cannot fit in the "
                        "remaining 35 bytes (file truncated?)");
}

/* ---- OBJ ---- */

static void test_obj_reads_polygons_and_index_forms(void **state)
{
    (void)state;
    geo_poly *p = text_ok("# comment\n"
                          "o thing\n"
                          "v 0 0 0\n"
                          "v 1 0 0 1.0\n"
                          "vt 0 0\n"
                          "vn 0 0 1\n"
                          "v 1 1 0\n"
                          "v 0 1 0   # fourth\n"
                          "f 1/1/1 2/1/1 3/1/1 4/1/1\n"
                          "s off\n"
                          "f -4 -1 -2\n"
                          "f 1//1 3//1 5\n"
                          "v 0 0 1\n",
                          PROTO_FMT_OBJ);
    assert_int_equal(p->nverts, 5);
    assert_int_equal(p->nfacets, 3);
    assert_int_equal(geo_poly_facet_size(p, 0), 4);
    const uint32_t want[] = {0, 1, 2, 3, 0, 3, 2, 0, 2, 4};
    assert_memory_equal(p->fidx, want, sizeof want);
    assert_true(p->planes[0][2] == 1);
    geo_poly_free(p);
}

static void test_obj_errors_name_line_and_place(void **state)
{
    (void)state;
    const char *v4 = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
    char text[256];
    snprintf(text, sizeof text, "%sf 1 2 0\n", v4);
    assert_string_equal(text_err(text, PROTO_FMT_OBJ),
                        "line 5: facets[0].vertices[2]: index 0 out of range "
                        "(4 vertices, 1-based)");
    snprintf(text, sizeof text, "%sf 1 2 3\nf 1 2 9\n", v4);
    assert_string_equal(text_err(text, PROTO_FMT_OBJ),
                        "line 6: facets[1].vertices[2]: index 9 out of range "
                        "(4 vertices, 1-based)");
    snprintf(text, sizeof text, "%sf -5 1 2\n", v4);
    assert_string_equal(text_err(text, PROTO_FMT_OBJ),
                        "line 5: facets[0].vertices[0]: index -5 out of range "
                        "(4 vertices so far)");
    snprintf(text, sizeof text, "%sf 1 2\n", v4);
    assert_string_equal(text_err(text, PROTO_FMT_OBJ),
                        "line 5: facets[0]: 2 vertices, a facet needs at "
                        "least 3");
    snprintf(text, sizeof text, "%sf 1 2 2 3\n", v4);
    assert_string_equal(text_err(text, PROTO_FMT_OBJ),
                        "line 5: facets[0].vertices[2]: index 2 repeated "
                        "consecutively");
    snprintf(text, sizeof text, "%sf 1 x 3\n", v4);
    assert_string_equal(text_err(text, PROTO_FMT_OBJ),
                        "line 5: facets[0].vertices[1]: expected a vertex "
                        "index, found \"x\"");
    snprintf(text, sizeof text, "%sf 1 99999999999999999999 3\n", v4);
    assert_string_equal(text_err(text, PROTO_FMT_OBJ),
                        "line 5: facets[0].vertices[1]: expected a vertex "
                        "index, found \"99999999999999999999\"");
    assert_string_equal(text_err("v 0 0 0\nv 1e300 0 0\nv 0 1e300 0\n"
                                 "f 1 2 3\n", PROTO_FMT_OBJ),
                        "vertices[1][0]: 1e+300 mm is beyond the ±1e+09 "
                        "mm a model may span");
    assert_string_equal(text_err("v 0 0 0\nv 1e-9 0 0\nv 0 1e-9 0\n"
                                 "f 1 2 3\n", PROTO_FMT_OBJ),
                        "the model is 1e-09 mm across, below the 1e-06 mm "
                        "the exact predicates can resolve (wrong units?)");
    assert_string_equal(text_err("v 1 2\n", PROTO_FMT_OBJ),
                        "line 1: vertices[0]: expected 3 numbers");
    assert_string_equal(text_err("\n\nv 1 2 inf\n", PROTO_FMT_OBJ),
                        "line 3: vertices[0][2]: expected a number, found "
                        "\"inf\"");
}

/* ---- STL ---- */

static const float TETRA_F[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0},
                                    {0, 0, 1}};
static const int TETRA_T[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

static void put_u32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static void put_f32(unsigned char *p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put_u32(p, u);
}

/* A binary STL tetrahedron whose header starts with "solid". */
static size_t binary_tetra(unsigned char *buf)
{
    memset(buf, 0, 84 + 4 * 50);
    memcpy(buf, "solid exported by a CAD program", 31);
    put_u32(buf + 80, 4);
    for (int t = 0; t < 4; t++)
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 3; k++)
                put_f32(buf + 84 + 50 * t + 12 + 12 * c + 4 * k,
                        TETRA_F[TETRA_T[t][c]][k]);
    return 84 + 4 * 50;
}

static void test_stl_binary_starting_with_solid_is_binary(void **state)
{
    (void)state;
    unsigned char buf[84 + 4 * 50];
    size_t len = binary_tetra(buf);
    geo_poly *p = read_ok(buf, len, PROTO_FMT_STL, NULL);
    assert_int_equal(p->nverts, 4);
    assert_int_equal(p->nfacets, 4);
    assert_true(fabs(geo_poly_volume(p) - 1.0 / 6) < 1e-15);
    geo_poly_free(p);
    assert_string_equal(read_err(buf, len - 1, PROTO_FMT_STL, NULL),
                        "byte 80: 4 triangles need 284 bytes, the file has "
                        "283 (truncated, or not an STL file)");
    put_f32(buf + 84 + 12, NAN);
    assert_string_equal(read_err(buf, len, PROTO_FMT_STL, NULL),
                        "byte 96: triangle 0, corner 0: not a finite number");
    binary_tetra(buf);
    put_f32(buf + 84 + 24, 0);
    put_f32(buf + 84 + 28, 0);
    assert_string_equal(read_err(buf, len, PROTO_FMT_STL, NULL),
                        "byte 84: triangle 0: corners 0 and 1 are the same "
                        "point (degenerate triangle)");
}

static void test_stl_huge_triangle_count_fails_fast(void **state)
{
    (void)state;
    unsigned char buf[84] = {0};
    put_u32(buf + 80, 1u << 31);
    assert_string_equal(read_err(buf, 84, PROTO_FMT_STL, NULL),
                        "byte 80: 2147483648 triangles need 107374182484 "
                        "bytes, the file has 84 (truncated, or not an STL "
                        "file)");
    assert_string_equal(read_err("abc", 3, PROTO_FMT_STL, NULL),
                        "3 bytes: neither an ASCII STL (\"solid ...\") nor a "
                        "binary one (84 bytes at least)");
}

static void test_stl_ascii_merges_equal_points(void **state)
{
    (void)state;
    char text[4096];
    size_t n = (size_t)snprintf(text, sizeof text, "solid tetra\n");
    for (int t = 0; t < 4; t++) {
        n += (size_t)snprintf(text + n, sizeof text - n,
                              " facet normal 0 0 0\n  outer loop\n");
        for (int c = 0; c < 3; c++) {
            const float *v = TETRA_F[TETRA_T[t][c]];
            /* −0 and 0 are one point */
            char x[16];
            snprintf(x, sizeof x, "%s%g", v[0] == 0 && t % 2 ? "-" : "",
                     v[0]);
            n += (size_t)snprintf(text + n, sizeof text - n,
                                  "   vertex %s %g %g\n", x, v[1], v[2]);
        }
        n += (size_t)snprintf(text + n, sizeof text - n,
                              "  endloop\n endfacet\n");
    }
    /* a second, empty solid follows */
    snprintf(text + n, sizeof text - n, "endsolid tetra\nsolid second\n"
                                        "endsolid\n");
    assert_non_null(strstr(text, "vertex -0 0 0"));
    geo_poly *p = text_ok(text, PROTO_FMT_STL);
    assert_int_equal(p->nverts, 4);
    assert_int_equal(p->nfacets, 4);
    assert_true(fabs(geo_poly_volume(p) - 1.0 / 6) < 1e-15);
    geo_poly_free(p);
}

static void test_stl_ascii_errors_name_the_line(void **state)
{
    (void)state;
    assert_string_equal(text_err("solid x\nfacet normal 0 0 1\nouter lop\n",
                                 PROTO_FMT_STL),
                        "line 3: expected \"loop\", found \"lop\"");
    assert_string_equal(text_err("solid x\nfacet normal 0 0 1\nouter loop\n"
                                 "vertex 0 0 0\nvertex 1 0 0\nendloop\n"
                                 "endfacet\nendsolid\n", PROTO_FMT_STL),
                        "line 2: facet 0: 2 vertices, a facet needs at least "
                        "3");
    assert_string_equal(text_err("solid x\nfacet normal 0 0 1\nouter loop\n"
                                 "vertex 0 0 0\nvertex 1 0 zz\n",
                                 PROTO_FMT_STL),
                        "line 5: vertex: expected a number, found \"zz\"");
    assert_string_equal(text_err("solid x\n", PROTO_FMT_STL),
                        "line 2: expected \"endsolid\", found the end of the "
                        "file");
    assert_string_equal(text_err("solid x\nfacets\n", PROTO_FMT_STL),
                        "line 2: expected \"facet\" or \"endsolid\", found "
                        "\"facets\"");
}

/* ---- PLY ---- */

static void test_ply_ascii_skips_unknown_elements_and_properties(void **state)
{
    (void)state;
    proto_read_report rep;
    const char *text = "ply\n"
                       "format ascii 1.0\n"
                       "comment made by hand\n"
                       "element vertex 4\n"
                       "property float x\n"
                       "property float y\n"
                       "property uchar red\n"
                       "property float z\n"
                       "element face 4\n"
                       "property list uchar int vertex_indices\n"
                       "property int flags\n"
                       "element edge 1\n"
                       "property int vertex1\n"
                       "property list uchar int more\n"
                       "end_header\n"
                       "0 0 255 0\n1 0 0 0\n0 1 0 0\n0 0 0 1\n"
                       "3 0 2 1 7\n3 0 1 3 7\n3 0 3 2 7\n3 1 2 3 7\n"
                       "0 2 5 6\n";
    geo_poly *p = read_ok(text, strlen(text), PROTO_FMT_PLY, &rep);
    assert_int_equal(p->nverts, 4);
    assert_int_equal(p->nfacets, 4);
    assert_int_equal(rep.planes_given, 0);
    assert_true(fabs(geo_poly_volume(p) - 1.0 / 6) < 1e-15);
    geo_poly_free(p);
}

/* A growable byte string for hand-made binary files. */
typedef struct bytes {
    unsigned char d[4096];
    size_t n;
} bytes;

static void b_str(bytes *b, const char *s)
{
    memcpy(b->d + b->n, s, strlen(s));
    b->n += strlen(s);
}

static void b_int(bytes *b, uint64_t v, unsigned size, bool big)
{
    for (unsigned i = 0; i < size; i++)
        b->d[b->n + (big ? size - 1 - i : i)] = (unsigned char)(v >> (8 * i));
    b->n += size;
}

static void b_f32(bytes *b, float f, bool big)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    b_int(b, u, 4, big);
}

/* The tetrahedron as binary PLY: float x y z; face list of count type
 * `ct` (size cs) and int indices. Returns the header length. */
static size_t ply_tetra(bytes *b, bool big, const char *ct, unsigned cs)
{
    b->n = 0;
    b_str(b, big ? "ply\nformat binary_big_endian 1.0\n"
                 : "ply\nformat binary_little_endian 1.0\n");
    b_str(b, "element vertex 4\nproperty float x\nproperty float y\n"
             "property float z\nelement face 4\nproperty list ");
    b_str(b, ct);
    b_str(b, " int vertex_index\nend_header\n");
    size_t h = b->n;
    for (int i = 0; i < 4; i++)
        for (int k = 0; k < 3; k++)
            b_f32(b, TETRA_F[i][k], big);
    for (int t = 0; t < 4; t++) {
        b_int(b, 3, cs, big);
        for (int c = 0; c < 3; c++)
            b_int(b, (uint32_t)TETRA_T[t][c], 4, big);
    }
    return h;
}

static void test_ply_binary_both_endians_and_count_types(void **state)
{
    (void)state;
    static const struct {
        const char *t;
        unsigned size;
    } counts[] = {{"uchar", 1}, {"int", 4}, {"uint", 4}, {"ushort", 2}};
    for (int big = 0; big < 2; big++)
        for (size_t c = 0; c < 4; c++) {
            bytes b;
            ply_tetra(&b, big, counts[c].t, counts[c].size);
            geo_poly *p = read_ok(b.d, b.n, PROTO_FMT_PLY, NULL);
            assert_int_equal(p->nverts, 4);
            assert_int_equal(p->nfacets, 4);
            assert_true(p->verts[3][2] == 1);
            assert_true(fabs(geo_poly_volume(p) - 1.0 / 6) < 1e-15);
            geo_poly_free(p);
        }
}

static void test_ply_errors_name_byte_or_line(void **state)
{
    (void)state;
    bytes b;
    size_t h = ply_tetra(&b, false, "uchar", 1);
    /* face 1, vertex_index[2] */
    size_t at = h + 4 * 12 + 13 + 1 + 2 * 4;
    b.d[at] = 9;
    char want[200];
    snprintf(want, sizeof want, "byte %zu: face 1: vertex_index[2]: index 9 "
                                "out of range (4 vertices)", at);
    assert_string_equal(read_err(b.d, b.n, PROTO_FMT_PLY, NULL), want);
    ply_tetra(&b, false, "uchar", 1);
    snprintf(want, sizeof want, "header: the declared elements need at "
                                "least 52 bytes, 40 follow the header "
                                "(truncated?)");
    assert_string_equal(read_err(b.d, h + 40, PROTO_FMT_PLY, NULL), want);
    snprintf(want, sizeof want, "byte %zu: face 3: vertex_index: 3 items "
                                "cannot fit in the remaining 2 bytes",
             h + 48 + 39);
    assert_string_equal(read_err(b.d, b.n - 10, PROTO_FMT_PLY, NULL), want);
    b.d[b.n++] = 0;
    snprintf(want, sizeof want, "byte %zu: 1 bytes after the last element",
             b.n - 1);
    assert_string_equal(read_err(b.d, b.n, PROTO_FMT_PLY, NULL), want);
    ply_tetra(&b, false, "uchar", 1);
    b.d[h + 4 * 12] = 2; /* face 0 claims 2 vertices */
    snprintf(want, sizeof want, "byte %zu: face 0: vertex_index: 2 vertices, "
                                "a facet needs at least 3", h + 48);
    assert_string_equal(read_err(b.d, b.n, PROTO_FMT_PLY, NULL), want);

    assert_string_equal(text_err("ply\nformat ascii 1.0\nelement vertex 1\n"
                                 "property float x\nproperty float y\n"
                                 "end_header\n0 0\n", PROTO_FMT_PLY),
                        "header: element vertex has no property z");
    assert_string_equal(text_err("ply\nformat ascii 1.0\n"
                                 "element vertex 4000000000\n"
                                 "property float x\nproperty float y\n"
                                 "property float z\nend_header\n",
                                 PROTO_FMT_PLY),
                        "header: vertices: 4000000000 exceed the limit of "
                        "2000000");
    assert_string_equal(text_err("ply\nformat binary_middle_endian 1.0\n",
                                 PROTO_FMT_PLY),
                        "line 2: unknown format \"binary_middle_endian\"");
    assert_string_equal(text_err("ply\nformat ascii 1.0\n", PROTO_FMT_PLY),
                        "no \"end_header\" line within the first 65536 bytes");
    assert_string_equal(text_err("solid\n", PROTO_FMT_PLY),
                        "line 1: not a PLY file (expected \"ply\")");
    assert_string_equal(text_err("ply\nformat ascii 1.0\nelement vertex 3\n"
                                 "property float x\nproperty float y\n"
                                 "property float z\nelement face 1\n"
                                 "property list uchar int vertex_indices\n"
                                 "end_header\n0 0 0\n1 0 0\n0 1 0\n"
                                 "3 0 1 x\n", PROTO_FMT_PLY),
                        "line 13: face 0: vertex_indices[2]: expected an "
                        "integer, found \"x\"");
}

static void test_ply_writes_wide_lists_for_big_facets(void **state)
{
    (void)state;
    enum { N = 300 };
    double v[N][3];
    uint32_t idx[N], start[2] = {0, N};
    for (int i = 0; i < N; i++) {
        v[i][0] = cos(2 * M_PI * i / N);
        v[i][1] = sin(2 * M_PI * i / N);
        v[i][2] = 0;
        idx[i] = (uint32_t)i;
    }
    geo_poly *a = geo_poly_from_arrays(N, &v[0][0], 1, start, idx, NULL, NULL);
    assert_non_null(a);
    size_t len;
    char *buf = write_fmt(a, PROTO_FMT_PLY, &len);
    assert_non_null(strstr(buf, "property list uint uint vertex_indices"));
    geo_poly *b = read_ok(buf, len, PROTO_FMT_PLY, NULL);
    char why[256];
    assert_true(tu_poly_same(a, b, 0, 0, why, sizeof why));
    free(buf);
    geo_poly_free(b);
    /* and the ear clipper splits the 300-gon for STL */
    buf = write_fmt(a, PROTO_FMT_STL, &len);
    assert_int_equal(len, 84 + 50 * (N - 2));
    free(buf);
    geo_poly_free(a);
}

/* ---- FMB1 ---- */

static void test_fmb1_errors_name_the_byte(void **state)
{
    (void)state;
    geo_poly *a = load("notch-cube.json");
    size_t len;
    unsigned char *buf = (unsigned char *)write_fmt(a, PROTO_FMT_FMB1, &len);
    size_t facets = 12 + 24 * 16;
    assert_string_equal(read_err("FMB0\0\0\0\0\0\0\0\0", 12, PROTO_FMT_FMB1,
                                 NULL),
                        "byte 0: not an FMB1 model (expected \"FMB1\" and "
                        "two counts)");
    /* facet 0 is [0,3,2,1]: its third index at facets + 34 + 8 */
    put_u32(buf + facets + 34 + 8, 9001);
    char want[200];
    snprintf(want, sizeof want, "byte %zu: facets[0].vertices[2]: index 9001 "
                                "out of range (16 vertices)", facets + 42);
    assert_string_equal(read_err(buf, len, PROTO_FMT_FMB1, NULL), want);
    put_u32(buf + facets + 34 + 8, 2);
    buf[facets] = 2;
    snprintf(want, sizeof want, "byte %zu: facets[0]: 2 vertices, a facet "
                                "needs at least 3", facets);
    assert_string_equal(read_err(buf, len, PROTO_FMT_FMB1, NULL), want);
    buf[facets] = 4;
    put_u32(buf + 12 + 4, 0x7ff80000); /* vertices[0][0]'s high half: NaN */
    assert_string_equal(read_err(buf, len, PROTO_FMT_FMB1, NULL),
                        "byte 12: vertices[0][0]: not a finite number");
    put_u32(buf + 12 + 4, 0);
    geo_poly *b = read_ok(buf, len, PROTO_FMT_FMB1, NULL);
    geo_poly_free(b);
    snprintf(want, sizeof want, "byte %zu: 1 bytes after the last facet", len);
    unsigned char *longer = malloc(len + 1);
    memcpy(longer, buf, len);
    longer[len] = 0;
    assert_string_equal(read_err(longer, len + 1, PROTO_FMT_FMB1, NULL), want);
    free(longer);
    assert_non_null(strstr(read_err(buf, len - 1, PROTO_FMT_FMB1, NULL),
                           "do not fit in the remaining"));
    free(buf);
    geo_poly_free(a);
}

static void test_huge_counts_fail_before_allocating(void **state)
{
    (void)state;
    /* limits raised as far as they go: only the input's length can stop
     * these (an attempt to allocate would abort under the sanitizers) */
    proto_limits big = {UINT32_MAX, UINT32_MAX, UINT32_MAX, (size_t)1 << 40,
                        false, false};
    unsigned char fmb[20] = "FMB1";
    put_u32(fmb + 4, 1u << 31);
    put_u32(fmb + 8, 5);
    assert_string_equal(read_err(fmb, 20, PROTO_FMT_FMB1, NULL),
                        "byte 4: vertices: 2147483648 exceed the limit of "
                        "2000000");
    put_u32(fmb + 4, 50000000);
    assert_string_equal(read_err(fmb, 20, PROTO_FMT_FMB1, &big),
                        "byte 4: 50000000 vertices and 5 facets need at least "
                        "1200000242 bytes, the model has 20 (truncated?)");
    assert_string_equal(read_err("99999999 3\n0 0 0", 16, PROTO_FMT_POLY,
                                 &big),
                        "line 1: 99999999 vertices and 3 facets cannot fit in "
                        "the remaining 6 bytes (file truncated?)");
    const char *ply = "ply\nformat binary_little_endian 1.0\n"
                      "element vertex 99999999\nproperty double x\n"
                      "property double y\nproperty double z\n"
                      "element face 100000000\n"
                      "property list uchar int vertex_indices\nend_header\n";
    assert_non_null(strstr(read_err(ply, strlen(ply), PROTO_FMT_PLY, &big),
                           "header: the declared elements need at least"));
    const char *face = "ply\nformat binary_little_endian 1.0\n"
                       "element vertex 3\nproperty float x\n"
                       "property float y\nproperty float z\n"
                       "element face 1\n"
                       "property list uint int vertex_indices\nend_header\n";
    bytes b = {.n = 0};
    b_str(&b, face);
    for (int i = 0; i < 9; i++)
        b_f32(&b, (float)(i % 4 == 0), false);
    b_int(&b, 0xfffffff0u, 4, false);
    b_int(&b, 0, 4, false);
    assert_non_null(strstr(read_err(b.d, b.n, PROTO_FMT_PLY, &big),
                           "4294967280 items cannot fit"));
}

/* ---- ASE ---- */

static size_t count_of(const char *s, const char *what)
{
    size_t n = 0;
    for (const char *p = s; (p = strstr(p, what)) != NULL; p++)
        n++;
    return n;
}

static void test_ase_lists_every_triangle_and_marks_diagonals(void **state)
{
    (void)state;
    geo_poly *a = load("notch-cube.json");
    size_t len;
    char *buf = write_fmt(a, PROTO_FMT_ASE, &len);
    uint32_t nt = geo_poly_ncorners(a) - 2 * a->nfacets, diag = 0;
    for (uint32_t f = 0; f < a->nfacets; f++)
        diag += geo_poly_facet_size(a, f) - 3;
    char want[64];
    snprintf(want, sizeof want, "*MESH_NUMFACES %u\n", nt);
    assert_non_null(strstr(buf, want));
    assert_non_null(strstr(buf, "*MESH_NUMVERTEX 16\n"));
    assert_int_equal(count_of(buf, "*MESH_FACE "), nt);
    assert_int_equal(count_of(buf, "*MESH_FACENORMAL "), nt);
    assert_int_equal(count_of(buf, "*MESH_VERTEXNORMAL "), 3 * nt);
    assert_int_equal(count_of(buf, "*MESH_VERTEX "), 16);
    /* every diagonal appears in two triangles, each time flagged 0 */
    assert_int_equal(count_of(buf, "AB: 0") + count_of(buf, "BC: 0") +
                         count_of(buf, "CA: 0"), 2 * diag);
    assert_int_equal(count_of(buf, "{"), count_of(buf, "}"));
    assert_memory_equal(buf, "*3DSMAX_ASCIIEXPORT\t200\n", 24);
    assert_string_equal(read_err(buf, len, PROTO_FMT_ASE, NULL),
                        "ASE files can be written, not read");
    free(buf);
    geo_poly_free(a);
}

/* ---- mutations ---- */

/* A read of arbitrary bytes must give an error message or a model that
 * keeps every invariant of geo_poly. */
static void check_read(const void *data, size_t len, proto_format fmt)
{
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_mem(data, len, fmt, NULL, &err);
    if (!p) {
        assert_true(err.msg[0] != '\0');
        return;
    }
    assert_int_equal(geo_poly_validate_indices(p, NULL), 0);
    for (uint32_t i = 0; i < p->nverts; i++)
        for (int k = 0; k < 3; k++)
            assert_true(isfinite(p->verts[i][k]));
    for (uint32_t f = 0; f < p->nfacets; f++)
        for (int k = 0; k < 4; k++)
            assert_true(isfinite(p->planes[f][k]));
    geo_poly_free(p);
}

static void test_mutated_inputs_give_errors_or_valid_models(void **state)
{
    (void)state;
    static const proto_format fmts[] = {
        PROTO_FMT_JSON, PROTO_FMT_POLY, PROTO_FMT_OBJ, PROTO_FMT_STL,
        PROTO_FMT_STL_ASCII, PROTO_FMT_PLY, PROTO_FMT_PLY_ASCII,
        PROTO_FMT_FMB1};
    static const unsigned char subst[] = {0x00, 0xff, '9', '-', ' ', '\n',
                                          '#', '/', 'e', 0x80};
    geo_poly *a = load("notch-cube.json");
    uint64_t seed = 12345;
    for (size_t i = 0; i < sizeof fmts / sizeof fmts[0]; i++) {
        size_t len;
        char *buf = write_fmt(a, fmts[i], &len);
        unsigned char *m = malloc(len + 1);
        assert_non_null(m);
        size_t step = len / 700 + 1;
        for (size_t cut = 0; cut <= len; cut += step)
            check_read(buf, cut, fmts[i]);
        for (size_t pos = 0; pos < len; pos += step) {
            for (size_t s = 0; s < sizeof subst; s++) {
                memcpy(m, buf, len);
                m[pos] = subst[s];
                check_read(m, len, fmts[i]);
            }
            memcpy(m, buf, len);
            m[pos] ^= 0x01;
            check_read(m, len, fmts[i]);
        }
        /* a few random bytes in several places at once */
        for (int r = 0; r < 300; r++) {
            memcpy(m, buf, len);
            for (int k = 0; k < 4; k++)
                m[geo_rand_next(&seed) % len] =
                    (unsigned char)geo_rand_next(&seed);
            check_read(m, len, fmts[i]);
        }
        free(m);
        free(buf);
    }
    /* pure noise, with and without each format's opening */
    static const char *const openings[] = {"", "solid ", "ply\n", "FMB1",
                                           "{\"format\":\"facet-model/1\","};
    unsigned char noise[512];
    for (int r = 0; r < 400; r++) {
        size_t n = geo_rand_next(&seed) % sizeof noise;
        for (size_t k = 0; k < n; k++)
            noise[k] = (unsigned char)geo_rand_next(&seed);
        const char *o = openings[r % 5];
        memcpy(noise, o, strlen(o) < n ? strlen(o) : n);
        for (size_t i = 0; i < sizeof fmts / sizeof fmts[0]; i++)
            check_read(noise, n, fmts[i]);
    }
    geo_poly_free(a);
}

/* Every list of formats comes from the one table: each entry's name maps
 * back to it, the list names them all in order, and the end is marked. */
static void test_format_table_is_the_one_list(void **state)
{
    (void)state;
    char list[256], want[256] = "";
    proto_format_list(list, sizeof list);
    size_t n = 0;
    proto_format f;
    for (; (f = proto_format_at(n)) != PROTO_FMT_UNKNOWN; n++)
        assert_int_equal(proto_format_from_name(proto_format_name(f)), f);
    assert_true(n >= 9);
    for (size_t i = 0; i < n; i++) {
        size_t len = strlen(want);
        snprintf(want + len, sizeof want - len, "%s%s",
                 i == 0 ? "" : i + 1 == n ? " or " : ", ",
                 proto_format_name(proto_format_at(i)));
    }
    assert_string_equal(list, want);
    assert_non_null(strstr(list, "json, poly, obj"));
    char tiny[8];
    proto_format_list(tiny, sizeof tiny);
    assert_int_equal(strlen(tiny), sizeof tiny - 1);
}

/* The text readers' number parse as it was: strtod on the whole token,
 * no "nan", "inf" or hex floats, an overflow -ERANGE. */
static int strtod_reference(const char *tok, size_t len, double *ret)
{
    char buf[64];
    if (len == 0 || len >= sizeof buf)
        return -EINVAL;
    memcpy(buf, tok, len);
    buf[len] = '\0';
    char c = buf[0] == '-' || buf[0] == '+' ? buf[1] : buf[0];
    if (!((c >= '0' && c <= '9') || c == '.') || strpbrk(buf, "xX"))
        return -EINVAL;
    char *endp;
    double d = strtod(buf, &endp);
    if (endp != buf + len)
        return -EINVAL;
    if (!isfinite(d))
        return -ERANGE;
    *ret = d;
    return 0;
}

/* proto_parse_double takes numbers in JSON's grammar through the JSON
 * reader's conversion and leaves the rest to strtod: the same verdict and
 * the same bits as strtod alone, on every syntax a text model holds. */
static void test_number_tokens_parse_as_strtod(void **state)
{
    (void)state;
    static const char *const fixed[] = {
        "0", "-0", "-0.0", "+0", "+1.5", ".5", "-.5", "5.", "01", "-007",
        "1e5", "1E+05", "1e-400", "1e400", "-1e400", "12345678901234567890",
        "-9223372036854775808", "9223372036854775807", "9223372036854775808",
        "0x1p3", "nan", "inf", "-", "1.2.3", "1e", "1e+", "1ee5", "",
        "0.1000000000000000055511151231257827", "4.9e-324", "2.5e-324",
        "1.7976931348623157e308", "1.7976931348623159e308",
    };
    size_t nfixed = sizeof fixed / sizeof *fixed;
    uint64_t rng = 99;
    char tok[48];
    for (size_t i = 0; i < nfixed + 200000; i++) {
        size_t n;
        if (i < nfixed) {
            n = strlen(fixed[i]);
            memcpy(tok, fixed[i], n);
        } else {
            /* sign, digits, point, digits, exponent: each optional */
            static const char *const signs[] = {"", "", "-", "+"};
            n = (size_t)snprintf(tok, sizeof tok, "%s",
                                 signs[geo_rand_next(&rng) % 4]);
            int nd = (int)(geo_rand_next(&rng) % 21);
            int point = (int)(geo_rand_next(&rng) % (unsigned)(nd + 2)) - 1;
            for (int k = 0; k < nd && n < 40; k++) {
                if (k == point)
                    tok[n++] = '.';
                tok[n++] = (char)('0' + geo_rand_next(&rng) % 10);
            }
            if (point == nd && geo_rand_next(&rng) % 2)
                tok[n++] = '.';
            if (geo_rand_next(&rng) % 3 == 0)
                n += (size_t)snprintf(tok + n, sizeof tok - n, "e%d",
                                      (int)(geo_rand_next(&rng) % 700) - 350);
        }
        tok[n] = '\0';
        double want = 0, got = 0;
        int rw = strtod_reference(tok, n, &want);
        int rg = proto_parse_double(tok, n, &got);
        if (rw != rg || (rw == 0 && memcmp(&want, &got, sizeof got) != 0))
            fail_msg("\"%s\": strtod %d %a, parse %d %a", tok, rw, want, rg,
                     got);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_format_table_is_the_one_list),
        cmocka_unit_test(test_exact_round_trip_through_poly_ply_fmb1),
        cmocka_unit_test(test_obj_round_trip_keeps_positions_and_polygons),
        cmocka_unit_test(test_stl_ascii_round_trip_keeps_positions_exactly),
        cmocka_unit_test(test_stl_binary_round_trip_is_exact_in_float),
        cmocka_unit_test(test_json_to_ply_to_json_gives_back_the_same_model),
        cmocka_unit_test(test_poly_reads_free_layout_with_comments),
        cmocka_unit_test(test_poly_errors_name_line_and_place),
        cmocka_unit_test(test_obj_reads_polygons_and_index_forms),
        cmocka_unit_test(test_obj_errors_name_line_and_place),
        cmocka_unit_test(test_stl_binary_starting_with_solid_is_binary),
        cmocka_unit_test(test_stl_huge_triangle_count_fails_fast),
        cmocka_unit_test(test_stl_ascii_merges_equal_points),
        cmocka_unit_test(test_stl_ascii_errors_name_the_line),
        cmocka_unit_test(test_ply_ascii_skips_unknown_elements_and_properties),
        cmocka_unit_test(test_ply_binary_both_endians_and_count_types),
        cmocka_unit_test(test_ply_errors_name_byte_or_line),
        cmocka_unit_test(test_ply_writes_wide_lists_for_big_facets),
        cmocka_unit_test(test_fmb1_errors_name_the_byte),
        cmocka_unit_test(test_huge_counts_fail_before_allocating),
        cmocka_unit_test(test_ase_lists_every_triangle_and_marks_diagonals),
        cmocka_unit_test(test_mutated_inputs_give_errors_or_valid_models),
        cmocka_unit_test(test_number_tokens_parse_as_strtod),
    };
    return cmocka_run_group_tests(tests, make_tmpdir, remove_tmpdir);
}
