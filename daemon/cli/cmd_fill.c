/* cmd_fill.c — `facet fill MODEL -o OUT [--weight area|edges|angle]
 * [--no-refine] [--no-fair] [--parts-overlap] [--remove-crossing]
 * [--report FILE] [--keep-invalid]`: closes
 * the holes of a mesh (lib/mesh/fill.h), writes it, prints a one-line
 * JSON summary and, with --report, the whole report (every hole with the
 * strategy that closed it or why it is open, the validity of the result
 * with the reasons when it is not valid, the time). OUT is written and
 * the exit status is 0 only when the result is a valid closed solid; any
 * other result exits 1 with the reasons (and is written only with
 * --keep-invalid, for inspection). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "cli_args.h"
#include "fill.h"
#include "fill_json.h"
#include "model_io.h"
#include "stats.h"

static const char USAGE[] =
    "usage: facet fill MODEL -o OUT [--weight area|edges|angle] [--no-refine]\n"
    "                  [--no-fair] [--parts-overlap] [--remove-crossing]\n"
    "                  [--report FILE] [--keep-invalid]\n"
    "\n"
    "Closes every hole (boundary loop) of MODEL and writes OUT. A planar hole\n"
    "(a missing facet) gets one planar facet; any other is triangulated with\n"
    "Liepa's minimum-weight triangulation, refined to the density of the\n"
    "mesh around it and faired (U² = 0, the mesh around kept fixed). Every\n"
    "patch is checked: one that would intersect the mesh is taken back and\n"
    "tried again (angle weight, no fairing, no refinement, then the search\n"
    "steered around the triangles that crossed); a hole that cannot be\n"
    "filled validly stays open and the report says why. Facets wound\n"
    "against their neighbours are reversed first (the report's\n"
    "facets_reversed); a polygon that is not planar is split into\n"
    "triangles (facets_split); vertices no facet uses are removed\n"
    "(vertices_unused) and seams whose sides repeat their vertices at the\n"
    "same points are welded (vertices_welded).\n"
    "\n"
    "  -o, --output OUT  the result (format from the extension)\n"
    "  --weight W        area (least area, default), edges (least edge\n"
    "                    length) or angle (least dihedral angle, then area)\n"
    "  --no-refine       keep the bare triangulation\n"
    "  --no-fair         do not fair the refined patches\n"
    "  --parts-overlap   MODEL is an assembly of overlapping parts: a patch\n"
    "                    may cross another shell that its own shell\n"
    "                    already crosses (no two parts come to cross that\n"
    "                    did not); never its own shell\n"
    "  --remove-crossing first remove every facet that crosses another and\n"
    "                    touches a hole (a flap folded over the opening),\n"
    "                    so that hole grows by it; where crossings remain\n"
    "                    or a hole stays open, both facets of every\n"
    "                    crossing pair and up to three rings around them\n"
    "                    and the open holes; kept only when every hole\n"
    "                    then closes and at most 5% of the facets go (the\n"
    "                    report's facets_removed)\n"
    "  --report FILE     write the full JSON report to FILE\n"
    "  --keep-invalid    write OUT even when the result is not valid (the\n"
    "                    exit status is still 1)\n"
    "\n"
    "Prints one line of JSON: loops, filled, planar, left_open,\n"
    "vertices_added, facets_added, max_dihedral_deg, valid, vertices, facets,\n"
    "ms. exit status: 0 OUT written and valid (closed, manifold, outward,\n"
    "no self-intersection), 1 bad input or a result that is not valid (the\n"
    "reasons on stderr; OUT not written unless --keep-invalid), 2 usage\n"
    "error\n";

int cmd_fill(int argc, char **argv)
{
    if (cli_wants_help(argc, argv)) {
        fputs(USAGE, stdout);
        return CLI_OK;
    }
    const char *in = NULL, *outpath = NULL, *report = NULL;
    bool keep_invalid = false;
    geo_mesh_fill_opts o;
    geo_mesh_fill_opts_default(&o);
    enum { O_OUT, O_REPORT, O_WEIGHT, O_NO_REFINE, O_NO_FAIR,
           O_PARTS_OVERLAP, O_REMOVE_CROSSING, O_KEEP_INVALID };
    static const cli_opt opts[] = {
        {"-o", O_OUT, true},              {"--output", O_OUT, true},
        {"--report", O_REPORT, true},     {"--weight", O_WEIGHT, true},
        {"--no-refine", O_NO_REFINE, false},
        {"--no-fair", O_NO_FAIR, false},
        {"--parts-overlap", O_PARTS_OVERLAP, false},
        {"--remove-crossing", O_REMOVE_CROSSING, false},
        {"--keep-invalid", O_KEEP_INVALID, false},
        {NULL, 0, false},
    };
    cli_args a;
    const char *v;
    cli_args_init(&a, "fill", argc, argv, opts);
    cli_args_positionals(&a, &in, 1);
    for (int k; (k = cli_args_next(&a, &v)) != CLI_ARGS_END;) {
        int r = 0;
        switch (k) {
        case O_OUT: outpath = v; break;
        case O_REPORT: report = v; break;
        case O_WEIGHT:
            if (strcmp(v, "area") == 0)
                o.fill.weight = GEO_FILL_AREA;
            else if (strcmp(v, "edges") == 0)
                o.fill.weight = GEO_FILL_EDGES;
            else if (strcmp(v, "angle") == 0)
                o.fill.weight = GEO_FILL_ANGLE;
            else
                r = cli_args_invalid(&a, v, "area, edges or angle");
            break;
        case O_NO_REFINE: o.fill.refine = false; break;
        case O_NO_FAIR: o.fill.fair = GEO_FAIR_NONE; break;
        case O_PARTS_OVERLAP: o.parts_overlap = true; break;
        case O_REMOVE_CROSSING: o.remove_crossing = true; break;
        case O_KEEP_INVALID: keep_invalid = true; break;
        default: r = CLI_ARGS_ERROR;
        }
        if (r)
            return CLI_USAGE;
    }
    if (!in)
        return cli_usage_error("fill", "needs a model file");
    if (cli_args_output(&a, outpath) != CLI_OK)
        return CLI_USAGE;

    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(in, PROTO_FMT_UNKNOWN, NULL, &err);
    if (!p)
        return cli_input_error("fill", "%s", err.msg);
    geo_mesh_fill_report rep;
    double t0 = cli_mono_ms();
    int r = geo_fill(p, &o, NULL, &rep, &err);
    double ms = cli_mono_ms() - t0;
    if (r < 0) {
        geo_poly_free(p);
        return cli_input_error("fill", "%s: %s", in, err.msg);
    }
    geo_stats st;
    json_t *fj = NULL, *vj = NULL, *doc = NULL;
    int rc = CLI_OK;
    if (geo_inspect(p, NULL, NULL, &st, &err) < 0) {
        rc = cli_input_error("fill", "inspecting the result: %s", err.msg);
        goto out_rep;
    }
    fj = proto_fill_report_to_json(&rep);
    vj = proto_validity_to_json(&st);
    doc = fj && vj ? json_pack("{s:O, s:O, s:f}", "fill", fj, "result", vj,
                               "ms", ms)
                   : NULL;
    if (!doc) {
        rc = cli_input_error("fill", "out of memory");
        goto out;
    }
    /* an invalid result is never written as a success: with
     * --keep-invalid it is written for inspection, and the exit status is
     * still 1 */
    if (!st.valid) {
        json_t *why = json_object_get(vj, "reasons");
        char *text = why ? json_dumps(why, JSON_COMPACT) : NULL;
        rc = cli_input_error("fill", "%s: the result is not a valid closed "
                             "solid%s: %s", in,
                             keep_invalid ? " (written anyway)" : ", not "
                                                                 "written",
                             text ? text : "[]");
        free(text);
    }
    if ((st.valid || keep_invalid) &&
        proto_model_write_file(p, outpath, PROTO_FMT_UNKNOWN, &err) < 0) {
        rc = cli_input_error("fill", "%s", err.msg);
        goto out;
    }
    if (report && json_dump_file(doc, report, JSON_INDENT(2)) < 0) {
        rc = cli_input_error("fill", "%s: cannot write the report: %s",
                             report, strerror(errno));
        goto out;
    }
    printf("{\"loops\":%u,\"filled\":%u,\"planar\":%u,\"left_open\":%u,"
           "\"vertices_added\":%u,\"facets_added\":%u,"
           "\"max_dihedral_deg\":%.6g,\"valid\":%s,\"vertices\":%u,"
           "\"facets\":%u,\"ms\":%.3f}\n",
           rep.nloops, rep.nfilled, rep.nplanar, rep.nopen, rep.verts_added,
           rep.facets_added, rep.max_dihedral_deg,
           st.valid ? "true" : "false", p->nverts, p->nfacets, ms);
out:
    geo_stats_clear(&st);
out_rep:
    json_decref(fj);
    json_decref(vj);
    json_decref(doc);
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(p);
    return rc;
}
