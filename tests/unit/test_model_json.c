/* test_model_json.c — facet-model/1 reading and writing, the format and
 * limit helpers, and the file entry points of proto/model_io.h. */
#include "testutil.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <fcntl.h>
#include <unistd.h>

#include "model_cmp.h"
#include "model_io.h"
#include "text_map.h"

static geo_poly *load(const char *name, proto_read_report *rep)
{
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file_ex(tu_model_path(name),
                                           PROTO_FMT_UNKNOWN, NULL, rep, &err);
    if (!p)
        fail_msg("%s: %s", name, err.msg);
    return p;
}

/* Parses text as facet-model/1 expecting failure; returns the message. */
static const char *parse_error(const char *text)
{
    static geo_err err;
    memset(&err, 0, sizeof err);
    geo_poly *p = proto_model_read_mem(text, strlen(text), PROTO_FMT_JSON,
                                       NULL, &err);
    if (p) {
        geo_poly_free(p);
        fail_msg("accepted: %s", text);
    }
    return err.msg;
}

static geo_poly *parse_ok(const char *text, proto_read_report *rep)
{
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_mem_ex(text, strlen(text), PROTO_FMT_JSON,
                                          NULL, rep, &err);
    if (!p)
        fail_msg("rejected (%s): %s", err.msg, text);
    return p;
}

#define HEAD "{\"format\":\"facet-model/1\","
#define TRI_VERTS "\"vertices\":[[0,0,0],[1,0,0],[0,1,0]]"

static void test_sample_models_load_with_their_counts(void **state)
{
    (void)state;
    static const struct {
        const char *name;
        uint32_t nv, nf;
    } samples[] = {
        {"brilliant.scan-k400.json", 3612, 1808},
        {"brilliant.scan-k100.json", 2114, 1059},
        {"brilliant.scan-k800.json", 4404, 2204},
        {"brilliant.truth.json", 238, 121},
        {"brilliant.holes.json", 238, 119},
        {"brilliant.selfint.json", 238, 121},
        {"notch-cube.json", 16, 10},
        {"notch-cube.flipped.json", 16, 10},
        {"l-prism.json", 12, 8},
    };
    for (size_t i = 0; i < sizeof samples / sizeof samples[0]; i++) {
        proto_read_report rep;
        geo_poly *p = load(samples[i].name, &rep);
        assert_int_equal(p->nverts, samples[i].nv);
        assert_int_equal(p->nfacets, samples[i].nf);
        assert_int_equal(rep.planes_given, samples[i].nf);
        for (uint32_t f = 0; f < p->nfacets; f++) {
            const double *pl = p->planes[f];
            assert_true(fabs(pl[0] * pl[0] + pl[1] * pl[1] + pl[2] * pl[2] -
                             1) < 1e-15);
        }
        geo_poly_free(p);
    }
}

static void test_valid_samples_have_matching_planes(void **state)
{
    (void)state;
    proto_read_report rep;
    geo_poly *p = load("brilliant.scan-k400.json", &rep);
    assert_int_equal(rep.plane_mismatches, 0);
    assert_string_equal(rep.first, "");
    assert_true(rep.worst_deviation <= geo_poly_eps(p));
    geo_poly_free(p);
    p = load("notch-cube.json", &rep);
    assert_int_equal(rep.plane_mismatches, 0);
    assert_true(fabs(geo_poly_volume(p) - 936) < 1e-9);
    geo_poly_free(p);
}

static void test_moved_vertex_is_reported_as_plane_mismatch(void **state)
{
    (void)state;
    proto_read_report rep;
    geo_poly *p = load("brilliant.selfint.json", &rep);
    assert_true(rep.plane_mismatches > 0);
    assert_true(rep.worst_deviation > 1);
    assert_non_null(strstr(rep.first, "off the plane"));
    assert_int_not_equal(rep.worst_facet, UINT32_MAX);
    geo_poly_free(p);
}

