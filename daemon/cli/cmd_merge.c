/* cmd_merge.c — `facet merge MODEL (--groups "3,13,248,252;1,12" | --auto)
 * -o OUT`: merges groups of adjacent, nearly coplanar facets into one
 * facet each (lib/correct/merge.h), writes the result and prints a summary. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "cli.h"
#include "cli_args.h"
#include "correct_json.h"
#include "merge.h"
#include "model_io.h"

static const char USAGE[] =
    "usage: facet merge MODEL --groups \"F,F,...;F,F,...\" -o OUT [options]\n"
    "       facet merge MODEL --auto [--max-angle DEG] [--max-deviation D] -o OUT\n"
    "\n"
    "Merges each group of adjacent facets of MODEL into one facet (Palachev\n"
    "2012, §2: contour, least-squares plane, lifting of the points below it, cut\n"
    "by it) and writes OUT. Every merge is checked; a group that cannot be\n"
    "merged, or whose result would not be a valid polyhedron, is left as it\n"
    "was and named on stderr with the reason.\n"
    "\n"
    "  --groups LIST        groups of facet indices of MODEL: commas within a\n"
    "                       group, semicolons between groups\n"
    "  --auto               find the groups: adjacent facets within\n"
    "                       --max-angle of their common plane and with every\n"
    "                       vertex within --max-deviation of it\n"
    "  --max-angle DEG      default 60\n"
    "  --max-deviation D    mm; default 5e-4 of the model's size; for\n"
    "                       every group also how deep the merged plane\n"
    "                       may cut into the model\n"
    "  --plane contour|weighted|area   the plane fit (default area)\n"
    "  --report FILE        write the full report as JSON\n"
    "  -o, --output OUT     the result\n"
    "\n"
    "Prints one line of JSON: groups, merged, failed, rounds, vertices and\n"
    "facets before and after, volume_before, volume_after.\n"
    "exit status: 0 every group merged (or, with --auto, success), 1 bad\n"
    "input or a group not merged (OUT is still written with the others),\n"
    "2 usage error\n";

/* "1,2,3;4,5" into CSR arrays; -1 on a syntax error. */
static int parse_groups(const char *s, uint32_t *ret_n, uint32_t **ret_start,
                        uint32_t **ret_facets)
{
    size_t len = strlen(s), ng = 1;
    for (size_t i = 0; i < len; i++)
        ng += s[i] == ';';
    uint32_t *start = calloc(ng + 1, sizeof *start);
    uint32_t *facets = malloc((len / 2 + 2) * sizeof *facets);
    if (!start || !facets) {
        free(start), free(facets);
        return -1;
    }
    uint32_t g = 0, k = 0;
    const char *p = s;
    for (;;) {
        char *end;
        errno = 0;
        if (*p < '0' || *p > '9')
            goto bad;
        unsigned long v = strtoul(p, &end, 10);
        if (errno || v >= UINT32_MAX)
            goto bad;
        facets[k++] = (uint32_t)v;
        p = end;
        if (*p == ',') {
            p++;
        } else if (*p == ';' || *p == '\0') {
            if (k - start[g] < 2)
                goto bad;
            start[++g] = k;
            if (*p == '\0')
                break;
            p++;
        } else {
            goto bad;
        }
    }
    *ret_n = g;
    *ret_start = start;
    *ret_facets = facets;
    return 0;
bad:
    free(start), free(facets);
    return -1;
}

