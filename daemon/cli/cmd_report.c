/* cmd_report.c — `facet report MODEL [--gear N] [--axis X,Y,Z]`: the
 * stone's tiers, proportions and facet table as JSON (lib/gem/report.h,
 * docs/kernels/report.md). */
#include <errno.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "model_io.h"
#include "report.h"

static const char USAGE[] =
    "usage: facet report MODEL [--gear N] [--axis X,Y,Z]\n"
    "\n"
    "Prints the stone's proportions as JSON: table %, diameters, depths,\n"
    "girdle thickness, crown and pavilion angles (the mains' mean and\n"
    "spread), and one entry per facet (tier, inclination, azimuth, gear\n"
    "index, distance from the axis point, area). The table is the largest\n"
    "facet whose normal lies within 10 degrees of the axis (+z unless\n"
    "--axis is given).\n"
    "  --gear N      teeth of the index gear (default 96)\n"
    "  --axis X,Y,Z  the main axis; also reports a model without a table\n"
    "\n"
    "exit status: 0 success, 1 bad input (the error names file and place),\n"
    "2 usage error\n";

static json_t *range(const geo_range *r)
{
    return json_pack("{s:f, s:f, s:f}", "min", r->min, "max", r->max, "mean",
                     r->mean);
}

static json_t *vec3(const double v[3])
{
    return json_pack("[f, f, f]", v[0], v[1], v[2]);
}

json_t *cli_report_json(const geo_report *r);

json_t *cli_report_json(const geo_report *r)
{
    json_t *facets = json_array();
    for (uint32_t f = 0; f < r->nfacets; f++) {
        const geo_report_facet *F = &r->facets[f];
        json_array_append_new(
            facets, json_pack("{s:s, s:f, s:f, s:f, s:f, s:f}", "tier",
                              geo_tier_name(F->tier), "inclination_deg",
                              F->inclination_deg, "azimuth_deg",
                              F->azimuth_deg, "index", F->index,
                              "distance_mm", F->distance_mm, "area_mm2",
                              F->area_mm2));
    }
    json_t *tiers = json_object();
    for (int t = 0; t < 5; t++)
        json_object_set_new(tiers, geo_tier_name((enum geo_tier)t),
                            json_integer(r->tier_count[t]));
    json_t *o = json_object();
    json_object_set_new(o, "table", json_boolean(r->has_table));
    json_object_set_new(o, "axis", vec3(r->axis));
    json_object_set_new(o, "axis_point", vec3(r->center));
    json_object_set_new(o, "table_percent", json_real(r->table_percent));
    json_object_set_new(o, "diameter_mm", range(&r->diameter_mm));
    json_object_set_new(o, "length_mm", json_real(r->length_mm));
    json_object_set_new(o, "width_mm", json_real(r->width_mm));
    json_object_set_new(o, "length_to_width", json_real(r->length_to_width));
    json_object_set_new(o, "total_depth_percent",
                        json_real(r->total_depth_percent));
    json_object_set_new(o, "crown_height_percent",
                        json_real(r->crown_height_percent));
    json_object_set_new(o, "pavilion_depth_percent",
                        json_real(r->pavilion_depth_percent));
    json_object_set_new(o, "girdle_thickness_percent",
                        range(&r->girdle_thickness_percent));
    json_object_set_new(o, "culet_percent", json_real(r->culet_percent));
    json_object_set_new(o, "crown_angle_deg", json_real(r->crown_angle_deg.mean));
    json_object_set_new(o, "crown_angle_spread_deg",
                        json_pack("{s:f, s:f}", "min", r->crown_angle_deg.min,
                                  "max", r->crown_angle_deg.max));
    json_object_set_new(o, "crown_mains", json_integer(r->crown_mains));
    json_object_set_new(o, "pavilion_angle_deg",
                        json_real(r->pavilion_angle_deg.mean));
    json_object_set_new(o, "pavilion_angle_spread_deg",
                        json_pack("{s:f, s:f}", "min",
                                  r->pavilion_angle_deg.min, "max",
                                  r->pavilion_angle_deg.max));
    json_object_set_new(o, "pavilion_mains", json_integer(r->pavilion_mains));
    json_object_set_new(o, "tiers", tiers);
    json_object_set_new(o, "facets", facets);
    return o;
}

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
    const char *path = NULL;
    unsigned long gear = 96;
    double axis[3];
    bool have_axis = false;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--gear") == 0) {
            char *end;
            if (i + 1 == argc)
                return cli_usage_error("report", "--gear needs N");
            errno = 0;
            gear = strtoul(argv[++i], &end, 10);
            if (errno || *end || gear == 0 || gear > 100000)
                return cli_usage_error("report", "--gear: '%s' is not a "
                                       "number of teeth 1..100000", argv[i]);
        } else if (strcmp(a, "--axis") == 0) {
            if (i + 1 == argc || parse_axis(argv[++i], axis) < 0)
                return cli_usage_error("report", "--axis needs X,Y,Z");
            have_axis = true;
        } else if (a[0] == '-' && a[1] != '\0') {
            return cli_usage_error("report", "unknown option '%s'", a);
        } else if (!path) {
            path = a;
        } else {
            return cli_usage_error("report", "unexpected argument '%s'", a);
        }
    }
    if (!path)
        return cli_usage_error("report", "needs a model");
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(path, PROTO_FMT_UNKNOWN, NULL, &err);
    if (!p)
        return cli_input_error("report", "%s", err.msg);
    geo_report r;
    int e = geo_report_compute(p, have_axis ? axis : NULL, (uint32_t)gear,
                               &r, &err);
    geo_poly_free(p);
    if (e < 0)
        return cli_input_error("report", "%s: %s", path, err.msg);
    json_t *j = cli_report_json(&r);
    geo_report_free(&r);
    int wr = json_dumpf(j, stdout, JSON_INDENT(2) | JSON_PRESERVE_ORDER);
    json_decref(j);
    if (wr < 0 || fputc('\n', stdout) == EOF)
        return cli_input_error("report", "cannot write the output");
    return CLI_OK;
}
