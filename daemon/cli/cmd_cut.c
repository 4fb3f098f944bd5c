/* cmd_cut.c — `facet cut MODEL --plane a,b,c,d -o OUT [--main-facet N]`:
 * cuts a model by a plane (lib/cut/cut.h), keeps the part where
 * a·x+b·y+c·z+d ≤ 0, writes it and prints a one-line JSON summary on
 * stdout. An unchanged or empty result is a success (the summary says
 * which); a result the model format cannot hold is bad input. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "cli_args.h"
#include "cut.h"
#include "model_io.h"

static const char USAGE[] =
    "usage: facet cut MODEL --plane A,B,C,D -o OUT [--main-facet N]\n"
    "\n"
    "Cuts the polyhedron MODEL by the plane A·x+B·y+C·z+D = 0 and writes the\n"
    "part where A·x+B·y+C·z+D <= 0 to OUT, closed by new facets on the plane\n"
    "(one per section component, several side by side for a component with\n"
    "holes; their outward normal is (A,B,C)). Formats\n"
    "come from the file extensions (see 'facet convert --help').\n"
    "\n"
    "  --plane A,B,C,D  the plane; (A,B,C) need not be unit\n"
    "  -o, --output OUT the result\n"
    "  --main-facet N   Palachev 2012, §3.4 (facet merging): facet N, which may be\n"
    "                   non-planar and must lie on or above the plane, is\n"
    "                   replaced by the one new facet\n"
    "\n"
    "Prints one line of JSON: components, new_facets, split_facets, pieces,\n"
    "removed_facets, new_vertices, removed_vertices, hanging_dropped,\n"
    "unchanged, empty, volume_before, volume_after, vertices, facets.\n"
    "exit status: 0 success (also unchanged or empty), 1 bad input or a\n"
    "result no valid polyhedron can represent (the kept part touching\n"
    "itself along an edge or at a point: the message says which way to\n"
    "move the plane), 2 usage error\n";

static int parse_plane(const char *s, double ret[4])
{
    const char *p = s;
    for (int k = 0; k < 4; k++) {
        char *end;
        errno = 0;
        ret[k] = strtod(p, &end);
        if (end == p || errno == ERANGE || !isfinite(ret[k]))
            return -1;
        p = end;
        if (k < 3) {
            if (*p != ',')
                return -1;
            p++;
        }
    }
    return *p == '\0' ? 0 : -1;
}

int cmd_cut(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        fputs(USAGE, stdout);
        return CLI_OK;
    }
    const char *in = NULL, *outpath = NULL;
    double plane[4];
    bool have_plane = false;
    geo_cut_opts opts;
    geo_cut_opts_default(&opts);
    enum { O_PLANE, O_OUT, O_MAIN };
    static const cli_opt cut_opts[] = {{"--plane", O_PLANE, true},
                                       {"-o", O_OUT, true},
                                       {"--output", O_OUT, true},
                                       {"--main-facet", O_MAIN, true},
                                       {NULL, 0, false}};
    cli_args a;
    const char *v;
    long f;
    cli_args_init(&a, "cut", argc, argv, cut_opts);
    cli_args_positionals(&a, &in, 1);
    for (int k; (k = cli_args_next(&a, &v)) != CLI_ARGS_END;) {
        int r = 0;
        switch (k) {
        case O_OUT: outpath = v; break;
        case O_PLANE:
            if (parse_plane(v, plane) < 0)
                return cli_usage_error("cut", "--plane: expected four "
                                       "finite numbers A,B,C,D, got '%s'", v);
            have_plane = true;
            break;
        case O_MAIN:
            r = cli_args_long(&a, v, 0, GEO_NONE - 1L, &f);
            opts.main_facet = (uint32_t)f;
            break;
        default: r = CLI_ARGS_ERROR;
        }
        if (r)
            return CLI_USAGE;
    }
    if (!in)
        return cli_usage_error("cut", "needs a model file");
    if (!have_plane)
        return cli_usage_error("cut", "needs --plane A,B,C,D");
    if (cli_args_output(&a, outpath) != CLI_OK)
        return CLI_USAGE;

    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(in, PROTO_FMT_UNKNOWN, NULL, &err);
    if (!p)
        return cli_input_error("cut", "%s", err.msg);
    geo_poly *out = geo_poly_new();
    if (!out) {
        geo_poly_free(p);
        return cli_input_error("cut", "out of memory");
    }
    geo_cut_report rep;
    int r = geo_cut(p, plane, &opts, NULL, out, &rep, &err);
    geo_poly_free(p);
    if (r < 0) {
        geo_poly_free(out);
        return cli_input_error("cut", "%s: %s", in, err.msg);
    }
    r = proto_model_write_file(out, outpath, PROTO_FMT_UNKNOWN, &err);
    if (r < 0) {
        geo_poly_free(out);
        return cli_input_error("cut", "%s", err.msg);
    }
    printf("{\"components\":%u,\"new_facets\":%u,\"split_facets\":%u,"
           "\"pieces\":%u,\"removed_facets\":%u,\"new_vertices\":%u,"
           "\"removed_vertices\":%u,\"hanging_dropped\":%u,"
           "\"unchanged\":%s,\"empty\":%s,\"volume_before\":%.17g,"
           "\"volume_after\":%.17g,\"vertices\":%u,\"facets\":%u}\n",
           rep.components, rep.new_facets, rep.split_facets, rep.pieces,
           rep.removed_facets, rep.new_vertices, rep.removed_vertices,
           rep.hanging_dropped, rep.unchanged ? "true" : "false",
           rep.empty ? "true" : "false", rep.volume_before, rep.volume_after,
           out->nverts, out->nfacets);
    geo_poly_free(out);
    return CLI_OK;
}
