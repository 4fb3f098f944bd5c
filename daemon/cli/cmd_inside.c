/* cmd_inside.c — `facet inside MODEL POINTS.json`: classifies points
 * against a polyhedron (the point-in-polyhedron tests of
 * "Tests of graphic elements", lib/inspect/inside.h)
 * and prints a JSON array of "inside" / "outside" / "boundary", one per
 * point, in order. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "cli_args.h"
#include "inside.h"
#include "model_io.h"
#include "parallel.h"
#include "points_json.h"
#include "topo.h"

static const char USAGE[] =
    "usage: facet inside MODEL POINTS.json [--threads N] [--method M]\n"
    "                    [--seed S]\n"
    "\n"
    "Classifies points against a polyhedron and prints a JSON array with\n"
    "\"inside\", \"outside\" or \"boundary\" for each point, in order.\n"
    "POINTS.json holds [[x, y, z], ...] (mm) or {\"points\": [...]};\n"
    "\"-\" reads standard input. MODEL is any readable model format.\n"
    "\n"
    "Answers are exact for the given coordinates: a point exactly on a\n"
    "facet, an edge or a vertex is \"boundary\", one a rounding step off it\n"
    "is \"inside\" or \"outside\".\n"
    "\n"
    "  --threads N  threads to use (default: all processors)\n"
    "  --method M   ray: ray parity (closed models, any facet orientation);\n"
    "               winding: generalized winding number (models with\n"
    "               holes; facets listed outward; slower); auto (default):\n"
    "               ray when every edge has two facets, else winding\n"
    "  --seed S     seed of the re-shot random rays (default 1); answers\n"
    "               do not depend on it for closed models\n"
    "\n"
    "exit status: 0 success, 1 bad input (the error names file and place),\n"
    "2 usage error\n";

static int parse_count(const char *opt, const char *s, unsigned long max,
                       unsigned long *ret)
{
    char *end;
    errno = 0;
    unsigned long v = strtoul(s, &end, 10);
    if (errno || end == s || *end || s[0] == '-' || v > max)
        return cli_usage_error("inside", "%s: expected a number from 0 to "
                                         "%lu, got '%s'", opt, max, s);
    *ret = v;
    return CLI_OK;
}

/* The method for "auto": ray parity needs a closed surface (every edge in
 * two facets) but not a consistent orientation, so a flipped facet does
 * not send a model to the slower winding number. */
static int closed_model(const geo_poly *p, bool *ret_closed)
{
    geo_err err;
    geo_topo *t = geo_topo_build(p, &err);
    if (!t)
        return -ENOMEM;
    *ret_closed = t->nboundary_edges == 0 && t->nnonmanifold_edges == 0;
    geo_topo_free(t);
    return 0;
}

int cmd_inside(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        fputs(USAGE, stdout);
        return CLI_OK;
    }
    const char *files[2] = {NULL, NULL};
    unsigned long threads = 0, seed = 1;
    const char *method = "auto";
    enum { O_THREADS, O_SEED, O_METHOD };
    static const cli_opt opts[] = {{"--threads", O_THREADS, true},
                                   {"--seed", O_SEED, true},
                                   {"--method", O_METHOD, true},
                                   {NULL, 0, false}};
    cli_args args;
    const char *val;
    cli_args_init(&args, "inside", argc, argv, opts);
    cli_args_positionals(&args, files, 2);
    for (int k; (k = cli_args_next(&args, &val)) != CLI_ARGS_END;) {
        int r = CLI_OK;
        switch (k) {
        case O_THREADS: r = parse_count(args.opt, val, 1024, &threads); break;
        case O_SEED:
            r = parse_count(args.opt, val, (unsigned long)-1, &seed);
            break;
        case O_METHOD:
            if (strcmp(val, "auto") && strcmp(val, "ray") &&
                strcmp(val, "winding"))
                r = cli_usage_error("inside", "--method: expected auto, ray "
                                              "or winding, got '%s'", val);
            else
                method = val;
            break;
        default: r = CLI_USAGE;
        }
        if (r != CLI_OK)
            return r;
    }
    if (!files[1])
        return cli_usage_error("inside", "needs a model and a points file");

    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(files[0], PROTO_FMT_UNKNOWN, NULL, &err);
    if (!p)
        return cli_input_error("inside", "%s", err.msg);
    int status = CLI_INPUT;
    double(*pts)[3] = NULL;
    size_t n = 0;
    int8_t *loc = NULL;
    char *text = NULL;
    geo_inside *ix = NULL;
    par_pool *pool = NULL;
    if (proto_points_read_file(files[1], 0, &pts, &n, &err) != 0) {
        cli_input_error("inside", "%s", err.msg);
        goto done;
    }
    enum geo_inside_method m = GEO_INSIDE_RAY;
    if (strcmp(method, "winding") == 0) {
        m = GEO_INSIDE_WINDING;
    } else if (strcmp(method, "auto") == 0) {
        bool closed;
        if (closed_model(p, &closed) != 0) {
            cli_input_error("inside", "out of memory");
            goto done;
        }
        m = closed ? GEO_INSIDE_RAY : GEO_INSIDE_WINDING;
    }
    ix = geo_inside_new(p, &err);
    loc = malloc(n + 1);
    pool = par_pool_new((int)threads);
    if (!ix || !loc || !pool) {
        cli_input_error("inside", "%s: %s", files[0],
                        ix ? "out of memory" : err.msg);
        goto done;
    }
    geo_ctx ctx = {.seed = seed, .parallel_for = par_for, .pf_user = pool};
    if (geo_inside_classify(ix, (const double(*)[3])pts, n, m, loc, &ctx,
                            &err) != 0) {
        cli_input_error("inside", "%s: %s", files[1], err.msg);
        goto done;
    }
    size_t len;
    text = proto_locs_to_text(loc, n, &len);
    if (!text) {
        cli_input_error("inside", "out of memory");
        goto done;
    }
    if (fwrite(text, 1, len, stdout) != len || fflush(stdout) != 0) {
        cli_input_error("inside", "writing the answers: %s", strerror(errno));
        goto done;
    }
    status = CLI_OK;
done:
    free(text);
    par_pool_free(pool);
    free(loc);
    geo_inside_free(ix);
    free(pts);
    geo_poly_free(p);
    return status;
}