static void test_reversed_facet_is_reported_as_inward_plane(void **state)
{
    (void)state;
    proto_read_report rep;
    geo_poly *p = parse_ok(HEAD TRI_VERTS ",\"facets\":[{\"vertices\":[0,1,2],"
                           "\"plane\":[0,0,-1,0]}]}", &rep);
    assert_int_equal(rep.plane_mismatches, 1);
    assert_string_equal(rep.first, "facets[0].plane: the normal points "
                                   "against the vertex order (inward)");
    /* the given plane is kept */
    assert_true(p->planes[0][2] == -1);
    geo_poly_free(p);
}

static void test_given_plane_is_normalised_and_checked(void **state)
{
    (void)state;
    proto_read_report rep;
    geo_poly *p = parse_ok(HEAD TRI_VERTS ",\"facets\":[{\"vertices\":[0,1,2],"
                           "\"plane\":[0,0,2,0]}]}", &rep);
    assert_true(p->planes[0][2] == 1);
    assert_int_equal(rep.plane_mismatches, 0);
    assert_int_equal(rep.planes_given, 1);
    geo_poly_free(p);
    p = parse_ok(HEAD TRI_VERTS ",\"facets\":[{\"vertices\":[0,1,2],"
                 "\"plane\":[0,0,1,-0.5]}]}", &rep);
    assert_int_equal(rep.plane_mismatches, 1);
    assert_string_equal(rep.first,
                        "facets[0].plane: vertex 0 (facets[0].vertices[0]) "
                        "lies 0.5 mm off the plane (tolerance 2.41e-10 mm)");
    assert_true(rep.worst_deviation == 0.5);
    assert_int_equal(rep.worst_facet, 0);
    geo_poly_free(p);
    p = parse_ok(HEAD TRI_VERTS ",\"facets\":[{\"vertices\":[0,1,2],"
                 "\"plane\":[0,0,0,3]}]}", &rep);
    assert_int_equal(rep.plane_mismatches, 1);
    assert_non_null(strstr(rep.first, "zero normal"));
    assert_true(p->planes[0][2] == 1 && p->planes[0][3] == 0);
    geo_poly_free(p);
}

static void test_absent_plane_is_computed_outward(void **state)
{
    (void)state;
    proto_read_report rep;
    geo_poly *p = parse_ok("{\"units\":\"mm\",\"format\":\"facet-model/1\","
                           "\"vertices\":[[0,0,5],[1,0,5],[0,1,5]],"
                           "\"facets\":[{\"vertices\":[2,1,0]}]}", &rep);
    assert_int_equal(rep.planes_given, 0);
    assert_true(fabs(p->planes[0][2] + 1) < 1e-15);
    assert_true(fabs(p->planes[0][3] - 5) < 1e-14);
    geo_poly_free(p);
}

/* Reads text with proto_limits.implicit_planes. */
static geo_poly *parse_implicit(const char *text)
{
    proto_limits lim;
    proto_limits_default(&lim);
    lim.implicit_planes = true;
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_mem(text, strlen(text), PROTO_FMT_JSON,
                                       &lim, &err);
    if (!p)
        fail_msg("rejected (%s): %s", err.msg, text);
    return p;
}

static void test_implicit_planes_only_for_planeless_triangles(
    void **state)
{
    (void)state;
    const char *tris = HEAD "\"vertices\":[[0,0,5],[1,0,5],[0,1,5],[0,0,6]],"
                       "\"facets\":[{\"vertices\":[2,1,0]},"
                       "{\"vertices\":[0,1,3]}]}";
    geo_poly *p = parse_implicit(tris), *q = parse_ok(tris, NULL);
    assert_null(p->planes);
    for (uint32_t f = 0; f < 2; f++) {
        double pl[4];
        geo_poly_facet_plane(p, f, pl);
        assert_memory_equal(pl, q->planes[f], sizeof pl);
    }
    /* a copy makes them explicit, the same bits */
    geo_poly *c = geo_poly_copy(p);
    assert_non_null(c);
    assert_non_null(c->planes);
    assert_memory_equal(c->planes, q->planes, 2 * sizeof *q->planes);
    geo_poly_free(c);
    geo_poly_free(p);
    geo_poly_free(q);
    /* a given plane, or a facet of four vertices, keeps them stored */
    p = parse_implicit(HEAD TRI_VERTS ",\"facets\":[{\"vertices\":[0,1,2],"
                       "\"plane\":[0,0,2,0]}]}");
    assert_non_null(p->planes);
    assert_true(p->planes[0][2] == 1);
    geo_poly_free(p);
    p = parse_implicit(HEAD "\"vertices\":[[0,0,0],[1,0,0],[1,1,0],[0,1,0]],"
                       "\"facets\":[{\"vertices\":[0,1,2,3]}]}");
    assert_non_null(p->planes);
    assert_true(p->planes[0][2] == 1);
    geo_poly_free(p);
}

