/* cut_check.c — validity and volume checks of plane-cut results. */
#include "cut_check.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cut_shapes.h"
#include "stats.h"

const char *cc_inspect_problem(const geo_poly *p)
{
    static char msg[1024];
    geo_stats st;
    geo_err err = {{0}};
    if (geo_inspect(p, NULL, NULL, &st, &err) < 0) {
        snprintf(msg, sizeof msg, "inspect failed: %s", err.msg);
        return msg;
    }
    const char *bad = NULL;
    if (!st.valid) {
        snprintf(msg, sizeof msg,
                 "inspect: closed %d, nonmanifold vertices %u, low degree %u, "
                 "orientation %d, inverted %u, nonplanarity %.3g (eps %.3g), "
                 "self-intersections %u, degenerate facets %u",
                 st.closed, st.nonmanifold_vertices, st.low_degree_vertices,
                 (int)st.orientation, st.inverted_facets, st.max_nonplanarity,
                 st.eps, st.self_intersecting_facets, st.degenerate_facets);
        bad = msg;
    }
    geo_stats_clear(&st);
    return bad;
}

const char *cc_result_problem(const geo_poly *model, const geo_poly *p)
{
    const char *bad = cs_check_valid(p, 1e-9 * (1.0 + geo_poly_size(model)));
    return bad ? bad : cc_inspect_problem(p);
}

const char *cc_cut_both(const geo_poly *p, const double plane[4],
                        cc_halves *ret)
{
    static char msg[1400];
    memset(ret, 0, sizeof *ret);
    double pl[2][4];
    for (int k = 0; k < 4; k++) {
        pl[0][k] = plane[k];
        pl[1][k] = -plane[k];
    }
    for (int s = 0; s < 2; s++) {
        geo_poly *o = geo_poly_new();
        if (!o)
            return "out of memory";
        ret->code[s] = geo_cut(p, pl[s], NULL, NULL, o, &ret->rep[s], &ret->err[s]);
        if (ret->code[s] == 0 && !ret->rep[s].empty) {
            const char *bad = cc_result_problem(p, o);
            if (bad) {
                snprintf(msg, sizeof msg, "%s side: %s", s ? "opposite" : "plane's",
                         bad);
                geo_poly_free(o);
                return msg;
            }
            ret->volume[s] = geo_poly_volume(o);
        }
        geo_poly_free(o);
    }
    double vol = geo_poly_volume(p);
    if (ret->code[0] == 0 && ret->code[1] == 0 &&
        !(fabs(ret->volume[0] + ret->volume[1] - vol) <= 1e-9 * fabs(vol))) {
        snprintf(msg, sizeof msg, "volumes %.17g + %.17g != %.17g",
                 ret->volume[0], ret->volume[1], vol);
        return msg;
    }
    return NULL;
}
