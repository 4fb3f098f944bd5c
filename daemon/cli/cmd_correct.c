/* cmd_correct.c — `facet correct MODEL -o OUT [--report FILE]`: the
 * automatic post-scan correction (lib/correct/correct.h: merge the slivers of
 * each true facet, collapse vertex clusters), the same call the daemon's
 * "auto" pipeline makes, so both give the same model. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "cli.h"
#include "correct.h"
#include "correct_json.h"
#include "model_io.h"

static const char USAGE[] =
    "usage: facet correct MODEL -o OUT [--report FILE] [options]\n"
    "\n"
    "Corrects a scanned model: merges the groups of nearly coplanar facets\n"
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
    "\n"
    "Prints one line of JSON: vertices and facets before and after,\n"
    "groups_merged, groups_failed, clusters_collapsed, views and noise (mm)\n"
    "the automatic groups used, hausdorff (mm),\n"
    "volume_before, volume_after, valid.\n"
    "exit status: 0 success, 1 bad input (e.g. a model that is not closed),\n"
    "2 usage error\n";

static int parse_number(const char *s, double hi, double *ret)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end || errno || !isfinite(v) || v <= 0 || v > hi)
        return -1;
    *ret = v;
    return 0;
}

int cmd_correct(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        fputs(USAGE, stdout);
        return CLI_OK;
    }
    const char *in = NULL, *outpath = NULL, *report = NULL;
    geo_correct_opts o;
    geo_correct_opts_default(&o);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--no-collapse") == 0) {
            o.collapse_clusters = false;
        } else if (strcmp(a, "-o") == 0 || strcmp(a, "--output") == 0 ||
                   strcmp(a, "--report") == 0 || strcmp(a, "--max-angle") == 0 ||
                   strcmp(a, "--max-deviation") == 0 ||
                   strcmp(a, "--views") == 0 || strcmp(a, "--noise") == 0 ||
                   strcmp(a, "--radius") == 0) {
            if (i + 1 == argc)
                return cli_usage_error("correct", "%s needs a value", a);
            const char *v = argv[++i];
            if (strcmp(a, "--report") == 0)
                report = v;
            else if (strcmp(a, "--max-angle") == 0) {
                if (parse_number(v, 89.999, &o.merge.max_angle_deg) < 0)
                    return cli_usage_error("correct", "--max-angle: expected "
                                           "degrees in (0, 90), got '%s'", v);
            } else if (strcmp(a, "--max-deviation") == 0) {
                if (parse_number(v, 1e9, &o.merge.max_deviation) < 0)
                    return cli_usage_error("correct", "--max-deviation: "
                                           "expected a positive length in mm, "
                                           "got '%s'", v);
            } else if (strcmp(a, "--views") == 0) {
                double k;
                if (parse_number(v, 1e5, &k) < 0 || k != floor(k) || k < 2)
                    return cli_usage_error("correct", "--views: expected a "
                                           "whole number of views, got '%s'", v);
                o.merge.views = (uint32_t)k;
            } else if (strcmp(a, "--noise") == 0) {
                if (parse_number(v, 1e9, &o.merge.noise) < 0)
                    return cli_usage_error("correct", "--noise: expected a "
                                           "positive length in mm, got '%s'", v);
            } else if (strcmp(a, "--radius") == 0) {
                if (parse_number(v, 1e9, &o.collapse.radius) < 0)
                    return cli_usage_error("correct", "--radius: expected a "
                                           "positive length in mm, got '%s'", v);
            } else {
                outpath = v;
            }
        } else if (a[0] == '-' && a[1] != '\0') {
            return cli_usage_error("correct", "unknown option '%s'", a);
        } else if (!in) {
            in = a;
        } else {
            return cli_usage_error("correct", "unexpected argument '%s'", a);
        }
    }
    if (!in)
        return cli_usage_error("correct", "needs a model file");
    if (!outpath)
        return cli_usage_error("correct", "needs -o OUT");
    if (proto_format_from_path(outpath) == PROTO_FMT_UNKNOWN)
        return cli_usage_error("correct", "%s: cannot tell the format from "
                               "the name", outpath);

    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(in, PROTO_FMT_UNKNOWN, NULL, &err);
    if (!p)
        return cli_input_error("correct", "%s", err.msg);
    geo_correct_report rep;
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
