/* cmd_triangulate.c — `facet triangulate OBJECT.json -o OUT ...`: reads a
 * frep-object/1 file, triangulates it (lib/frep/triangulate.h) on a thread
 * pool, writes the mesh in the format of OUT's extension
 * (proto/model_io.h) and the quality report as JSON (--metrics), and
 * prints a one-line summary. */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "cli_args.h"
#include "frep_json.h"
#include "model_io.h"
#include "parallel.h"
#include "tri_report_json.h"
#include "triangulate.h"

static const char USAGE[] =
    "usage: facet triangulate OBJECT.json -o OUT [options]\n"
    "\n"
    "Triangulates a functionally defined object (frep-object/1) and writes\n"
    "a closed triangle mesh; the format comes from OUT's extension\n"
    "(.obj .stl .ply .ase .json .poly) or --to.\n"
    "  --quad-levels N    quadtree levels over the projection plane, 1..11\n"
    "                     (default 9: 512 x 512 rays)\n"
    "  --binary-levels N  binary levels along each ray, 1..20 (default 10)\n"
    "  --fill area|edges  hole patches of least area (default) or least\n"
    "                     total edge length\n"
    "  --no-refine        keep the patches as triangulated\n"
    "  --fair uniform|length|none  fairing of refined patches (default\n"
    "                     uniform)\n"
    "  --no-sharpen       do not recover creases of unions/intersections\n"
    "  --threads N        threads (default: all processors)\n"
    "  --metrics FILE     write the quality report as JSON ('-': stdout)\n"
    "  --to FMT           output format (json, poly, obj, stl, stl-ascii,\n"
    "                     ply, ply-ascii, ase)\n"
    "\n"
    "exit status: 0 success, 1 bad input (the error names file and place),\n"
    "2 usage error\n";

static int parse_long(const char *opt, const char *s, long lo, long hi,
                      long *ret)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || end == s || *end || v < lo || v > hi)
        return cli_usage_error("triangulate", "%s: expected a number %ld..%ld,"
                                              " got '%s'",
                               opt, lo, hi, s);
    *ret = v;
    return CLI_OK;
}

static int write_metrics(const char *path, const geo_tri_report *rep)
{
    json_t *j = proto_tri_report_to_json(rep);
    if (!j)
        return cli_input_error("triangulate", "out of memory");
    int rc;
    if (strcmp(path, "-") == 0) {
        rc = json_dumpf(j, stdout, JSON_INDENT(2) | JSON_PRESERVE_ORDER);
        if (rc == 0 && (fputc('\n', stdout) == EOF || fflush(stdout) == EOF))
            rc = -1;
    } else {
        rc = json_dump_file(j, path, JSON_INDENT(2) | JSON_PRESERVE_ORDER);
    }
    json_decref(j);
    if (rc != 0)
        return cli_input_error("triangulate", "%s: cannot write the report",
                               path);
    return CLI_OK;
}

