/* cli.h — the `facet` command-line tool: one function per command
 * (daemon/cli/cmd_*.c), dispatched by daemon/cli/facet.c.
 *
 * Exit status contract of every command: CLI_OK (0) on success, CLI_INPUT
 * (1) on bad input (the error on stderr, naming the file and place),
 * CLI_USAGE (2) on a usage error. Each command prints its own usage for
 * `facet COMMAND --help` (exit 0). */
#ifndef FACET_CLI_H
#define FACET_CLI_H

#include <stdbool.h>
#include <stddef.h>

#include "version.h"

enum { CLI_OK = 0, CLI_INPUT = 1, CLI_USAGE = 2 };

typedef struct cli_command {
    const char *name;    /* e.g. "convert" */
    const char *summary; /* one line for `facet --help` */
    int (*run)(int argc, char **argv); /* argv[0] is the command name */
} cli_command;

/* Prints "facet COMMAND: message" to stderr and returns CLI_USAGE. */
int cli_usage_error(const char *cmd, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

/* Prints "facet COMMAND: message" to stderr and returns CLI_INPUT. */
int cli_input_error(const char *cmd, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

/* Prints j (its reference taken; NULL: out of memory) to stdout with
 * jansson's flags and a newline, in one write and with the numbers
 * formatted without snprintf (proto/json_text.h: the same text): a
 * report's 750 reals otherwise cost more than computing it. CLI_OK, or
 * CLI_INPUT with the error said for cmd. */
typedef struct json_t json_t;
int cli_print_json(const char *cmd, json_t *j, size_t flags);

/* A monotonic clock in milliseconds, for the "ms" a command reports. */
double cli_mono_ms(void);

/* True when argv holds -h or --help. */
bool cli_wants_help(int argc, char **argv);

/* The commands; each lives in daemon/cli/cmd_NAME.c. */
int cmd_inside(int argc, char **argv);
int cmd_convert(int argc, char **argv);
int cmd_cut(int argc, char **argv);
int cmd_inspect(int argc, char **argv);
int cmd_orient(int argc, char **argv);
int cmd_triangulate(int argc, char **argv);
int cmd_run(int argc, char **argv);
int cmd_move(int argc, char **argv);
int cmd_inversion_stats(int argc, char **argv);
int cmd_merge(int argc, char **argv);
int cmd_collapse(int argc, char **argv);
int cmd_correct(int argc, char **argv);
int cmd_fill(int argc, char **argv);
int cmd_stitch(int argc, char **argv);
int cmd_report(int argc, char **argv);
int cmd_compare(int argc, char **argv);

#endif
