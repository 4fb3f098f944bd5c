/* cmd_replanar_args.c — parsing of the re-planarisation options shared by
 * `facet move` and `facet inversion-stats` (cmd_replanar_args.h). */
#include "cmd_replanar_args.h"

#include <errno.h>
#include <stdlib.h>

#include "cli.h"

void cli_replanar_args_init(cli_replanar_args *a,
                            enum geo_replanar_schedule schedule)
{
    a->schedule = schedule;
    a->max_steps = 0;
    a->fit = GEO_REPLANAR_FIT_THROUGH_FIXED;
    a->scaled_k = GEO_REPLANAR_SCALED_K_S2SUM;
}

static bool parse_steps(const char *s, uint32_t *ret)
{
    char *end;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (end == s || *end || errno || s[0] == '-' || v == 0 || v > UINT32_MAX)
        return false;
    *ret = (uint32_t)v;
    return true;
}

int cli_replanar_option(const char *cmd, int c, const char *arg,
                        cli_replanar_args *a)
{
    switch (c) {
    case CLI_RP_SCHEDULE:
        if (geo_replanar_schedule_parse(arg, &a->schedule) < 0)
            return cli_usage_error(cmd, "--schedule: unknown '%s'", arg);
        return 1;
    case CLI_RP_MAX_STEPS:
        if (!parse_steps(arg, &a->max_steps))
            return cli_usage_error(cmd, "--max-steps: expected a positive "
                                        "integer: '%s'", arg);
        return 1;
    case CLI_RP_FIT:
        if (geo_replanar_fit_parse(arg, &a->fit) < 0)
            return cli_usage_error(cmd, "--fit: unknown '%s'", arg);
        return 1;
    case CLI_RP_SCALED_K:
        if (geo_replanar_scaled_k_parse(arg, &a->scaled_k) < 0)
            return cli_usage_error(cmd, "--scaled-k: unknown '%s'", arg);
        return 1;
    default:
        return 0;
    }
}

void cli_replanar_opts(const cli_replanar_args *a, geo_replanar_opts *o)
{
    geo_replanar_opts_default(o, a->schedule);
    if (a->max_steps)
        o->max_steps = a->max_steps;
    o->fit = a->fit;
    o->scaled_k = a->scaled_k;
}

int cli_replanar_next(cli_args *a, cli_replanar_args *rp, const char **model,
                      const char **val)
{
    for (;;) {
        int c = cli_args_next(a, val);
        if (c == CLI_ARGS_END || c == CLI_ARGS_ERROR)
            return c;
        if (c == CLI_ARGS_POSITIONAL) {
            if (*model) {
                cli_usage_error(a->cmd, "expected one MODEL");
                return CLI_ARGS_ERROR;
            }
            *model = *val;
            continue;
        }
        int taken = cli_replanar_option(a->cmd, c, *val, rp);
        if (taken == 0)
            return c;
        if (taken != 1)
            return CLI_ARGS_ERROR;
    }
}
