/* cmd_report.c — `facet report MODEL [--gear N] [--axis X,Y,Z] [--scan
 * RAW]`: the stone's tiers, proportions and facet table as JSON, with
 * each facet's deviation from the raw scan when given (lib/gem/report.h,
 * docs/kernels/report.md). */
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "cli_args.h"
#include "model_io.h"
#include "report.h"
#include "report_json.h"

static const char USAGE[] =
    "usage: facet report MODEL [--gear N] [--axis X,Y,Z] [--scan RAW]\n"
    "\n"
    "Prints the stone's proportions as JSON: table %, diameters, depths,\n"
    "girdle thickness, crown and pavilion angles (the mains' mean and\n"
    "spread), and one entry per facet (tier, inclination, azimuth, gear\n"
    "index, distance from the axis point, area). The table is the largest\n"
    "facet whose normal lies within 10 degrees of the axis (+z unless\n"
    "--axis is given).\n"
    "  --gear N      teeth of the index gear (default 96)\n"
    "  --axis X,Y,Z  the main axis; also reports a model without a table\n"
    "  --scan RAW    the raw scan MODEL was corrected from: each facet also\n"
    "                gets scan_deviation_um {max, rms}, how far the scan's\n"
    "                surface lies from it (null: no part of the scan is\n"
    "                nearest to it)\n"
    "\n"
    "exit status: 0 success, 1 bad input (the error names file and place),\n"
    "2 usage error\n";

static int parse_axis(const char *s, double v[3])
{
    char *end;
    for (int k = 0; k < 3; k++) {
        v[k] = strtod(s, &end);
        if (end == s || (k < 2 && *end != ',') || (k == 2 && *end))
            return -1;
        s = end + 1;
    }
    return 0;
}

int cmd_report(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        fputs(USAGE, stdout);
        return CLI_OK;
    }
    const char *path = NULL, *scan_path = NULL;
    long gear = 96;
    double axis[3];
    bool have_axis = false;
    enum { O_GEAR, O_AXIS, O_SCAN };
    static const cli_opt opts[] = {{"--gear", O_GEAR, true},
                                   {"--axis", O_AXIS, true},
                                   {"--scan", O_SCAN, true},
                                   {NULL, 0, false}};
    cli_args args;
    const char *val;
    cli_args_init(&args, "report", argc, argv, opts);
    for (int k; (k = cli_args_next(&args, &val)) != CLI_ARGS_END;) {
        int r = 0;
        switch (k) {
        case O_GEAR: r = cli_args_long(&args, val, 1, 100000, &gear); break;
        case O_AXIS:
            if (parse_axis(val, axis) < 0)
                r = cli_usage_error("report", "--axis: expected X,Y,Z, got "
                                    "'%s'", val);
            have_axis = true;
            break;
        case O_SCAN: scan_path = val; break;
        case CLI_ARGS_POSITIONAL:
            if (path)
                r = cli_args_unexpected(&args, val);
            path = val;
            break;
        default: r = CLI_ARGS_ERROR;
        }
        if (r != 0)
            return CLI_USAGE;
    }
    if (!path)
        return cli_usage_error("report", "needs a model");
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(path, PROTO_FMT_UNKNOWN, NULL, &err);
    if (!p)
        return cli_input_error("report", "%s", err.msg);
    geo_poly *scan = NULL;
    if (scan_path &&
        !(scan = proto_model_read_file(scan_path, PROTO_FMT_UNKNOWN, NULL,
                                       &err))) {
        geo_poly_free(p);
        return cli_input_error("report", "%s", err.msg);
    }
    geo_report r;
    int e = geo_report_compute(p, have_axis ? axis : NULL, (uint32_t)gear,
                               &r, &err);
    if (e < 0) {
        geo_poly_free(p);
        geo_poly_free(scan);
        return cli_input_error("report", "%s: %s", path, err.msg);
    }
    if (scan && (e = geo_report_scan_deviation(&r, p, scan, &err)) < 0) {
        geo_report_free(&r);
        geo_poly_free(p);
        geo_poly_free(scan);
        return cli_input_error("report", "%s: %s", scan_path, err.msg);
    }
    geo_poly_free(p);
    geo_poly_free(scan);
    json_t *j = proto_report_to_json(&r);
    geo_report_free(&r);
    return cli_print_json("report", j, JSON_INDENT(2) | JSON_PRESERVE_ORDER);
}