int cmd_triangulate(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        fputs(USAGE, stdout);
        return CLI_OK;
    }
    const char *in = NULL, *out = NULL, *metrics = NULL;
    long threads = 0, v;
    proto_format to = PROTO_FMT_UNKNOWN;
    geo_tri_opts o;
    geo_tri_opts_default(&o);
    enum { O_OUT, O_QLEV, O_BLEV, O_FILL, O_FAIR, O_THREADS, O_METRICS,
           O_TO, O_NO_REFINE, O_NO_SHARPEN };
    static const cli_opt opts[] = {
        {"-o", O_OUT, true},                {"--output", O_OUT, true},
        {"--quad-levels", O_QLEV, true},    {"--binary-levels", O_BLEV, true},
        {"--fill", O_FILL, true},           {"--fair", O_FAIR, true},
        {"--threads", O_THREADS, true},     {"--metrics", O_METRICS, true},
        {"--to", O_TO, true},               {"--no-refine", O_NO_REFINE, false},
        {"--no-sharpen", O_NO_SHARPEN, false},
        {NULL, 0, false},
    };
    cli_args args;
    const char *val;
    cli_args_init(&args, "triangulate", argc, argv, opts);
    cli_args_positionals(&args, &in, 1);
    for (int k; (k = cli_args_next(&args, &val)) != CLI_ARGS_END;) {
        const char *a = args.opt;
        int r = CLI_OK;
        switch (k) {
        case O_OUT: out = val; break;
        case O_QLEV:
            if ((r = parse_long(a, val, 1, GEO_FREP_MAX_QLEV, &v)) == CLI_OK)
                o.quad_levels = (uint32_t)v;
            break;
        case O_BLEV:
            if ((r = parse_long(a, val, 1, GEO_FREP_MAX_BLEV, &v)) == CLI_OK)
                o.binary_levels = (uint32_t)v;
            break;
        case O_FILL:
            if (strcmp(val, "area") == 0)
                o.fill = GEO_FILL_AREA;
            else if (strcmp(val, "edges") == 0)
                o.fill = GEO_FILL_EDGES;
            else
                r = cli_usage_error("triangulate", "--fill: expected area or "
                                                   "edges, got '%s'", val);
            break;
        case O_FAIR:
            if (strcmp(val, "uniform") == 0)
                o.fair = GEO_FAIR_UNIFORM;
            else if (strcmp(val, "length") == 0)
                o.fair = GEO_FAIR_LENGTH;
            else if (strcmp(val, "none") == 0)
                o.fair = GEO_FAIR_NONE;
            else
                r = cli_usage_error("triangulate", "--fair: expected uniform, "
                                                   "length or none, got '%s'",
                                    val);
            break;
        case O_THREADS: r = parse_long(a, val, 0, 1024, &threads); break;
        case O_METRICS: metrics = val; break;
        case O_TO:
            if ((to = proto_format_from_name(val)) == PROTO_FMT_UNKNOWN)
                r = cli_usage_error("triangulate", "--to: unknown format '%s'",
                                    val);
            break;
        case O_NO_REFINE: o.refine = false; break;
        case O_NO_SHARPEN: o.sharpen = false; break;
        default: r = CLI_USAGE;
        }
        if (r != CLI_OK)
            return r;
    }
    if (!in)
        return cli_usage_error("triangulate", "needs an object file");
    if (!out)
        return cli_usage_error("triangulate", "needs -o OUT");
    if (to == PROTO_FMT_UNKNOWN &&
        proto_format_from_path(out) == PROTO_FMT_UNKNOWN)
        return cli_usage_error("triangulate", "%s: unknown output format; "
                                              "use --to", out);

    geo_err err = {{0}};
    geo_frep *f = proto_frep_read_file(in, NULL, &err);
    if (!f)
        return cli_input_error("triangulate", "%s", err.msg);
    par_pool *pool = par_pool_new((int)threads);
    if (!pool) {
        geo_frep_free(f);
        return cli_input_error("triangulate", "cannot start threads");
    }
    geo_ctx ctx = {.parallel_for = par_for, .pf_user = pool};
    geo_poly *m = NULL;
    geo_tri_report rep;
    int rc = geo_triangulate(f, &o, &ctx, &m, &rep, &err);
    par_pool_free(pool);
    geo_frep_free(f);
    if (rc < 0)
        return cli_input_error("triangulate", "%s: %s", in, err.msg);
    int status = CLI_OK;
    if (proto_model_write_file(m, out, to, &err) < 0)
        status = cli_input_error("triangulate", "%s", err.msg);
    if (status == CLI_OK && metrics)
        status = write_metrics(metrics, &rep);
    if (status == CLI_OK && rep.empty &&
        !(metrics && strcmp(metrics, "-") == 0))
        printf("empty: no part of the object is thicker than a voxel at "
               "these levels (%g × %g × %g); wrote an empty model\n",
               rep.voxel[0], rep.voxel[1], rep.voxel[2]);
    else if (status == CLI_OK && !(metrics && strcmp(metrics, "-") == 0))
        printf("%u triangles, %u vertices; holes %u filled, %u open; max "
               "deviation %.3g; %lld self-intersections; %.3f s\n",
               rep.quality.nfacets, rep.quality.nverts, rep.fill.nfilled,
               rep.fill.nopen, rep.quality.dev_max,
               (long long)rep.self_intersections, rep.t_total);
    geo_tri_report_clear(&rep);
    geo_poly_free(m);
    return status;
}