static void test_unknown_keys_are_ignored(void **state)
{
    (void)state;
    geo_poly *p = parse_ok(HEAD "\"name\":\"x\",\"extra\":{\"a\":[1,2]},"
                           TRI_VERTS ",\"facets\":[{\"vertices\":[0,1,2],"
                           "\"color\":\"red\"}]}", NULL);
    assert_int_equal(p->nfacets, 1);
    geo_poly_free(p);
}

static void test_empty_model_is_valid(void **state)
{
    (void)state;
    geo_poly *p = parse_ok(HEAD "\"vertices\":[],\"facets\":[]}", NULL);
    assert_int_equal(p->nverts, 0);
    assert_int_equal(p->nfacets, 0);
    geo_poly_free(p);
}

static void test_syntax_errors_name_line_and_column(void **state)
{
    (void)state;
    assert_string_equal(parse_error("{\"format\":\"facet-model/1\",\n"
                                    "\"vertices\":[[0,0,0],\n[1,0 0]]}"),
                        "line 3, column 6: ']' expected near '0'");
    assert_string_equal(parse_error("{\"format\":\"facet-model/1\","
                                    "\"format\":\"facet-model/1\"}"),
                        "line 1, column 34: duplicate object key near "
                        "'\"format\"'");
    assert_non_null(strstr(parse_error(HEAD "\"vertices\":[[NaN,0,0]]"),
                           "line 1"));
    assert_non_null(strstr(parse_error(HEAD "\"vertices\":[[Infinity,0,0]]"),
                           "line 1"));
    assert_non_null(strstr(parse_error(HEAD "\"vertices\":[[1e999,0,0]],"
                                       "\"facets\":[]}"),
                           "real number overflow"));
    assert_non_null(strstr(parse_error(HEAD "\"vertices\":[],\"facets\":[]}"
                                       " trailing"),
                           "end of file expected"));
    assert_non_null(strstr(parse_error(""), "line 1"));
    assert_string_equal(parse_error("{\"a\":\"\xff\"}"),
                        "line 1, column 6: unable to decode byte 0xff near "
                        "'\"'");
}

