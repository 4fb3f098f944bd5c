/* cmd_run.c — `facet run PIPELINE.json MODEL -o OUT [--stats FILE]`:
 * runs a job pipeline offline, through the same runner facetd's workers
 * use (proto/runner.h), so a pipeline can be tried and a result
 * reproduced without a daemon. PIPELINE.json holds the pipeline value of
 * the Job API (an array of operations, or "auto"); formats of MODEL and
 * OUT come from their extensions. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "cli_args.h"
#include "model_io.h"
#include "parallel.h"
#include "pipeline.h"
#include "runner.h"

static const char USAGE[] =
    "usage: facet run PIPELINE.json MODEL -o OUT [--stats FILE]\n"
    "\n"
    "Runs a job pipeline on a model, as facetd's workers do.\n"
    "  PIPELINE.json  an array of operations or \"auto\" (see the Job API)\n"
    "  MODEL          the input (.json .poly .obj .stl .ply .fmb)\n"
    "  -o OUT         the result (.json .poly .obj .stl .ply .ase .fmb)\n"
    "  --stats FILE   write the statistics JSON there ('-': stdout)\n"
    "\n"
    "exit status: 0 success, 1 bad input or a failed operation (the error\n"
    "names the file and place), 2 usage error\n";

static int progress(void *user, double fraction)
{
    int *last = user;
    int pct = (int)(fraction * 100);
    if (pct / 10 != *last / 10) {
        fprintf(stderr, "\rfacet run: %3d%%", pct);
        if (pct >= 100)
            fputc('\n', stderr);
        *last = pct;
    }
    return 0;
}

int cmd_run(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        fputs(USAGE, stdout);
        return CLI_OK;
    }
    const char *files[2] = {NULL, NULL}, *out = NULL, *stats_path = NULL;
    enum { O_OUT, O_STATS };
    static const cli_opt opts[] = {{"-o", O_OUT, true},
                                   {"--output", O_OUT, true},
                                   {"--stats", O_STATS, true},
                                   {NULL, 0, false}};
    cli_args args;
    const char *val;
    cli_args_init(&args, "run", argc, argv, opts);
    cli_args_positionals(&args, files, 2);
    for (int k; (k = cli_args_next(&args, &val)) != CLI_ARGS_END;) {
        if (k == O_OUT)
            out = val;
        else if (k == O_STATS)
            stats_path = val;
        else
            return CLI_USAGE;
    }
    if (!files[1] || !out)
        return cli_usage_error("run", "needs PIPELINE.json, MODEL and -o OUT");
    json_error_t je;
    json_t *pj = json_load_file(files[0], JSON_DECODE_ANY |
                                          JSON_REJECT_DUPLICATES, &je);
    if (!pj)
        return cli_input_error("run", "%s:%d:%d: %s", files[0], je.line,
                               je.column, je.text);
    proto_pipeline pl;
    geo_err err = {{0}};
    int r = proto_pipeline_from_json(pj, "pipeline", &pl, &err);
    json_decref(pj);
    if (r < 0)
        return cli_input_error("run", "%s: %s", files[0], err.msg);
    char dep[256];
    if (proto_pipeline_deprecations(&pl, dep, sizeof dep))
        fprintf(stderr, "facet run: warning: %s: %s\n", files[0], dep);
    geo_poly *p = proto_model_read_file(files[1], PROTO_FMT_UNKNOWN, NULL,
                                        &err);
    if (!p) {
        proto_pipeline_free(&pl);
        return cli_input_error("run", "%s", err.msg);
    }
    par_pool *pool = par_pool_new(0);
    int last = -10;
    geo_ctx ctx = {.progress = isatty(STDERR_FILENO) ? progress : NULL,
                   .user = &last, .seed = 1,
                   .parallel_for = par_for, .pf_user = pool};
    json_t *stats = NULL, *summary = NULL;
    r = runner_run(&pl, &p, &ctx, NULL, NULL, &stats, &summary, &err);
    proto_pipeline_free(&pl);
    par_pool_free(pool);
    int rc = CLI_OK;
    if (r < 0) {
        rc = cli_input_error("run", "%s: %s", files[1], err.msg);
        goto done;
    }
    if (proto_model_write_file(p, out, PROTO_FMT_UNKNOWN, &err) < 0) {
        rc = cli_input_error("run", "%s", err.msg);
        goto done;
    }
    if (stats_path) {
        int fr = strcmp(stats_path, "-") == 0
                     ? json_dumpf(stats, stdout, JSON_INDENT(2))
                     : json_dump_file(stats, stats_path, JSON_INDENT(2));
        if (strcmp(stats_path, "-") == 0)
            fputc('\n', stdout);
        if (fr < 0) {
            rc = cli_input_error("run", "%s: cannot write: %s", stats_path,
                                 strerror(errno));
            goto done;
        }
    }
    char *line = json_dumps(summary, JSON_COMPACT);
    fprintf(stderr, "facet run: %s\n", line ? line : "done");
    free(line);
done:
    json_decref(stats);
    json_decref(summary);
    geo_poly_free(p);
    return rc;
}
