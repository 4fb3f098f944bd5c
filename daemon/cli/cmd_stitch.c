/* cmd_stitch.c — `facet stitch A B -o OUT [--report FILE]
 * [--keep-invalid]`: joins two open meshes into one closed mesh
 * (lib/mesh/stitch.h, Nesterenko), writes it, prints a one-line JSON
 * summary and, with --report, the whole report (the loops and vertices
 * chosen, the bridge, the openings closed, the validity of the result
 * with the reasons when it is not valid, the time). A result that is not
 * a valid closed solid exits 1 with the reasons and is not written
 * (unless --keep-invalid, for inspection). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "cli_args.h"
#include "fill_json.h"
#include "model_io.h"
#include "stats.h"
#include "stitch.h"

static const char USAGE[] =
    "usage: facet stitch A B -o OUT [--report FILE] [--keep-invalid]\n"
    "\n"
    "Joins the open meshes A and B (Nesterenko): the free-edge loops of the\n"
    "two with the closest centres are joined by the facet planes along them\n"
    "extended across the gap and intersected (planar loops of a pair convex\n"
    "about the gap), or else bridged by a mesh of meridians between the\n"
    "vertices facing each other, divided to the meshes' edge length;\n"
    "B is turned over when its orientation disagrees with A's; openings left\n"
    "are closed by hole filling (see 'facet fill --help').\n"
    "\n"
    "  -o, --output OUT  the result (format from the extension)\n"
    "  --report FILE     write the full JSON report to FILE\n"
    "  --keep-invalid    write OUT even when the result is not valid (the\n"
    "                    exit status is still 1)\n"
    "\n"
    "Prints one line of JSON: method (planes, band or weld), band (loops\n"
    "joined whole), flipped, meridians,\n"
    "rows, band_vertices, band_facets, welded (loop vertices joined where\n"
    "the loops coincide), openings_filled, left_open, valid,\n"
    "vertices, facets, ms. exit status: 0 OUT written and valid, 1 bad\n"
    "input (also meshes without free edges) or a result that is not a\n"
    "valid closed solid (the reasons on stderr; OUT not written unless\n"
    "--keep-invalid), 2 usage error\n";

int cmd_stitch(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        fputs(USAGE, stdout);
        return CLI_OK;
    }
    const char *in[2] = {NULL, NULL}, *outpath = NULL, *report = NULL;
    bool keep_invalid = false;
    enum { O_OUT, O_REPORT, O_KEEP_INVALID };
    static const cli_opt opts[] = {
        {"-o", O_OUT, true},           {"--output", O_OUT, true},
        {"--report", O_REPORT, true},  {"--keep-invalid", O_KEEP_INVALID, false},
        {NULL, 0, false},
    };
    cli_args a;
    const char *v;
    cli_args_init(&a, "stitch", argc, argv, opts);
    cli_args_positionals(&a, in, 2);
    for (int k; (k = cli_args_next(&a, &v)) != CLI_ARGS_END;) {
        int r = 0;
        switch (k) {
        case O_OUT: outpath = v; break;
        case O_REPORT: report = v; break;
        case O_KEEP_INVALID: keep_invalid = true; break;
        default: r = CLI_ARGS_ERROR;
        }
        if (r)
            return CLI_USAGE;
    }
    if (!in[1])
        return cli_usage_error("stitch", "needs two model files");
    if (cli_args_output(&a, outpath) != CLI_OK)
        return CLI_USAGE;
    geo_err err = {{0}};
    geo_poly *m[2] = {NULL, NULL}, *out = NULL;
    json_t *sj = NULL, *vj = NULL, *doc = NULL;
    int rc = CLI_OK;
    for (int k = 0; k < 2; k++)
        if (!(m[k] = proto_model_read_file(in[k], PROTO_FMT_UNKNOWN, NULL,
                                           &err))) {
            rc = cli_input_error("stitch", "%s", err.msg);
            goto out;
        }
    if (!(out = geo_poly_new())) {
        rc = cli_input_error("stitch", "out of memory");
        goto out;
    }
    geo_stitch_report rep;
    double t0 = cli_mono_ms();
    int r = geo_stitch(m[0], m[1], NULL, NULL, out, &rep, &err);
    double ms = cli_mono_ms() - t0;
    if (r < 0) {
        rc = cli_input_error("stitch", "%s, %s: %s", in[0], in[1], err.msg);
        goto out;
    }
    geo_stats st;
    if (geo_inspect(out, NULL, NULL, &st, &err) < 0) {
        rc = cli_input_error("stitch", "inspecting the result: %s", err.msg);
        geo_stitch_report_clear(&rep);
        goto out;
    }
    sj = proto_stitch_report_to_json(&rep);
    vj = proto_validity_to_json(&st);
    doc = sj && vj ? json_pack("{s:O, s:O, s:f}", "stitch", sj, "result", vj,
                               "ms", ms)
                   : NULL;
    if (doc && !st.valid) {
        json_t *why = json_object_get(vj, "reasons");
        char *text = why ? json_dumps(why, JSON_COMPACT) : NULL;
        rc = cli_input_error("stitch", "%s, %s: the result is not a valid "
                             "closed solid%s: %s", in[0], in[1],
                             keep_invalid ? " (written anyway)"
                                          : ", not written",
                             text ? text : "[]");
        free(text);
    }
    if (!doc) {
        rc = cli_input_error("stitch", "out of memory");
    } else if ((st.valid || keep_invalid) &&
               proto_model_write_file(out, outpath, PROTO_FMT_UNKNOWN,
                                      &err) < 0) {
        rc = cli_input_error("stitch", "%s", err.msg);
    } else if (report && json_dump_file(doc, report, JSON_INDENT(2)) < 0) {
        rc = cli_input_error("stitch", "%s: cannot write the report: %s",
                             report, strerror(errno));
    } else {
        printf("{\"method\":\"%s\",\"band\":%s,\"flipped\":%s,\"meridians\":%u,\"rows\":%u,"
               "\"band_vertices\":%u,\"band_facets\":%u,\"welded\":%u,"
               "\"openings_filled\":%u,\"left_open\":%u,\"valid\":%s,"
               "\"vertices\":%u,\"facets\":%u,\"ms\":%.3f}\n",
               geo_stitch_method_name(rep.method), rep.band ? "true" : "false",
               rep.flipped2 ? "true" : "false",
               rep.meridians, rep.rows, rep.band_vertices, rep.band_facets,
               rep.welded, rep.fill.nfilled, rep.fill.nopen, st.valid ? "true" : "false",
               out->nverts, out->nfacets, ms);
    }
    geo_stats_clear(&st);
    geo_stitch_report_clear(&rep);
out:
    json_decref(sj);
    json_decref(vj);
    json_decref(doc);
    geo_poly_free(m[0]);
    geo_poly_free(m[1]);
    geo_poly_free(out);
    return rc;
}
