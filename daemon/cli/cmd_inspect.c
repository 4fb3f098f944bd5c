/* cmd_inspect.c — `facet inspect MODEL [--pairs N] [--threads N]
 * [--from FMT]`: prints the inspection statistics of a model as JSON
 * (lib/inspect/stats.h, proto/stats_json.h). A model's defects are results, not
 * errors: the exit status is 0 whatever its state, 1 only when the file
 * cannot be read, 2 for a usage error. */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "cli_args.h"
#include "model_io.h"
#include "parallel.h"
#include "stats.h"
#include "stats_json.h"

static const char USAGE[] =
    "usage: facet inspect MODEL [--pairs N] [--threads N] [--from FMT]\n"
    "\n"
    "Prints the model's statistics as JSON: counts of vertices, edges and\n"
    "facets, boundary edges and holes, non-manifold edges and vertices,\n"
    "orientation (outward, inward, inconsistent) and the facets at fault,\n"
    "volume, area, largest non-planarity, non-convex and degenerate facets,\n"
    "self-intersections (count and the first N facet pairs), near-coplanar\n"
    "neighbours, vertex degrees, clusters of short edges, and 'valid'.\n"
    "\n"
    "  --pairs N    list at most N self-intersecting pairs (default 1000);\n"
    "               the count is always complete\n"
    "  --threads N  threads for the self-intersection search (default: all\n"
    "               CPUs)\n"
    "  --from FMT   input format when the extension does not tell it\n"
    "\n"
    "exit status: 0 inspected (whatever the model's state), 1 the model\n"
    "cannot be read, 2 usage error\n";

int cmd_inspect(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        fputs(USAGE, stdout);
        return CLI_OK;
    }
    const char *path = NULL, *val;
    long pairs = 1000, threads = 0;
    proto_format fmt = PROTO_FMT_UNKNOWN;
    enum { O_PAIRS, O_THREADS, O_FROM };
    static const cli_opt opts[] = {{"--pairs", O_PAIRS, true},
                                   {"--threads", O_THREADS, true},
                                   {"--from", O_FROM, true},
                                   {NULL, 0, false}};
    cli_args a;
    cli_args_init(&a, "inspect", argc, argv, opts);
    cli_args_positionals(&a, &path, 1);
    for (int k; (k = cli_args_next(&a, &val)) != CLI_ARGS_END;) {
        int r = 0;
        switch (k) {
        case O_PAIRS:
            r = cli_args_long(&a, val, 0, UINT32_MAX > LONG_MAX ? LONG_MAX
                                                                : UINT32_MAX,
                              &pairs);
            break;
        case O_THREADS: r = cli_args_long(&a, val, 0, 1024, &threads); break;
        case O_FROM: r = cli_args_format(&a, val, &fmt); break;
        default: r = CLI_ARGS_ERROR;
        }
        if (r)
            return CLI_USAGE;
    }
    if (!path)
        return cli_usage_error("inspect", "needs a model file");

    geo_err err = {{0}};
    /* the statistics read a triangle's plane where they need it: a
     * mesh of triangles keeps no planes (32 bytes a facet) */
    proto_limits lim;
    proto_limits_default(&lim);
    lim.implicit_planes = true;
    lim.map_file = true; /* and its text is never resident whole */
    geo_poly *p = proto_model_read_file(path, fmt, &lim, &err);
    if (!p)
        return cli_input_error("inspect", "%s", err.msg);
    par_pool *pool = par_pool_new((int)threads);
    if (!pool) {
        geo_poly_free(p);
        return cli_input_error("inspect", "cannot start threads");
    }
    geo_ctx ctx = {0};
    ctx.parallel_for = par_for;
    ctx.pf_user = pool;
    geo_inspect_opts o;
    geo_inspect_opts_default(&o);
    o.selfint.max_pairs = (uint32_t)pairs;
    geo_stats s;
    int rc = geo_inspect(p, &o, &ctx, &s, &err);
    par_pool_free(pool);
    geo_poly_free(p);
    if (rc < 0)
        return cli_input_error("inspect", "%s: %s", path, err.msg);
    json_t *j = proto_stats_to_json(&s);
    geo_stats_clear(&s);
    return cli_print_json("inspect", j, JSON_INDENT(2) | JSON_PRESERVE_ORDER);
}