static void test_structure_errors_name_the_place(void **state)
{
    (void)state;
    assert_string_equal(parse_error("[1,2]"), "expected a JSON object");
    assert_string_equal(parse_error("{\"vertices\":[],\"facets\":[]}"),
                        "format: missing (expected \"facet-model/1\")");
    assert_string_equal(parse_error("{\"format\":3}"),
                        "format: expected a string");
    assert_string_equal(parse_error("{\"format\":\"facet-model/2\"}"),
                        "format: \"facet-model/2\" is not supported (expected "
                        "\"facet-model/1\")");
    assert_string_equal(parse_error(HEAD "\"units\":\"in\"}"),
                        "units: \"in\" is not supported (only \"mm\")");
    assert_string_equal(parse_error(HEAD "\"units\":1}"),
                        "units: expected a string");
    assert_string_equal(parse_error(HEAD "\"facets\":[]}"),
                        "vertices: missing");
    assert_string_equal(parse_error(HEAD "\"vertices\":{},\"facets\":[]}"),
                        "vertices: expected an array");
    assert_string_equal(parse_error(HEAD "\"vertices\":[]}"),
                        "facets: missing");
    assert_string_equal(parse_error(HEAD "\"vertices\":[],\"facets\":3}"),
                        "facets: expected an array");
    assert_string_equal(parse_error(HEAD "\"vertices\":[[0,0,0],[1,0]],"
                                    "\"facets\":[]}"),
                        "vertices[1]: expected an array of 3 numbers");
    assert_string_equal(
        parse_error(HEAD "\"vertices\":[[0,0,0],[0,0,0],[0,0,0],[0,0,0],"
                    "[0,0,0],[0,\"1\",0]],\"facets\":[]}"),
        "vertices[5][1]: expected a number");
    assert_string_equal(parse_error(HEAD TRI_VERTS ",\"facets\":[[0,1,2]]}"),
                        "facets[0]: expected an object");
    assert_string_equal(parse_error(HEAD TRI_VERTS ",\"facets\":[{}]}"),
                        "facets[0].vertices: missing");
    assert_string_equal(parse_error(HEAD TRI_VERTS
                                    ",\"facets\":[{\"vertices\":7}]}"),
                        "facets[0].vertices: expected an array");
    assert_string_equal(parse_error(HEAD TRI_VERTS
                                    ",\"facets\":[{\"vertices\":[0,1]}]}"),
                        "facets[0].vertices: 2 vertices, a facet needs at "
                        "least 3");
    assert_string_equal(parse_error(HEAD TRI_VERTS
                                    ",\"facets\":[{\"vertices\":[0,1.0,2]}]}"),
                        "facets[0].vertices[1]: expected an integer");
    assert_string_equal(parse_error(HEAD TRI_VERTS
                                    ",\"facets\":[{\"vertices\":[0,1,2]},"
                                    "{\"vertices\":[0,1,9001]}]}"),
                        "facets[1].vertices[2]: index 9001 out of range "
                        "(3 vertices)");
    assert_string_equal(parse_error(HEAD TRI_VERTS
                                    ",\"facets\":[{\"vertices\":[0,-1,2]}]}"),
                        "facets[0].vertices[1]: index -1 out of range "
                        "(3 vertices)");
    assert_string_equal(parse_error(HEAD TRI_VERTS
                                    ",\"facets\":[{\"vertices\":[0,1,1,2]}]}"),
                        "facets[0].vertices[2]: index 1 repeated "
                        "consecutively");
    assert_string_equal(parse_error(HEAD TRI_VERTS
                                    ",\"facets\":[{\"vertices\":[0,1,2,0]}]}"),
                        "facets[0].vertices[0]: index 0 repeated "
                        "consecutively");
    assert_string_equal(parse_error(HEAD TRI_VERTS
                                    ",\"facets\":[{\"vertices\":[0,1,2],"
                                    "\"plane\":[0,0,1]}]}"),
                        "facets[0].plane: expected an array of 4 numbers");
    assert_string_equal(parse_error(HEAD TRI_VERTS
                                    ",\"facets\":[{\"vertices\":[0,1,2],"
                                    "\"plane\":[0,0,1,null]}]}"),
                        "facets[0].plane[3]: expected a number");
}

static void test_index_error_in_a_large_model_names_facet(void **state)
{
    (void)state;
    /* 8000 vertices, facet 12 refers to vertex 9001 */
    size_t cap = 8000 * 16 + 4096;
    char *s = malloc(cap);
    assert_non_null(s);
    size_t n = (size_t)snprintf(s, cap, HEAD "\"vertices\":[");
    for (int i = 0; i < 8000; i++)
        n += (size_t)snprintf(s + n, cap - n, "%s[%d,0,0]", i ? "," : "", i);
    n += (size_t)snprintf(s + n, cap - n, "],\"facets\":[");
    for (int f = 0; f < 13; f++)
        n += (size_t)snprintf(s + n, cap - n, "%s{\"vertices\":[0,1,2,%d]}",
                              f ? "," : "", f == 12 ? 9001 : 3);
    snprintf(s + n, cap - n, "]}");
    assert_string_equal(parse_error(s), "facets[12].vertices[3]: index 9001 "
                                        "out of range (8000 vertices)");
    free(s);
}

