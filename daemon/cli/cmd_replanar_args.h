/* cmd_replanar_args.h — the re-planarisation options that `facet move`
 * and `facet inversion-stats` share (--schedule, --max-steps, --fit,
 * --scaled-k): parsed in one place so both commands accept and refuse
 * the same values with the same messages. */
#ifndef FACET_CMD_REPLANAR_ARGS_H
#define FACET_CMD_REPLANAR_ARGS_H

#include <getopt.h>
#include <stdint.h>

#include "replanar.h"

/* getopt_long codes of the shared options, above every character. */
enum {
    CLI_RP_SCHEDULE = 0x100,
    CLI_RP_MAX_STEPS,
    CLI_RP_FIT,
    CLI_RP_SCALED_K,
};

/* The shared entries of a command's struct option table. */
#define CLI_REPLANAR_LONGOPTS                                        \
    {"schedule", required_argument, NULL, CLI_RP_SCHEDULE},          \
        {"max-steps", required_argument, NULL, CLI_RP_MAX_STEPS},    \
        {"fit", required_argument, NULL, CLI_RP_FIT},                \
        {"scaled-k", required_argument, NULL, CLI_RP_SCALED_K}

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

/* Takes getopt_long's code c with its argument when it is one of the
 * shared options. Returns 1 when taken, 0 when c is not one of them,
 * CLI_USAGE (after printing "facet CMD: --option: ...") on a bad value. */
int cli_replanar_option(const char *cmd, int c, const char *arg,
                        cli_replanar_args *a);

/* Replanarisation options for a: the schedule's defaults with the
 * arguments given applied. */
void cli_replanar_opts(const cli_replanar_args *a, geo_replanar_opts *o);

#endif
