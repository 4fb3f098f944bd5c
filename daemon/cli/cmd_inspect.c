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

static int parse_count(const char *opt, const char *s, long max, long *ret)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || end == s || *end || v < 0 || v > max)
        return cli_usage_error("inspect", "%s: expected a number 0..%ld, got "
                                          "'%s'", opt, max, s);
    *ret = v;
    return CLI_OK;
}

int cmd_inspect(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        fputs(USAGE, stdout);
        return CLI_OK;
    }
    const char *path = NULL;
    long pairs = 1000, threads = 0;
    proto_format fmt = PROTO_FMT_UNKNOWN;
    bool only_files = false;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int r = CLI_OK;
        if (!only_files && strcmp(a, "--") == 0) {
            only_files = true;
        } else if (!only_files && (strcmp(a, "--pairs") == 0 ||
                                   strcmp(a, "--threads") == 0 ||
                                   strcmp(a, "--from") == 0)) {
            if (i + 1 == argc)
                return cli_usage_error("inspect", "%s needs a value", a);
            const char *val = argv[++i];
            if (a[2] == 'p')
                r = parse_count(a, val, UINT32_MAX > LONG_MAX ? LONG_MAX
                                                              : UINT32_MAX,
                                &pairs);
            else if (a[2] == 't')
                r = parse_count(a, val, 1024, &threads);
            else if ((fmt = proto_format_from_name(val)) == PROTO_FMT_UNKNOWN)
                r = cli_usage_error("inspect", "--from: unknown format '%s'",
                                    val);
        } else if (!only_files && a[0] == '-' && a[1] != '\0') {
            r = cli_usage_error("inspect", "unknown option '%s'", a);
        } else if (!path) {
            path = a;
        } else {
            r = cli_usage_error("inspect", "unexpected argument '%s'", a);
        }
        if (r != CLI_OK)
            return r;
    }
    if (!path)
        return cli_usage_error("inspect", "needs a model file");

    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(path, fmt, NULL, &err);
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
    if (!j)
        return cli_input_error("inspect", "out of memory");
    int wr = json_dumpf(j, stdout, JSON_INDENT(2) | JSON_PRESERVE_ORDER);
    json_decref(j);
    if (wr < 0 || fputc('\n', stdout) == EOF || fflush(stdout) == EOF)
        return cli_input_error("inspect", "cannot write the output");
    return CLI_OK;
}