static void test_limits_reject_before_building(void **state)
{
    (void)state;
    proto_limits lim;
    proto_limits_default(&lim);
    assert_int_equal(lim.max_vertices, 2000000);
    assert_int_equal(lim.max_facets, 4000000);
    assert_int_equal(lim.max_corners, 16000000);
    assert_true(lim.max_bytes == (size_t)512 << 20);
    const char *text = HEAD TRI_VERTS ",\"facets\":[{\"vertices\":[0,1,2]},"
                                      "{\"vertices\":[2,1,0]}]}";
    geo_err err = {{0}};
    lim.max_vertices = 2;
    assert_null(proto_model_read_mem(text, strlen(text), PROTO_FMT_JSON, &lim,
                                     &err));
    assert_string_equal(err.msg, "vertices: 3 exceed the limit of 2");
    proto_limits_default(&lim);
    lim.max_facets = 1;
    assert_null(proto_model_read_mem(text, strlen(text), PROTO_FMT_JSON, &lim,
                                     &err));
    assert_string_equal(err.msg, "facets: 2 exceed the limit of 1");
    proto_limits_default(&lim);
    lim.max_corners = 5;
    assert_null(proto_model_read_mem(text, strlen(text), PROTO_FMT_JSON, &lim,
                                     &err));
    assert_string_equal(err.msg, "facets: 6 vertex indices in all exceed the "
                                 "limit of 5");
    proto_limits_default(&lim);
    lim.max_bytes = 10;
    assert_null(proto_model_read_mem(text, strlen(text), PROTO_FMT_JSON, &lim,
                                     &err));
    assert_non_null(strstr(err.msg, "exceed the limit of 10"));
}

static void test_json_round_trip_is_bit_exact(void **state)
{
    (void)state;
    const char *names[] = {"brilliant.scan-k400.json", "notch-cube.json",
                           "brilliant.selfint.json"};
    for (size_t i = 0; i < 3; i++) {
        geo_poly *a = load(names[i], NULL);
        char *buf;
        size_t len;
        geo_err err = {{0}};
        assert_int_equal(proto_model_write_mem(a, PROTO_FMT_JSON, &buf, &len,
                                               &err), 0);
        geo_poly *b = proto_model_read_mem(buf, len, PROTO_FMT_JSON, NULL,
                                           &err);
        assert_non_null(b);
        char why[256];
        if (!tu_poly_same(a, b, 0, 0, why, sizeof why))
            fail_msg("%s: %s", names[i], why);
        free(buf);
        geo_poly_free(a);
        geo_poly_free(b);
    }
}

static void test_awkward_doubles_round_trip_exactly(void **state)
{
    (void)state;
    /* within the coordinate range of a model (±1e9 mm, model_codec.h);
     * the extremes of the double range are refused on reading, below */
    double v[9] = {0.1, -0.0, 1e-300, 5e-324, 999999999.99999988,
                   -123456789.01234567, 1.0 / 3, 2.5e-17,
                   -0.30000000000000004};
    uint32_t start[] = {0, 3}, idx[] = {0, 1, 2};
    double planes[4] = {0, 0, 1, 0};
    geo_poly *a = geo_poly_from_arrays(3, v, 1, start, idx, planes, NULL);
    assert_non_null(a);
    char *buf;
    size_t len;
    assert_int_equal(proto_model_write_mem(a, PROTO_FMT_JSON, &buf, &len,
                                           NULL), 0);
    /* shortest forms: 0.1 stays 0.1, negative zero keeps its sign */
    assert_non_null(strstr(buf, "[0.1,-0.0,1e-300]"));
    geo_poly *b = proto_model_read_mem(buf, len, PROTO_FMT_JSON, NULL, NULL);
    assert_non_null(b);
    char why[256];
    if (!tu_poly_same(a, b, 0, -1, why, sizeof why))
        fail_msg("%s", why);
    free(buf);
    geo_poly_free(b);
    /* the largest double is written exactly but refused as a coordinate */
    a->verts[1][1] = 1.7976931348623157e308;
    assert_int_equal(proto_model_write_mem(a, PROTO_FMT_JSON, &buf, &len,
                                           NULL), 0);
    geo_err err = {{0}};
    assert_null(proto_model_read_mem(buf, len, PROTO_FMT_JSON, NULL, &err));
    assert_non_null(strstr(err.msg, "vertices[1][1]: 1.79769e+308 mm is "
                                    "beyond the ±1e+09 mm"));
    free(buf);
    geo_poly_free(a);
}

