/* cmd_collapse.c — `facet collapse MODEL -o OUT [--radius MM]`: collapses
 * the clusters of vertices joined by very short edges into one vertex each
 * (lib/correct/clusters.h), the pipeline op `collapse` on a file. */
#include <stdio.h>

#include <jansson.h>

#include "cli.h"
#include "cli_args.h"
#include "clusters.h"
#include "correct_json.h"
#include "model_io.h"

static const char USAGE[] =
    "usage: facet collapse MODEL -o OUT [--radius MM] [--report FILE]\n"
    "       [--from FMT] [--to FMT]\n"
    "\n"
    "Collapses each cluster of vertices joined by edges shorter than the\n"
    "radius into one vertex at the point nearest the planes around it, then\n"
    "re-planarizes the facets (Palachev 2012, §4.1). A cluster whose\n"
    "collapse would leave the model invalid is rolled back; the result is\n"
    "always a valid polyhedron.\n"
    "\n"
    "  --radius MM        default 2e-4 of the model's size\n"
    "  --report FILE      write the full report (clusters, vertex map) as JSON\n"
    "  --from, --to FMT   formats of MODEL and OUT (default: from the names)\n"
    "  -o, --output OUT   the result\n"
    "\n"
    "Prints one line of JSON: radius, clusters, collapsed, rolled_back,\n"
    "vertices and facets before and after, max_displacement.\n"
    "exit status: 0 written, 1 bad input, 2 usage error\n";

enum { O_OUT, O_RADIUS, O_REPORT, O_FROM, O_TO };
static const cli_opt opts[] = {
    {"-o", O_OUT, true},          {"--output", O_OUT, true},
    {"--radius", O_RADIUS, true}, {"--report", O_REPORT, true},
    {"--from", O_FROM, true},     {"--to", O_TO, true},
    {NULL, 0, false},
};

int cmd_collapse(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        fputs(USAGE, stdout);
        return CLI_OK;
    }
    const char *in = NULL, *out = NULL, *report = NULL, *val;
    proto_format from = PROTO_FMT_UNKNOWN, to = PROTO_FMT_UNKNOWN;
    geo_collapse_opts o;
    geo_collapse_opts_default(&o);
    cli_args a;
    cli_args_init(&a, "collapse", argc, argv, opts);
    cli_args_positionals(&a, &in, 1);
    for (int k; (k = cli_args_next(&a, &val)) != CLI_ARGS_END;) {
        int r = 0;
        switch (k) {
        case O_OUT: out = val; break;
        case O_REPORT: report = val; break;
        case O_RADIUS: r = cli_args_double(&a, val, 0, 1e9, true, &o.radius);
            break;
        case O_FROM: r = cli_args_format(&a, val, &from); break;
        case O_TO: r = cli_args_format(&a, val, &to); break;
        default: r = CLI_ARGS_ERROR;
        }
        if (r)
            return CLI_USAGE;
    }
    if (!in || !out)
        return cli_usage_error("collapse", "needs a model file and -o OUT");
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(in, from, NULL, &err);
    if (!p)
        return cli_input_error("collapse", "%s", err.msg);
    geo_collapse_report rep;
    int rc = geo_collapse(p, &o, NULL, &rep, &err);
    if (rc < 0) {
        geo_poly_free(p);
        return cli_input_error("collapse", "%s: %s", in, err.msg);
    }
    rc = proto_model_write_file(p, out, to, &err);
    geo_poly_free(p);
    json_t *j = rc < 0 ? NULL : proto_collapse_report_to_json(&rep);
    json_t *line = j ? json_pack("{s:O, s:O, s:O, s:O, s:i, s:i, s:i, s:i, "
                                 "s:f}", "radius", json_object_get(j, "radius"),
                                 "clusters", json_object_get(j, "clusters"),
                                 "collapsed", json_object_get(j, "collapsed"),
                                 "rolled_back",
                                 json_object_get(j, "rolled_back"),
                                 "vertices_before", (int)rep.vertices_before,
                                 "vertices_after", (int)rep.vertices_after,
                                 "facets_before", (int)rep.facets_before,
                                 "facets_after", (int)rep.facets_after,
                                 "max_displacement", rep.max_displacement)
                     : NULL;
    geo_collapse_report_clear(&rep);
    if (rc < 0) {
        json_decref(j);
        return cli_input_error("collapse", "%s", err.msg);
    }
    if (!line) {
        json_decref(j);
        return cli_input_error("collapse", "out of memory");
    }
    int bad = report && json_dump_file(j, report, JSON_INDENT(2) |
                                                  JSON_PRESERVE_ORDER) < 0;
    json_decref(j);
    if (bad) {
        json_decref(line);
        return cli_input_error("collapse", "%s: cannot write the report",
                               report);
    }
    json_dumpf(line, stdout, JSON_COMPACT | JSON_PRESERVE_ORDER);
    json_decref(line);
    if (fputc('\n', stdout) == EOF || fflush(stdout) == EOF)
        return cli_input_error("collapse", "cannot write the output");
    return CLI_OK;
}
