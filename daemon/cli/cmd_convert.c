/* cmd_convert.c — `facet convert IN OUT [--from FMT] [--to FMT]
 * [--width MM]`: reads a model in one format and writes it in another
 * (proto/model_io.h). The formats come from the file extensions unless
 * given. Given planes that disagree with their vertices are reported on
 * stderr as a warning; the conversion still succeeds. --width scales the
 * model (a GemCad design has no units) to a given outline width. */
#include <float.h>
#include <stdio.h>

#include "cli.h"
#include "cli_args.h"
#include "model_io.h"

static const char USAGE[] =
    "usage: facet convert IN OUT [--from FMT] [--to FMT] [--width MM]\n"
    "\n"
    "Converts a polyhedron between file formats. Formats are taken from the\n"
    "extensions (.json .poly .obj .stl .ply .ase .fmb .off .asc) unless\n"
    "given:\n"
    "  json       facet-model/1 (read, write)\n"
    "  poly       the paper's text format: counts, vertices, facets with\n"
    "             planes (read, write)\n"
    "  obj        Wavefront OBJ, polygons kept (read, write)\n"
    "  stl        STL, binary or ASCII on reading, binary (float32) on\n"
    "             writing; facets split into triangles\n"
    "  stl-ascii  ASCII STL on writing (exact decimals)\n"
    "  ply        PLY, ASCII or binary on reading, binary little-endian\n"
    "             (double) on writing\n"
    "  ply-ascii  ASCII PLY on writing\n"
    "  ase        3ds Max ASCII export, triangles (write only)\n"
    "  fmb1       the scanner's binary model FMB1 (read, write)\n"
    "  off        Geomview OFF (and COFF, NOFF, 4OFF, nOFF on reading;\n"
    "             colours, normals, comments skipped), polygons kept\n"
    "  asc        GemCad design: read as the exact intersection of its\n"
    "             facets' half-spaces; written from a convex model as\n"
    "             tiers on a 96-tooth gear (fractional indices off it)\n"
    "\n"
    "--width MM scales the model about the origin so that the largest\n"
    "caliper width of its outline seen along z is MM millimetres.\n"
    "\n"
    "The output is written atomically (temporary file, then rename).\n"
    "exit status: 0 success, 1 bad input (the error names file and place),\n"
    "2 usage error\n";

int cmd_convert(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        fputs(USAGE, stdout);
        return CLI_OK;
    }
    const char *files[2] = {NULL, NULL};
    proto_format from = PROTO_FMT_UNKNOWN, to = PROTO_FMT_UNKNOWN;
    double width = 0.0;
    enum { O_FROM, O_TO, O_WIDTH };
    static const cli_opt opts[] = {
        {"--from", O_FROM, true}, {"--to", O_TO, true},
        {"--width", O_WIDTH, true}, {NULL, 0, false},
    };
    cli_args a;
    const char *v;
    cli_args_init(&a, "convert", argc, argv, opts);
    cli_args_positionals(&a, files, 2);
    for (int k; (k = cli_args_next(&a, &v)) != CLI_ARGS_END;) {
        int r = 0;
        switch (k) {
        case O_FROM: r = cli_args_format(&a, v, &from); break;
        case O_TO: r = cli_args_format(&a, v, &to); break;
        case O_WIDTH:
            r = cli_args_positive(&a, v, DBL_MAX, "a positive number of mm",
                                  &width);
            break;
        default: r = CLI_ARGS_ERROR;
        }
        if (r)
            return CLI_USAGE;
    }
    if (!files[1])
        return cli_usage_error("convert", "needs an input and an output file");
    if (from == PROTO_FMT_UNKNOWN)
        from = proto_format_from_path(files[0]);
    if (to == PROTO_FMT_UNKNOWN)
        to = proto_format_from_path(files[1]);
    if (from == PROTO_FMT_UNKNOWN)
        return cli_usage_error("convert", "%s: cannot tell the format from "
                                          "the name; use --from", files[0]);
    if (to == PROTO_FMT_UNKNOWN)
        return cli_usage_error("convert", "%s: cannot tell the format from "
                                          "the name; use --to", files[1]);
    if (from == PROTO_FMT_ASE)
        return cli_usage_error("convert", "ASE can be written, not read");

    geo_err err = {{0}};
    proto_read_report rep;
    geo_poly *p = proto_model_read_file_ex(files[0], from, NULL, &rep, &err);
    if (!p)
        return cli_input_error("convert", "%s", err.msg);
    if (rep.plane_mismatches)
        fprintf(stderr, "facet convert: %s: warning: %u of %u given planes "
                        "disagree with their vertices (largest distance "
                        "%.3g mm); first: %s\n",
                files[0], rep.plane_mismatches, rep.planes_given,
                rep.worst_deviation, rep.first);
    if (width > 0 && proto_model_scale_to_width(p, width, &err) < 0) {
        geo_poly_free(p);
        return cli_input_error("convert", "%s: %s", files[0], err.msg);
    }
    int r = proto_model_write_file(p, files[1], to, &err);
    geo_poly_free(p);
    if (r < 0)
        return cli_input_error("convert", "%s", err.msg);
    return CLI_OK;
}