static void test_to_json_value_reads_back_exactly(void **state)
{
    (void)state;
    geo_poly *a = load("brilliant.truth.json", NULL);
    json_t *j = proto_model_to_json(a);
    assert_non_null(j);
    char *text = json_dumps(j, JSON_COMPACT);
    assert_non_null(text);
    geo_poly *b = proto_model_read_mem(text, strlen(text), PROTO_FMT_JSON,
                                       NULL, NULL);
    assert_non_null(b);
    char why[256];
    if (!tu_poly_same(a, b, 0, 0, why, sizeof why))
        fail_msg("%s", why);
    geo_poly *c = proto_model_from_json(j, NULL, "model", NULL);
    assert_non_null(c);
    assert_true(tu_poly_same(a, c, 0, 0, why, sizeof why));
    free(text);
    json_decref(j);
    geo_poly_free(a);
    geo_poly_free(b);
    geo_poly_free(c);
}

static void test_from_json_prefixes_the_path(void **state)
{
    (void)state;
    json_error_t je;
    json_t *j = json_loads(HEAD TRI_VERTS ",\"facets\":[{\"vertices\":"
                           "[0,1,7]}]}", 0, &je);
    assert_non_null(j);
    geo_err err = {{0}};
    assert_null(proto_model_from_json(j, NULL, "model", &err));
    assert_string_equal(err.msg, "model.facets[0].vertices[2]: index 7 out "
                                 "of range (3 vertices)");
    json_decref(j);
    j = json_integer(3);
    assert_null(proto_model_from_json(j, NULL, "model", &err));
    assert_string_equal(err.msg, "model: expected a JSON object");
    json_decref(j);
}

static void test_format_names_and_extensions(void **state)
{
    (void)state;
    assert_int_equal(proto_format_from_path("a/b.JSON"), PROTO_FMT_JSON);
    assert_int_equal(proto_format_from_path("x.poly"), PROTO_FMT_POLY);
    assert_int_equal(proto_format_from_path("x.obj"), PROTO_FMT_OBJ);
    assert_int_equal(proto_format_from_path("x.stl"), PROTO_FMT_STL);
    assert_int_equal(proto_format_from_path("x.ply"), PROTO_FMT_PLY);
    assert_int_equal(proto_format_from_path("x.ase"), PROTO_FMT_ASE);
    assert_int_equal(proto_format_from_path("x.fmb"), PROTO_FMT_FMB1);
    assert_int_equal(proto_format_from_path("dir.json/x"), PROTO_FMT_UNKNOWN);
    assert_int_equal(proto_format_from_path("x.txt"), PROTO_FMT_UNKNOWN);
    assert_int_equal(proto_format_from_name("stl-ascii"),
                     PROTO_FMT_STL_ASCII);
    assert_int_equal(proto_format_from_name("ply-ascii"),
                     PROTO_FMT_PLY_ASCII);
    assert_int_equal(proto_format_from_name("fmb1"), PROTO_FMT_FMB1);
    assert_int_equal(proto_format_from_name("nope"), PROTO_FMT_UNKNOWN);
    for (int f = PROTO_FMT_JSON; f <= PROTO_FMT_FMB1; f++)
        assert_int_equal(proto_format_from_name(proto_format_name(f)), f);
    assert_string_equal(proto_format_mime(PROTO_FMT_JSON), "application/json");
    assert_string_equal(proto_format_mime(PROTO_FMT_STL), "model/stl");
}

static char tmpdir[256];

