/* cmd_move.c — `facet move`: move one vertex, fix it there and restore the
 * planarity of the facets (Palachev 2012, §4, lib/replanar/replanar.h). Prints the result
 * summary as JSON; writes the model only when the result is valid
 * (converged, no self-intersection, no inverted facet), or with --force. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "cli_args.h"
#include "cmd_replanar_args.h"
#include "model_io.h"
#include "replanar.h"
#include "replanar_json.h"

static const char *const CMD = "move";

static void usage(FILE *out)
{
    fprintf(out,
            "usage: facet move MODEL --vertex I (--to X,Y,Z | --by DX,DY,DZ)\n"
            "                  [--schedule least-norm|local-exp|scaled|"
            "global-exp]\n"
            "                  [--max-steps N] [--count-selfint] [--log FILE]\n"
            "                  [--fit through-fixed|all] [--scaled-k s2sum|s2]\n"
            "                  [--force] -o OUT\n"
            "\n"
            "Moves vertex I (0-based) to X,Y,Z (or by DX,DY,DZ, mm), keeps it\n"
            "there, and moves the other vertices and the planes until every\n"
            "vertex lies in its facets again.\n"
            "Schedules (default least-norm): least-norm moves the other\n"
            "vertices as little as can be (least sum of squares, the planes\n"
            "free), by Gauss-Newton steps on a region that grows from I until\n"
            "S2 < 1e-10; the paper's (Palachev 2012, section 4.2.3):\n"
            "local-exp minimises each step, K=100 doubling over 10 rounds of\n"
            "bounds 1e-7 halving; scaled sets K = S1/S2sum every step;\n"
            "global-exp minimises the total displacement, K doubling until\n"
            "S2 < 1e-10.\n"
            "  --log FILE       the iteration log: JSON if FILE ends in .json,\n"
            "                   else a tab-separated table like the paper's\n"
            "  --count-selfint  count self-intersections after every step\n"
            "  --fit all        plain least-squares planes, the moved vertex\n"
            "                   included (the paper's logs; leaves it off its\n"
            "                   planes by fixed_residual; not least-norm)\n"
            "  --scaled-k s2    scaled: K = S1/S2 as in the paper's tables\n"
            "  --force          write OUT even when the result is not valid\n"
            "Prints the result as JSON. Exit 1 when the result is not valid.\n");
}

/* Parses "x,y,z" into ret; false on anything else. */
static bool parse_vec3(const char *s, double ret[3])
{
    char *end;
    for (int k = 0; k < 3; k++) {
        errno = 0;
        ret[k] = strtod(s, &end);
        if (end == s || errno != 0 || !isfinite(ret[k]))
            return false;
        if (k < 2) {
            if (*end != ',')
                return false;
            s = end + 1;
        }
    }
    return *end == '\0';
}

static bool parse_u32(const char *s, uint32_t *ret)
{
    char *end;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (end == s || *end || errno || v > UINT32_MAX || s[0] == '-')
        return false;
    *ret = (uint32_t)v;
    return true;
}

static int write_log(const char *path, const geo_replanar_log *log)
{
    size_t len = strlen(path);
    if (len >= 5 && strcmp(path + len - 5, ".json") == 0) {
        json_t *j = proto_replanar_log_to_json(log);
        int rc = j ? json_dump_file(j, path, JSON_INDENT(1)) : -1;
        json_decref(j);
        return rc;
    }
    FILE *f = fopen(path, "w");
    if (!f)
        return -1;
    fprintf(f, "step\touter\tinner\tdelta\tS1\tS2\tS2sum\teps0\tK\tselfint\t"
               "active_vertices\tactive_facets\n");
    for (size_t i = 0; i < log->n; i++) {
        const geo_replanar_step *r = &log->rows[i];
        fprintf(f, "%u\t%u\t%u\t%.6e\t%.6e\t%.6e\t%.6e\t%.6e\t%f\t%lld\t%u\t%u\n",
                r->step, r->outer, r->inner, r->delta, r->s1, r->s2,
                r->s2sum, r->eps0, r->k, (long long)r->nselfint,
                r->active_vertices, r->active_facets);
    }
    return fclose(f) == 0 ? 0 : -1;
}

