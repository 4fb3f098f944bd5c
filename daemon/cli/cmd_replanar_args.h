/* cmd_replanar_args.h — the re-planarisation options that `facet move`
 * and `facet inversion-stats` share (--schedule, --max-steps, --fit,
 * --scaled-k): parsed in one place so both commands accept and refuse
 * the same values with the same messages. */
#ifndef FACET_CMD_REPLANAR_ARGS_H
#define FACET_CMD_REPLANAR_ARGS_H

#include <stdint.h>

#include "cli_args.h"
#include "replanar.h"

/* cli_args keys of the shared options, above every command's own. */
enum {
    CLI_RP_SCHEDULE = 0x100,
    CLI_RP_MAX_STEPS,
    CLI_RP_FIT,
    CLI_RP_SCALED_K,
};

/* The shared entries of a command's cli_opt table (cli_args.h). */
#define CLI_REPLANAR_OPTS                                            \
    {"--schedule", CLI_RP_SCHEDULE, true},                           \
        {"--max-steps", CLI_RP_MAX_STEPS, true},                     \
        {"--fit", CLI_RP_FIT, true},                                 \
        {"--scaled-k", CLI_RP_SCALED_K, true}

typedef struct cli_replanar_args {
    enum geo_replanar_schedule schedule;
    uint32_t max_steps; /* 0: the schedule's default */
    enum geo_replanar_fit fit;
    enum geo_replanar_scaled_k scaled_k;
} cli_replanar_args;

/* The defaults: the given schedule, its own step budget, planes through
 * the fixed vertices, K = S1/ΣS2 for the scaled schedule. */
void cli_replanar_args_init(cli_replanar_args *a,
                            enum geo_replanar_schedule schedule);

/* Takes cli_args_next's key c with its value when it is one of the
 * shared options. Returns 1 when taken, 0 when c is not one of them,
 * CLI_USAGE (after printing "facet CMD: --option: ...") on a bad value. */
int cli_replanar_option(const char *cmd, int c, const char *arg,
                        cli_replanar_args *a);

/* The next option of a command that takes the shared options and one
 * MODEL: the shared ones are taken into rp, the MODEL into *model (a
 * second one is a usage error); returns the command's own key (*val its
 * value), CLI_ARGS_END, or CLI_ARGS_ERROR (printed). */
int cli_replanar_next(cli_args *a, cli_replanar_args *rp, const char **model,
                      const char **val);

/* Replanarisation options for a: the schedule's defaults with the
 * arguments given applied. */
void cli_replanar_opts(const cli_replanar_args *a, geo_replanar_opts *o);

#endif