static int make_tmpdir(void **state)
{
    (void)state;
    const char *base = getenv("TMPDIR");
    snprintf(tmpdir, sizeof tmpdir, "%s/facet-json-XXXXXX",
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

static int count_entries(const char *dir)
{
    DIR *d = opendir(dir);
    int n = 0;
    struct dirent *e;
    while (d && (e = readdir(d)))
        if (e->d_name[0] != '.')
            n++;
    if (d)
        closedir(d);
    return n;
}

static void test_write_file_is_atomic_and_reads_back(void **state)
{
    (void)state;
    geo_poly *a = load("notch-cube.json", NULL);
    char path[600];
    snprintf(path, sizeof path, "%s/m.json", tmpdir);
    geo_err err = {{0}};
    assert_int_equal(proto_model_write_file(a, path, PROTO_FMT_UNKNOWN, &err),
                     0);
    assert_int_equal(count_entries(tmpdir), 1);
    assert_int_equal(chmod(path, 0600), 0);
    assert_int_equal(proto_model_write_file(a, path, PROTO_FMT_JSON, &err), 0);
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    assert_int_equal(st.st_mode & 0777, 0600);
    assert_int_equal(count_entries(tmpdir), 1);
    geo_poly *b = proto_model_read_file(path, PROTO_FMT_UNKNOWN, NULL, &err);
    assert_non_null(b);
    char why[256];
    assert_true(tu_poly_same(a, b, 0, 0, why, sizeof why));
    /* an unwritable target leaves nothing behind */
    char bad[700];
    snprintf(bad, sizeof bad, "%s/no/such/dir/m.json", tmpdir);
    assert_int_equal(proto_model_write_file(a, bad, PROTO_FMT_UNKNOWN, &err),
                     -ENOENT);
    assert_non_null(strstr(err.msg, "no/such/dir/m.json"));
    assert_int_equal(count_entries(tmpdir), 1);
    assert_int_equal(proto_model_write_file(a, "x.unknown", PROTO_FMT_UNKNOWN,
                                            &err), -EINVAL);
    assert_non_null(strstr(err.msg, "cannot tell the format"));
    geo_poly_free(a);
    geo_poly_free(b);
}

static void test_read_file_errors_name_the_file(void **state)
{
    (void)state;
    char path[600];
    snprintf(path, sizeof path, "%s/bad.json", tmpdir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(HEAD TRI_VERTS ",\"facets\":[{\"vertices\":[0,1,3]}]}", f);
    fclose(f);
    geo_err err = {{0}};
    assert_null(proto_model_read_file(path, PROTO_FMT_UNKNOWN, NULL, &err));
    char want[800];
    snprintf(want, sizeof want, "%s: facets[0].vertices[2]: index 3 out of "
                                "range (3 vertices)", path);
    assert_string_equal(err.msg, want);
    proto_limits lim;
    proto_limits_default(&lim);
    lim.max_bytes = 16;
    assert_null(proto_model_read_file(path, PROTO_FMT_UNKNOWN, &lim, &err));
    assert_non_null(strstr(err.msg, "exceed the limit of 16"));
    snprintf(path, sizeof path, "%s/missing.json", tmpdir);
    assert_null(proto_model_read_file(path, PROTO_FMT_UNKNOWN, NULL, &err));
    assert_non_null(strstr(err.msg, "missing.json: No such file"));
    assert_null(proto_model_read_file(tmpdir, PROTO_FMT_JSON, NULL, &err));
    assert_non_null(strstr(err.msg, "directory"));
    unlink(path);
}

/* Writes a facet-model/1 text of several MiB (n vertices on lines, a
 * name with multi-byte characters, then tail) to path. */
static void write_big(const char *path, uint32_t n, const char *tail)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(HEAD "\"name\":\"\u00e9t\u00e9 \xc3\xa9t\xc3\xa9"
          "\",\n\"vertices\":[\n", f);
    for (uint32_t i = 0; i < n; i++)
        fprintf(f, "[%u.125,%u.5,%u]%s\n", i, i % 7, i % 3,
                i + 1 < n ? "," : "");
    fputs(tail, f);
    assert_int_equal(fclose(f), 0);
}

static void test_mapped_file_reads_as_read(void **state)
{
    (void)state;
    char path[600];
    snprintf(path, sizeof path, "%s/big.json", tmpdir);
    proto_limits lim;
    proto_limits_default(&lim);
    lim.map_file = true;
    /* a model, and errors late in the text: the same model, the same
     * messages (line and column counted over released pages) */
    static const char *tails[] = {
        "],\"facets\":[{\"vertices\":[0,1,2]},{\"vertices\":[3,2,1]}]}\n",
        "],\"facets\":[{\"vertices\":[0,1,2]},{\"vertices\":[3,2,1]]}\n",
        "],\"facets\":[{\"vertices\":[0,1,2]},{\"vertices\":[3,2,9999999]}]}",
        "],\"facets\":[{\"vertices\":[0,1,2]}]} x",
    };
    for (size_t k = 0; k < sizeof tails / sizeof *tails; k++) {
        write_big(path, 300000, tails[k]);
        geo_err e1 = {{0}}, e2 = {{0}};
        geo_poly *a = proto_model_read_file(path, PROTO_FMT_UNKNOWN, NULL, &e1);
        geo_poly *b = proto_model_read_file(path, PROTO_FMT_UNKNOWN, &lim, &e2);
        assert_true((a == NULL) == (b == NULL));
        assert_true((a == NULL) == (k > 0));
        if (a) {
            char why[256];
            assert_true(tu_poly_same(a, b, 0, 0, why, sizeof why));
        } else {
            assert_string_equal(e1.msg, e2.msg);
        }
        geo_poly_free(a);
        geo_poly_free(b);
    }
    /* the pages behind are given back and read back the same */
    int fd = open(path, O_RDONLY);
    assert_true(fd >= 0);
    proto_text_map tm;
    geo_err err = {{0}};
    assert_int_equal(proto_text_map_open(fd, lim.max_bytes, &tm, &err), 0);
    close(fd);
    assert_true(tm.len > 3 * PROTO_JPULL_BEHIND_STEP);
    char head[64];
    memcpy(head, tm.data, sizeof head);
    proto_text_map_behind(&tm, tm.len / 2);
    assert_true(tm.released > 0 && tm.released <= tm.len / 2);
    assert_memory_equal(tm.data, head, sizeof head);
    proto_text_map_close(&tm);
    /* the limit, and what cannot be mapped, as without the option */
    lim.max_bytes = 16;
    assert_null(proto_model_read_file(path, PROTO_FMT_UNKNOWN, &lim, &err));
    assert_non_null(strstr(err.msg, "exceed the limit of 16"));
    lim.max_bytes = (size_t)512 << 20;
    assert_null(proto_model_read_file(tmpdir, PROTO_FMT_JSON, &lim, &err));
    assert_non_null(strstr(err.msg, "directory"));
    unlink(path);
}

static void test_writers_reject_non_finite_models(void **state)
{
    (void)state;
    geo_poly *a = load("notch-cube.json", NULL);
    a->verts[3][1] = NAN;
    char *buf = NULL;
    size_t len;
    geo_err err = {{0}};
    assert_int_equal(proto_model_write_mem(a, PROTO_FMT_JSON, &buf, &len,
                                           &err), -EINVAL);
    assert_string_equal(err.msg, "vertices[3][1]: not a finite number");
    assert_null(buf);
    geo_poly_free(a);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sample_models_load_with_their_counts),
        cmocka_unit_test(test_valid_samples_have_matching_planes),
        cmocka_unit_test(test_moved_vertex_is_reported_as_plane_mismatch),
        cmocka_unit_test(test_reversed_facet_is_reported_as_inward_plane),
        cmocka_unit_test(test_given_plane_is_normalised_and_checked),
        cmocka_unit_test(test_absent_plane_is_computed_outward),
        cmocka_unit_test(test_implicit_planes_only_for_planeless_triangles),
        cmocka_unit_test(test_unknown_keys_are_ignored),
        cmocka_unit_test(test_empty_model_is_valid),
        cmocka_unit_test(test_syntax_errors_name_line_and_column),
        cmocka_unit_test(test_structure_errors_name_the_place),
        cmocka_unit_test(test_index_error_in_a_large_model_names_facet),
        cmocka_unit_test(test_limits_reject_before_building),
        cmocka_unit_test(test_json_round_trip_is_bit_exact),
        cmocka_unit_test(test_awkward_doubles_round_trip_exactly),
        cmocka_unit_test(test_to_json_value_reads_back_exactly),
        cmocka_unit_test(test_from_json_prefixes_the_path),
        cmocka_unit_test(test_format_names_and_extensions),
        cmocka_unit_test(test_write_file_is_atomic_and_reads_back),
        cmocka_unit_test(test_read_file_errors_name_the_file),
        cmocka_unit_test(test_mapped_file_reads_as_read),
        cmocka_unit_test(test_writers_reject_non_finite_models),
    };
    return cmocka_run_group_tests(tests, make_tmpdir, remove_tmpdir);
}