int cmd_move(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        usage(stdout);
        return CLI_OK;
    }
    static const cli_opt opts[] = {
        {"--vertex", 'v', true},        {"--to", 't', true},
        {"--by", 'b', true},            {"--count-selfint", 'c', false},
        {"--log", 'l', true},           {"--force", 'f', false},
        {"--output", 'o', true},        {"-o", 'o', true},
        CLI_REPLANAR_OPTS,              {NULL, 0, false},
    };
    uint32_t vertex = 0;
    bool have_vertex = false, have_to = false, have_by = false, force = false;
    double to[3] = {0, 0, 0}, by[3] = {0, 0, 0};
    const char *log_path = NULL, *out = NULL;
    bool count_si = false;
    cli_replanar_args rp;
    cli_replanar_args_init(&rp, GEO_REPLANAR_LEAST_NORM);
    const char *optarg, *model = NULL;
    cli_args a;
    cli_args_init(&a, CMD, argc, argv, opts);
    for (int c; (c = cli_replanar_next(&a, &rp, &model, &optarg)) !=
                CLI_ARGS_END;) {
        if (c == CLI_ARGS_ERROR)
            return CLI_USAGE;
        switch (c) {
        case 'v':
            if (!parse_u32(optarg, &vertex))
                return cli_usage_error(CMD, "--vertex: not an index: '%s'",
                                       optarg);
            have_vertex = true;
            break;
        case 't':
            if (!parse_vec3(optarg, to))
                return cli_usage_error(CMD, "--to: expected X,Y,Z: '%s'",
                                       optarg);
            have_to = true;
            break;
        case 'b':
            if (!parse_vec3(optarg, by))
                return cli_usage_error(CMD, "--by: expected DX,DY,DZ: '%s'",
                                       optarg);
            have_by = true;
            break;
        case 'c':
            count_si = true;
            break;
        case 'l':
            log_path = optarg;
            break;
        case 'f':
            force = true;
            break;
        case 'o':
            out = optarg;
            break;
        }
    }
    if (!model)
        return cli_usage_error(CMD, "expected one MODEL");
    if (!have_vertex)
        return cli_usage_error(CMD, "--vertex is required");
    if (have_to == have_by)
        return cli_usage_error(CMD, "give exactly one of --to and --by");
    if (!out)
        return cli_usage_error(CMD, "-o OUT is required");
    geo_replanar_opts o;
    cli_replanar_opts(&rp, &o);
    o.count_selfint = count_si;

    const char *path = model;
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(path, PROTO_FMT_UNKNOWN, NULL, &err);
    if (!p)
        return cli_input_error(CMD, "%s", err.msg);
    if (vertex >= p->nverts) {
        uint32_t nv = p->nverts;
        geo_poly_free(p);
        return cli_input_error(CMD, "%s: --vertex %u out of range (%u "
                                    "vertices)", path, vertex, nv);
    }
    if (have_by)
        for (int k = 0; k < 3; k++)
            to[k] = p->verts[vertex][k] + by[k];

    geo_replanar_log log = {0};
    geo_replanar_result res;
    int rc = geo_move(p, vertex, to, rp.schedule, &o, NULL,
                             log_path ? &log : NULL, &res, &err);
    int status = CLI_OK;
    if (rc < 0) {
        status = cli_input_error(CMD, "%s: %s", path, err.msg);
        goto done;
    }
    if (log_path && write_log(log_path, &log) < 0) {
        status = cli_input_error(CMD, "%s: cannot write the log", log_path);
        goto done;
    }
    json_t *j = proto_replanar_result_to_json(&res, rp.schedule);
    if (!j) {
        status = cli_input_error(CMD, "out of memory");
        goto done;
    }
    json_dumpf(j, stdout, JSON_INDENT(2));
    fputc('\n', stdout);
    json_decref(j);
    bool valid = geo_replanar_result_valid(&res);
    if (valid || force) {
        if (proto_model_write_file(p, out, PROTO_FMT_UNKNOWN, &err) < 0) {
            status = cli_input_error(CMD, "%s", err.msg);
            goto done;
        }
    }
    if (!valid)
        status = cli_input_error(
            CMD, "%s: the move does not give a valid polyhedron (%s)%s", path,
            !res.converged ? "did not converge"
            : res.nselfint > 0 ? "self-intersections"
                               : "inverted facets",
            force ? "; written anyway (--force)" : "; nothing written");
done:
    geo_replanar_log_clear(&log);
    geo_poly_free(p);
    return status;
}
