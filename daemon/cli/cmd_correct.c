/* cmd_correct.c — `facet correct MODEL -o OUT [--report FILE]`: the
 * automatic post-scan correction (lib/correct/correct.h: a convex scan
 * rebuilt from its recovered planes, else the slivers of each true facet
 * merged and vertex clusters collapsed), the same call the daemon's "auto"
 * pipeline makes, so both give the same model. */
#include <math.h>
#include <stdio.h>

#include <jansson.h>

#include "cli.h"
#include "cli_args.h"
#include "correct.h"
#include "correct_json.h"
#include "model_io.h"

static const char USAGE[] =
    "usage: facet correct MODEL -o OUT [--report FILE] [options]\n"
    "\n"
    "Corrects a scanned model. A convex scan is rebuilt as the intersection\n"
    "of its true facets' planes, recovered from the slivers of each; else\n"
    "(and with --no-convex) it merges the groups of nearly coplanar facets\n"
    "a shadow-profile scanner makes of each true facet (Palachev 2012, §2) and\n"
    "collapses the clusters of vertices joined by very short edges (§4.1),\n"
    "repeating both until nothing changes; every step is checked and\n"
    "nothing invalid is written. Same as the daemon's \"auto\" pipeline.\n"
    "\n"
    "  -o, --output OUT     the corrected model\n"
    "  --report FILE        the full report as JSON (groups, clusters, moved\n"
    "                       vertices, Hausdorff estimate, statistics before\n"
    "                       and after)\n"
    "  --max-angle DEG      merge: default 60\n"
    "  --max-deviation D    merge: mm; default 5e-4 of the model's size\n"
    "  --views K            merge: the scanner's views over 180°; default read\n"
    "                       off the scan's facet normals\n"
    "  --noise D            merge: the scan's surface noise, mm; default\n"
    "                       measured on the scan\n"
    "  --radius R           clusters: mm; default 2e-4 of the model's size\n"
    "  --no-collapse        do not collapse clusters\n"
    "  --convex             a convex scan is rebuilt as the intersection of its\n"
    "                       recovered facet planes, the merge its fallback and\n"
    "                       the path of a non-convex scan (the default)\n"
    "  --no-convex          the merge rounds alone\n"
    "\n"
    "Prints one line of JSON: vertices and facets before and after,\n"
    "groups_merged, groups_failed, clusters_collapsed, views and noise (mm)\n"
    "the automatic groups used, hausdorff (mm),\n"
    "volume_before, volume_after, valid.\n"
    "exit status: 0 success, 1 bad input (e.g. a model that is not closed),\n"
    "2 usage error\n";

int cmd_correct(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        fputs(USAGE, stdout);
        return CLI_OK;
    }
    const char *in = NULL, *outpath = NULL, *report = NULL;
    geo_correct_opts o;
    geo_correct_opts_default(&o);
    enum { O_OUT, O_REPORT, O_ANGLE, O_DEV, O_VIEWS, O_NOISE, O_RADIUS,
           O_NO_COLLAPSE, O_CONVEX, O_NO_CONVEX };
    static const cli_opt opts[] = {
        {"-o", O_OUT, true},              {"--output", O_OUT, true},
        {"--report", O_REPORT, true},     {"--max-angle", O_ANGLE, true},
        {"--max-deviation", O_DEV, true}, {"--views", O_VIEWS, true},
        {"--noise", O_NOISE, true},       {"--radius", O_RADIUS, true},
        {"--no-collapse", O_NO_COLLAPSE, false},
        {"--convex", O_CONVEX, false},
        {"--no-convex", O_NO_CONVEX, false}, {NULL, 0, false},
    };
    static const char LENGTH[] = "a positive length in mm";
    static const char VIEWS[] = "a whole number of views";
    cli_args a;
    const char *v;
    cli_args_init(&a, "correct", argc, argv, opts);
    cli_args_positionals(&a, &in, 1);
    for (int k; (k = cli_args_next(&a, &v)) != CLI_ARGS_END;) {
        int r = 0;
        double views;
        switch (k) {
        case O_OUT: outpath = v; break;
        case O_REPORT: report = v; break;
        case O_ANGLE:
            r = cli_args_positive(&a, v, 89.999, "degrees in (0, 90)",
                                  &o.merge.max_angle_deg);
            break;
        case O_DEV:
            r = cli_args_positive(&a, v, 1e9, LENGTH, &o.merge.max_deviation);
            break;
        case O_VIEWS:
            r = cli_args_positive(&a, v, 1e5, VIEWS, &views);
            if (r == 0 && (views != floor(views) || views < 2))
                r = cli_args_invalid(&a, v, VIEWS);
            if (r == 0)
                o.merge.views = (uint32_t)views;
            break;
        case O_NOISE:
            r = cli_args_positive(&a, v, 1e9, LENGTH, &o.merge.noise);
            break;
        case O_RADIUS:
            r = cli_args_positive(&a, v, 1e9, LENGTH, &o.collapse.radius);
            break;
        case O_NO_COLLAPSE: o.collapse_clusters = false; break;
        case O_CONVEX: o.convex = true; break;
        case O_NO_CONVEX: o.convex = false; break;
        default: r = CLI_ARGS_ERROR;
        }
        if (r)
            return CLI_USAGE;
    }
    if (!in)
        return cli_usage_error("correct", "needs a model file");
    if (cli_args_output(&a, outpath) != CLI_OK)
        return CLI_USAGE;

    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(in, PROTO_FMT_UNKNOWN, NULL, &err);
    if (!p)
        return cli_input_error("correct", "%s", err.msg);
    geo_correct_report rep;
    o.input_stats = report != NULL; /* only the report prints them */
    int r = geo_correct(p, &o, NULL, &rep, &err);
    if (r < 0) {
        geo_poly_free(p);
        return cli_input_error("correct", "%s: %s", in, err.msg);
    }
    int rc = CLI_OK;
    if (proto_model_write_file(p, outpath, PROTO_FMT_UNKNOWN, &err) < 0)
        rc = cli_input_error("correct", "%s", err.msg);
    if (rc == CLI_OK && report) {
        json_t *j = proto_correct_report_to_json(&rep);
        if (!j || json_dump_file(j, report, JSON_INDENT(1)) < 0)
            rc = cli_input_error("correct", "%s: cannot write the report",
                                 report);
        json_decref(j);
    }
    printf("{\"vertices_before\":%u,\"facets_before\":%u,\"vertices_after\":%u,"
           "\"facets_after\":%u,\"groups_merged\":%u,\"groups_failed\":%u,"
           "\"clusters_collapsed\":%u,\"views\":%u,\"noise\":%.6g,"
           "\"hausdorff\":%.6g,\"volume_before\":%.17g,"
           "\"volume_after\":%.17g,\"valid\":%s}\n",
           rep.vertices_before, rep.facets_before, rep.vertices_after,
           rep.facets_after, rep.merge.merged, rep.merge.failed,
           rep.clusters_collapsed, rep.views, rep.noise, rep.hausdorff,
           rep.volume_before,
           rep.volume_after, rep.after.valid ? "true" : "false");
    geo_correct_report_clear(&rep);
    geo_poly_free(p);
    return rc;
}
