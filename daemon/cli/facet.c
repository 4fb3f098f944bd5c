/* facet.c — entry point of the `facet` tool: dispatches to a command. */
#include <errno.h>
#include <malloc.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <jansson.h>

#include "cli.h"
#include "json_text.h"

static int cmd_version(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    printf("facet %s\n", FACET_VERSION);
    return CLI_OK;
}

static const cli_command commands[] = {
    {"version", "print the version", cmd_version},
    {"inside", "classify points as inside, outside or on a model", cmd_inside},
    {"convert", "convert a model between file formats", cmd_convert},
    {"cut", "cut a model by a plane (Palachev 2012, §3)", cmd_cut},
    {"inspect", "print a model's statistics and defects as JSON", cmd_inspect},
    {"report", "print a stone's proportions and facet table as JSON",
     cmd_report},
    {"compare", "align two models of a stone and measure their "
     "differences", cmd_compare},
    {"orient", "make a model's facets consistent and outward", cmd_orient},
    {"triangulate", "triangulate a functionally defined object",
     cmd_triangulate},
    {"run", "run a job pipeline on a model offline", cmd_run},
    {"move", "move a vertex and re-planarise the facets", cmd_move},
    {"inversion-stats", "how often vertex moves break the model",
     cmd_inversion_stats},
    {"merge", "merge groups of nearly coplanar facets (Palachev 2012, §2)",
     cmd_merge},
    {"collapse", "collapse clusters of vertices joined by very short "
     "edges", cmd_collapse},
    {"correct", "the automatic post-scan correction", cmd_correct},
    {"fill", "close the holes of a mesh (Vyatkin; Nesterenko)", cmd_fill},
    {"stitch", "join two open meshes into one closed mesh (Nesterenko)",
     cmd_stitch},
};
enum { NCOMMANDS = sizeof commands / sizeof commands[0] };

static void usage(FILE *out)
{
    fprintf(out, "usage: facet COMMAND [ARGS...]\n"
                 "       facet COMMAND --help\n\ncommands:\n");
    for (int i = 0; i < NCOMMANDS; i++)
        fprintf(out, "  %-16s %s\n", commands[i].name, commands[i].summary);
    fprintf(out, "\nexit status: 0 success, 1 bad input, 2 usage error\n");
}

static void vreport(const char *cmd, const char *fmt, va_list ap)
{
    fprintf(stderr, "facet %s: ", cmd);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
}

int cli_usage_error(const char *cmd, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vreport(cmd, fmt, ap);
    va_end(ap);
    fprintf(stderr, "try 'facet %s --help'\n", cmd);
    return CLI_USAGE;
}

int cli_input_error(const char *cmd, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vreport(cmd, fmt, ap);
    va_end(ap);
    return CLI_INPUT;
}

int cli_print_json(const char *cmd, json_t *j, size_t flags)
{
    char *text = j ? proto_json_dumps(j, flags) : NULL;
    json_decref(j);
    if (!text)
        return cli_input_error(cmd, "out of memory");
    size_t len = strlen(text);
    bool ok = fwrite(text, 1, len, stdout) == len && fputc('\n', stdout) != EOF &&
              fflush(stdout) != EOF;
    free(text);
    return ok ? CLI_OK : cli_input_error(cmd, "cannot write the output");
}

double cli_mono_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec / 1e6;
}

bool cli_wants_help(int argc, char **argv)
{
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--") == 0)
            return false;
        if (strcmp(argv[i], "-h") == 0 || strcmp(argv[i], "--help") == 0)
            return true;
    }
    return false;
}

int main(int argc, char **argv)
{
    /* keep freed blocks below 4 MiB for reuse instead of handing each
     * back to the kernel (and taking it again zero-filled, page by page,
     * for the next): a command allocates and frees a few tens of arrays,
     * and on a scan their page faults were a tenth of inspecting it.
     * Larger arrays are mapped: freed, they leave the process (kept, a
     * model's file text and each phase's arrays stayed resident to the
     * end, twice the peak of any phase on a 10^6-triangle mesh), and
     * they grow by remapping, without a copy */
    mallopt(M_MMAP_THRESHOLD, 4 << 20);
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
    if (argc < 2) {
        usage(stderr);
        return CLI_USAGE;
    }
    if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0 ||
        strcmp(argv[1], "help") == 0) {
        usage(stdout);
        return CLI_OK;
    }
    for (int i = 0; i < NCOMMANDS; i++)
        if (strcmp(argv[1], commands[i].name) == 0) {
            int rc = commands[i].run(argc - 1, argv + 1);
            /* a result lost on a full disk or a closed pipe is a failure */
            if (fflush(stdout) != 0 || ferror(stdout)) {
                fprintf(stderr, "facet %s: standard output: %s\n",
                        argv[1], strerror(errno));
                if (rc == CLI_OK)
                    rc = CLI_INPUT;
            }
            return rc;
        }
    fprintf(stderr, "facet: unknown command '%s'\n", argv[1]);
    usage(stderr);
    return CLI_USAGE;
}
