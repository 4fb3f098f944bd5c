/* cmd_orient.c — `facet orient MODEL -o OUT [--from FMT] [--to FMT]`:
 * makes a model's facets consistent and outward (lib/inspect/orient.h: flips the
 * minority of each shell, then any shell still turned inside out; planes
 * are negated with their facets) and writes the result. A non-orientable
 * model cannot be repaired by flipping: it is reported and nothing is
 * written. */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "cli_args.h"
#include "model_io.h"
#include "orient.h"

static const char USAGE[] =
    "usage: facet orient MODEL -o OUT [--from FMT] [--to FMT]\n"
    "\n"
    "Reverses the facets whose orientation disagrees with their neighbours\n"
    "(the smaller side of each disagreement) and, when the whole model or a\n"
    "shell of it is turned inside out (negative volume; positive for the\n"
    "wall of a cavity), all of its facets;\n"
    "writes the result to OUT (format from the extension unless given).\n"
    "Prints what was done on stderr.\n"
    "\n"
    "exit status: 0 written, 1 unreadable, non-orientable or unwritable\n"
    "model, 2 usage error\n";

int cmd_orient(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        fputs(USAGE, stdout);
        return CLI_OK;
    }
    const char *in = NULL, *out = NULL, *val;
    proto_format from = PROTO_FMT_UNKNOWN, to = PROTO_FMT_UNKNOWN;
    enum { O_OUT, O_FROM, O_TO };
    static const cli_opt opts[] = {{"-o", O_OUT, true},
                                   {"--output", O_OUT, true},
                                   {"--from", O_FROM, true},
                                   {"--to", O_TO, true},
                                   {NULL, 0, false}};
    cli_args a;
    cli_args_init(&a, "orient", argc, argv, opts);
    cli_args_positionals(&a, &in, 1);
    for (int k; (k = cli_args_next(&a, &val)) != CLI_ARGS_END;) {
        int r = 0;
        switch (k) {
        case O_OUT: out = val; break;
        case O_FROM: r = cli_args_format(&a, val, &from); break;
        case O_TO: r = cli_args_format(&a, val, &to); break;
        default: r = CLI_ARGS_ERROR;
        }
        if (r)
            return CLI_USAGE;
    }
    if (!in || !out)
        return cli_usage_error("orient", "needs a model file and -o OUT");
    if (to == PROTO_FMT_UNKNOWN && proto_format_from_path(out) ==
                                       PROTO_FMT_UNKNOWN)
        return cli_usage_error("orient", "%s: cannot tell the format from "
                                         "the name; use --to", out);

    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(in, from, NULL, &err);
    if (!p)
        return cli_input_error("orient", "%s", err.msg);
    geo_orient_report rep;
    int rc = geo_orient_repair(p, &rep, &err);
    if (rc < 0) {
        geo_poly_free(p);
        return cli_input_error("orient", "%s: %s", in, err.msg);
    }
    rc = proto_model_write_file(p, out, to, &err);
    geo_poly_free(p);
    if (rc < 0)
        return cli_input_error("orient", "%s", err.msg);
    fprintf(stderr,
            "facet orient: %s: %u facet%s reversed (%u inconsistent with "
            "their neighbours, %u of %u shell%s turned inside out)\n",
            in, rep.nflipped, rep.nflipped == 1 ? "" : "s",
            rep.ninconsistent, rep.ninverted_shells, rep.nshells,
            rep.nshells == 1 ? "" : "s");
    return CLI_OK;
}
