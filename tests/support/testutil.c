/* testutil.c — shared fixtures of the unit tests. */
#include "testutil.h"

#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>

#include "stats.h"

const char *tu_models_dir(void)
{
    const char *env = getenv("FACET_MODELS");
    if (env && *env)
        return env;
    struct stat st;
    if (stat("tests/data/models", &st) == 0 && S_ISDIR(st.st_mode))
        return "tests/data/models";
    return "../shared/models";
}

const char *tu_model_path(const char *name)
{
    static char buf[4096];
    snprintf(buf, sizeof buf, "%s/%s", tu_models_dir(), name);
    return buf;
}

geo_poly *tu_box(const double lo[3], const double hi[3])
{
    double v[8][3];
    for (int i = 0; i < 8; i++) {
        v[i][0] = (i & 1) ? hi[0] : lo[0];
        v[i][1] = (i & 2) ? hi[1] : lo[1];
        v[i][2] = (i & 4) ? hi[2] : lo[2];
    }
    /* counter-clockwise seen from outside */
    static const uint32_t idx[] = {0, 2, 3, 1, /* z = lo */
                                   4, 5, 7, 6, /* z = hi */
                                   0, 1, 5, 4, /* y = lo */
                                   2, 6, 7, 3, /* y = hi */
                                   0, 4, 6, 2, /* x = lo */
                                   1, 3, 7, 5}; /* x = hi */
    static const uint32_t start[] = {0, 4, 8, 12, 16, 20, 24};
    return geo_poly_from_arrays(8, &v[0][0], 6, start, idx, NULL, NULL);
}

geo_poly *tu_seed003_example(void)
{
    /* P as printed in "Tests of graphic elements" (columns x, y, z); G uses 1-based indices
     * there, 0-based here; the seven facets as listed (the y = 0 side is
     * not among them, so the example is open). */
    static const double v[11][3] = {
        {0, 5, 0}, {0, 2, 6}, {3, 2, 6}, {3, 2, 0}, {4, 5, 0}, {0, 0, 6},
        {4, 0, 6}, {4, 0, 0}, {4, 1, 0}, {4, 1, 6}, {0, 0, 0}};
    static const uint32_t idx[] = {0, 1, 2, 4,          /* G1 */
                                   1, 2, 9, 6, 5,       /* G2 */
                                   2, 3, 4,             /* G3 */
                                   2, 3, 8, 9,          /* G4 */
                                   6, 7, 8, 9,          /* G5 */
                                   4, 3, 8, 7, 10, 0,   /* G6 */
                                   0, 1, 5, 10};        /* G7 */
    static const uint32_t start[] = {0, 4, 9, 12, 16, 20, 26, 30};
    return geo_poly_from_arrays(11, &v[0][0], 7, start, idx, NULL, NULL);
}

geo_poly *tu_notch_cube(void)
{
    static const double v[16][3] = {
        {0, 0, 0}, {10, 0, 0}, {10, 10, 0}, {0, 10, 0}, {0, 0, 10},
        {10, 0, 10}, {10, 10, 10}, {0, 10, 10}, {10, 3, 10}, {6, 3, 10},
        {6, 7, 10}, {10, 7, 10}, {10, 3, 6}, {10, 7, 6}, {6, 3, 6},
        {6, 7, 6}};
    static const uint32_t idx[] = {0, 3, 2, 1,  4, 5, 8, 9, 10, 11, 6, 7,
                                   0, 1, 5, 4,  2, 3, 7, 6,  0, 4, 7, 3,
                                   1, 2, 6, 11, 13, 12, 8, 5,
                                   14, 12, 13, 15, 9, 8, 12, 14,
                                   10, 15, 13, 11, 9, 14, 15, 10};
    static const uint32_t start[] = {0, 4, 12, 16, 20, 24, 32, 36, 40, 44, 48};
    return geo_poly_from_arrays(16, &v[0][0], 10, start, idx, NULL, NULL);
}

bool tu_is_valid(const geo_poly *p)
{
    geo_stats st;
    if (geo_inspect(p, NULL, NULL, &st, NULL) < 0)
        return false;
    bool v = st.valid;
    geo_stats_clear(&st);
    return v;
}