int cmd_merge(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        fputs(USAGE, stdout);
        return CLI_OK;
    }
    const char *in = NULL, *outpath = NULL, *groups = NULL, *report = NULL;
    bool automatic = false;
    geo_merge_opts o;
    geo_merge_opts_default(&o);
    enum { O_AUTO, O_GROUPS, O_OUT, O_ANGLE, O_DEV, O_REPORT, O_PLANE };
    static const cli_opt opts[] = {
        {"--auto", O_AUTO, false},        {"--groups", O_GROUPS, true},
        {"-o", O_OUT, true},              {"--output", O_OUT, true},
        {"--max-angle", O_ANGLE, true},   {"--max-deviation", O_DEV, true},
        {"--report", O_REPORT, true},     {"--plane", O_PLANE, true},
        {NULL, 0, false},
    };
    cli_args args;
    const char *v;
    cli_args_init(&args, "merge", argc, argv, opts);
    cli_args_positionals(&args, &in, 1);
    for (int k; (k = cli_args_next(&args, &v)) != CLI_ARGS_END;) {
        switch (k) {
        case O_AUTO: automatic = true; break;
        case O_GROUPS: groups = v; break;
        case O_REPORT: report = v; break;
        case O_OUT: outpath = v; break;
        case O_ANGLE:
            if (cli_args_positive(&args, v, 89.999, "degrees in (0, 90)",
                                  &o.max_angle_deg) < 0)
                return CLI_USAGE;
            break;
        case O_DEV:
            if (cli_args_positive(&args, v, 1e9, "a positive length in mm",
                                  &o.max_deviation) < 0)
                return CLI_USAGE;
            break;
        case O_PLANE:
            if (strcmp(v, "contour") == 0)
                o.plane = GEO_MERGE_PLANE_CONTOUR;
            else if (strcmp(v, "weighted") == 0)
                o.plane = GEO_MERGE_PLANE_CONTOUR_WEIGHTED;
            else if (strcmp(v, "area") == 0)
                o.plane = GEO_MERGE_PLANE_AREA;
            else {
                cli_args_invalid(&args, v, "contour, weighted or area");
                return CLI_USAGE;
            }
            break;
        default: return CLI_USAGE;
        }
    }
    if (!in)
        return cli_usage_error("merge", "needs a model file");
    if (!!groups == automatic)
        return cli_usage_error("merge", "needs exactly one of --groups and --auto");
    if (cli_args_output(&args, outpath) != CLI_OK)
        return CLI_USAGE;
    uint32_t ng = 0, *gstart = NULL, *gfacets = NULL;
    if (groups && parse_groups(groups, &ng, &gstart, &gfacets) < 0)
        return cli_usage_error("merge", "--groups: expected facet indices "
                               "like \"3,13,248;1,12\" (two or more per "
                               "group), got '%s'", groups);

    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(in, PROTO_FMT_UNKNOWN, NULL, &err);
    if (!p) {
        free(gstart), free(gfacets);
        return cli_input_error("merge", "%s", err.msg);
    }
    geo_merge_report rep = {0};
    int r = automatic ? geo_merge_auto(p, &o, NULL, &rep, &err)
                      : geo_merge_groups(p, ng, gstart, gfacets, &o, NULL,
                                         &rep, &err);
    free(gstart), free(gfacets);
    if (r < 0) {
        geo_poly_free(p);
        return cli_input_error("merge", "%s: %s", in, err.msg);
    }
    int rc = CLI_OK;
    if (proto_model_write_file(p, outpath, PROTO_FMT_UNKNOWN, &err) < 0)
        rc = cli_input_error("merge", "%s", err.msg);
    if (rc == CLI_OK && report) {
        json_t *j = proto_merge_report_to_json(&rep);
        if (!j || json_dump_file(j, report, JSON_INDENT(1)) < 0)
            rc = cli_input_error("merge", "%s: cannot write the report", report);
        json_decref(j);
    }
    if (!automatic)
        for (uint32_t g = 0; g < rep.ngroups; g++)
            if (rep.groups[g].status != 0) {
                fprintf(stderr, "facet merge: group %u: %s\n", g,
                        rep.groups[g].reason);
                rc = CLI_INPUT;
            }
    printf("{\"groups\":%u,\"merged\":%u,\"failed\":%u,\"rounds\":%u,"
           "\"vertices_before\":%u,\"facets_before\":%u,\"vertices_after\":%u,"
           "\"facets_after\":%u,\"volume_before\":%.17g,\"volume_after\":%.17g}\n",
           rep.ngroups, rep.merged, rep.failed, rep.rounds, rep.vertices_before,
           rep.facets_before, rep.vertices_after, rep.facets_after,
           rep.volume_before, rep.volume_after);
    geo_merge_report_clear(&rep);
    geo_poly_free(p);
    return rc;
}
