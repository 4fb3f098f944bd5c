/* cmd_compare.c — `facet compare A B [--axis X,Y,Z]`: lays B onto A by
 * the best rigid motion and prints, as JSON, the motion, the distances
 * between the surfaces and the matched facets (lib/gem/compare.h,
 * docs/kernels/compare.md). */
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "cli_args.h"
#include "compare.h"
#include "compare_json.h"
#include "model_io.h"
#include "parallel.h"

static const char USAGE[] =
    "usage: facet compare A B [--axis X,Y,Z] [--threads N]\n"
    "\n"
    "Aligns model B onto model A (any format facet reads, any orientation\n"
    "and position) by the rigid motion that takes B's table onto A's and\n"
    "best matches the facet normals, then prints as JSON: aligned, the\n"
    "rotation (rotation_deg, rotation_axis) and translation_mm applied to\n"
    "B, hausdorff_mm and mean_distance_mm between the surfaces,\n"
    "volume_difference_relative ((B - A) / A), and the facets matched one\n"
    "to one (a, b, angle_deg, offset_mm: B's plane minus A's along A's\n"
    "normal) with the counts of matched and unmatched facets.\n"
    "  --axis X,Y,Z  the main axis of both models (default: the table that\n"
    "                stands out, else the largest facet within 10 degrees\n"
    "                of +z); needed for a model without a table\n"
    "  --threads N   threads measuring the two directions (default: all\n"
    "                CPUs)\n"
    "\n"
    "exit status: 0 success, 1 bad input (the error names file and place),\n"
    "2 usage error\n";

int cmd_compare(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        fputs(USAGE, stdout);
        return CLI_OK;
    }
    const char *path[2] = {NULL, NULL}, *val;
    double axis[3];
    bool have_axis = false;
    int npath = 0;
    long threads = 0;
    enum { O_AXIS, O_THREADS };
    static const cli_opt opts[] = {{"--axis", O_AXIS, true},
                                   {"--threads", O_THREADS, true},
                                   {NULL, 0, false}};
    cli_args a;
    cli_args_init(&a, "compare", argc, argv, opts);
    for (int k; (k = cli_args_next(&a, &val)) != CLI_ARGS_END;) {
        int r = 0;
        switch (k) {
        case O_AXIS:
            r = cli_args_direction(&a, val, axis);
            have_axis = true;
            break;
        case O_THREADS: r = cli_args_long(&a, val, 0, 1024, &threads); break;
        case CLI_ARGS_POSITIONAL:
            if (npath == 2)
                r = cli_args_unexpected(&a, val);
            else
                path[npath++] = val;
            break;
        default: r = CLI_ARGS_ERROR;
        }
        if (r)
            return CLI_USAGE;
    }
    if (npath < 2)
        return cli_usage_error("compare", "needs two models, A and B");
    geo_err err = {{0}};
    geo_poly *m[2] = {NULL, NULL};
    for (int i = 0; i < 2; i++)
        if (!(m[i] = proto_model_read_file(path[i], PROTO_FMT_UNKNOWN, NULL,
                                           &err))) {
            geo_poly_free(m[0]);
            return cli_input_error("compare", "%s", err.msg);
        }
    geo_compare_opts o = {.axis = have_axis ? axis : NULL,
                          .name_a = path[0], .name_b = path[1]};
    par_pool *pool = par_pool_new((int)threads);
    if (!pool) {
        geo_poly_free(m[0]);
        geo_poly_free(m[1]);
        return cli_input_error("compare", "cannot start threads");
    }
    geo_ctx ctx = {.parallel_for = par_for, .pf_user = pool};
    geo_compare_result res;
    int e = geo_compare(m[0], m[1], &o, &ctx, &res, &err);
    par_pool_free(pool);
    geo_poly_free(m[0]);
    geo_poly_free(m[1]);
    if (e < 0)
        return cli_input_error("compare", "%s", err.msg);
    json_t *j = proto_compare_to_json(&res);
    geo_compare_free(&res);
    return cli_print_json("compare", j, JSON_INDENT(2) | JSON_PRESERVE_ORDER);
}
