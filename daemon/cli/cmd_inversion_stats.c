/* cmd_inversion_stats.c — `facet inversion-stats`: the probability that
 * re-planarisation after a random vertex move breaks the model, per move
 * magnitude (Palachev 2012, §4.3.4, lib/replanar/inversion.h), as JSON on stdout. Runs
 * on a thread pool (proto/parallel.h); the table is the same for any
 * --threads. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "cli_args.h"
#include "cmd_replanar_args.h"
#include "inversion.h"
#include "model_io.h"
#include "parallel.h"
#include "replanar_json.h"

static const char *const CMD = "inversion-stats";

static void usage(FILE *out)
{
    fprintf(out,
            "usage: facet inversion-stats MODEL [--samples N] [--seed S]\n"
            "                  [--magnitudes M1,M2,...] [--threads N]\n"
            "                  [--schedule local-exp|scaled|global-exp]\n"
            "                  [--max-steps N] [--runs] [--first-selfint]\n"
            "                  [--fit through-fixed|all] [--scaled-k s2sum|s2]\n"
            "\n"
            "For N random vertices (default 100, seed S, default 1): moves\n"
            "each by m times the distance to its nearest vertex in a random\n"
            "direction, for every m (default 1,.5,.1,.05,.01,.005,.001,.0005,\n"
            ".0001,.00005), re-planarises (default schedule: scaled) and\n"
            "counts the runs that self-intersect, invert a facet or do not\n"
            "converge. Prints JSON: per m the probability with its 95%%\n"
            "Wilson interval and the count of each failure.\n"
            "  --threads N      worker threads (default: all CPUs)\n"
            "  --runs           also list every run\n"
            "  --first-selfint  record the step of each run's first\n"
            "                   self-intersection (counts every step)\n"
            "  --fit, --scaled-k  as in facet move\n");
}

static bool parse_u64(const char *s, uint64_t *ret)
{
    char *end;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (end == s || *end || errno || s[0] == '-')
        return false;
    *ret = v;
    return true;
}

static bool parse_list(const char *s, geo_inversion_opts *o)
{
    o->nmagnitudes = 0;
    for (;;) {
        char *end;
        errno = 0;
        double m = strtod(s, &end);
        if (end == s || errno || !(m > 0) || !isfinite(m) ||
            o->nmagnitudes == GEO_INVERSION_MAX_MAGNITUDES)
            return false;
        o->magnitudes[o->nmagnitudes++] = m;
        if (*end == '\0')
            return true;
        if (*end != ',')
            return false;
        s = end + 1;
    }
}

int cmd_inversion_stats(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        usage(stdout);
        return CLI_OK;
    }
    static const cli_opt opts[] = {
        {"--samples", 'n', true},       {"--seed", 'S', true},
        {"--magnitudes", 'm', true},    {"--threads", 'j', true},
        {"--runs", 'r', false},         {"--first-selfint", 'F', false},
        CLI_REPLANAR_OPTS,              {NULL, 0, false},
    };
    geo_inversion_opts o;
    geo_inversion_opts_default(&o);
    uint64_t seed = 1, samples = o.samples, threads = 0;
    cli_replanar_args rp;
    cli_replanar_args_init(&rp, o.schedule);
    const char *optarg, *path = NULL;
    cli_args a;
    cli_args_init(&a, CMD, argc, argv, opts);
    for (int c; (c = cli_replanar_next(&a, &rp, &path, &optarg)) !=
                CLI_ARGS_END;) {
        if (c == CLI_ARGS_ERROR)
            return CLI_USAGE;
        switch (c) {
        case 'n':
            if (!parse_u64(optarg, &samples) || samples == 0 ||
                samples > 1000000)
                return cli_usage_error(CMD, "--samples: expected 1 to "
                                            "1000000: '%s'", optarg);
            break;
        case 'S':
            if (!parse_u64(optarg, &seed))
                return cli_usage_error(CMD, "--seed: expected an unsigned "
                                            "integer: '%s'", optarg);
            break;
        case 'm':
            if (!parse_list(optarg, &o))
                return cli_usage_error(CMD, "--magnitudes: expected 1 to %d "
                                            "positive numbers separated by "
                                            "commas: '%s'",
                                       GEO_INVERSION_MAX_MAGNITUDES, optarg);
            break;
        case 'j':
            if (!parse_u64(optarg, &threads) || threads == 0 || threads > 1024)
                return cli_usage_error(CMD, "--threads: expected 1 to 1024: "
                                            "'%s'", optarg);
            break;
        case 'r':
            o.keep_runs = true;
            break;
        case 'F':
            o.first_selfint = true;
            break;
        }
    }
    if (!path)
        return cli_usage_error(CMD, "expected one MODEL");
    o.samples = (uint32_t)samples;
    o.schedule = rp.schedule;
    cli_replanar_opts(&rp, &o.replanar);

    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(path, PROTO_FMT_UNKNOWN, NULL, &err);
    if (!p)
        return cli_input_error(CMD, "%s", err.msg);
    par_pool *pool = par_pool_new((int)threads);
    if (!pool) {
        geo_poly_free(p);
        return cli_input_error(CMD, "cannot start threads: %s",
                               strerror(errno));
    }
    geo_ctx ctx = {.seed = seed, .parallel_for = par_for, .pf_user = pool};
    geo_inversion_stats st;
    int status = CLI_OK;
    int rc = geo_inversion_stats_run(p, &o, &ctx, &st, &err);
    if (rc < 0) {
        status = cli_input_error(CMD, "%s: %s", path, err.msg);
    } else {
        json_t *j = proto_inversion_stats_to_json(&st);
        if (j) {
            json_dumpf(j, stdout, JSON_INDENT(2));
            fputc('\n', stdout);
            json_decref(j);
        } else {
            status = cli_input_error(CMD, "out of memory");
        }
        geo_inversion_stats_clear(&st);
    }
    par_pool_free(pool);
    geo_poly_free(p);
    return status;
}
