/* cli_args.h — the one option parser of every `facet` command.
 *
 * A command lists its options in a table; cli_args_next walks argv and
 * gives back each option's key with its value, each positional argument,
 * and the end. Accepted: "--name VALUE", "--name=VALUE", "-o VALUE" for
 * options that take a value, "--" ending the options, "-" as a positional
 * (standard input or output). Every error is printed as
 * "facet CMD: message" and returned as CLI_ARGS_ERROR, after which the
 * command returns CLI_USAGE. -h/--help is cli_wants_help's (cli.h). */
#ifndef FACET_CLI_ARGS_H
#define FACET_CLI_ARGS_H

#include <stdbool.h>

#include "model_io.h"

typedef struct cli_opt {
    const char *name; /* "--pairs", or "-o" */
    int key;          /* what cli_args_next returns for it (>= 0) */
    bool value;       /* takes a value */
} cli_opt;

enum { CLI_ARGS_END = -1, CLI_ARGS_POSITIONAL = -2, CLI_ARGS_ERROR = -3 };

typedef struct cli_args {
    const char *cmd;
    int argc, i;
    char **argv;
    const cli_opt *opts; /* terminated by {NULL} */
    bool only_positional;
    const char *opt;     /* the option just returned, as written */
    const char **slots;  /* where positionals go (cli_args_positionals) */
    int nslots;
} cli_args;

void cli_args_init(cli_args *a, const char *cmd, int argc, char **argv,
                   const cli_opt *opts);

/* Keeps the positional arguments in slots[0 .. n), in order, instead of
 * returning them (the slots are set to NULL first); one more is an error,
 * "unexpected argument 'X'". A command then sees a missing argument as a
 * NULL slot. */
void cli_args_positionals(cli_args *a, const char **slots, int n);

/* The next option's key (*val = its value, or NULL), CLI_ARGS_POSITIONAL
 * (*val = the argument), CLI_ARGS_END, or CLI_ARGS_ERROR (printed). */
int cli_args_next(cli_args *a, const char **val);

/* Value checks for the option just returned (a->opt names it in the
 * message): 0, or CLI_ARGS_ERROR printed. */
int cli_args_long(cli_args *a, const char *s, long lo, long hi, long *ret);
int cli_args_double(cli_args *a, const char *s, double lo, double hi,
                    bool lo_open, double *ret);
int cli_args_format(cli_args *a, const char *s, proto_format *ret);
/* "X,Y,Z": three finite numbers, not all zero (a direction). */
int cli_args_direction(cli_args *a, const char *s, double ret[3]);

/* A finite number in (0, hi]; the message says what was expected:
 * "OPT: expected EXPECTED, got 'S'". */
int cli_args_positive(cli_args *a, const char *s, double hi,
                      const char *expected, double *ret);

/* Prints "facet CMD: OPT: expected EXPECTED, got 'S'" for the option just
 * returned and returns CLI_ARGS_ERROR: for a value a command checks
 * itself (a keyword, a list). */
int cli_args_invalid(cli_args *a, const char *s, const char *expected);

/* The output path a command writes a model to: CLI_OK, or CLI_USAGE
 * printed ("needs -o OUT"; "OUT: cannot tell the format from the name"
 * when its extension names no format). */
int cli_args_output(cli_args *a, const char *out);

/* Prints "facet CMD: unexpected argument 'X'" and returns CLI_ARGS_ERROR. */
int cli_args_unexpected(cli_args *a, const char *arg);

#endif
