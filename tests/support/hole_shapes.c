/* hole_shapes.c — polyhedra with holed sections for the plane-cut tests:
 * prisms over cell maps, a hollow box, a ring with a saddle. */
#include "hole_shapes.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

typedef struct grid {
    const char *const *rows;
    uint32_t nrows, ncols;
    uint32_t *vid; /* per grid point and level: vertex id or UINT32_MAX */
    double *v;
    uint32_t nv;
} grid;

static bool solid(const grid *g, int r, int c)
{
    return r >= 0 && c >= 0 && (uint32_t)r < g->nrows && (uint32_t)c < g->ncols &&
           g->rows[r][c] == '#';
}

/* Vertex at grid point (x, y), level 0 (bottom) or 1 (top). */
static uint32_t gv(grid *g, uint32_t x, uint32_t y, int level, double h)
{
    size_t k = ((size_t)y * (g->ncols + 1) + x) * 2 + (size_t)level;
    if (g->vid[k] == UINT32_MAX) {
        g->vid[k] = g->nv;
        g->v[3 * g->nv] = x;
        g->v[3 * g->nv + 1] = y;
        g->v[3 * g->nv + 2] = level ? h : 0;
        g->nv++;
    }
    return g->vid[k];
}

geo_poly *hs_grid_prism(const char *const *rows, uint32_t nrows, double h)
{
    grid g = {rows, nrows, (uint32_t)strlen(rows[0]), NULL, NULL, 0};
    size_t npts = (size_t)(g.ncols + 1) * (nrows + 1) * 2;
    size_t cells = (size_t)g.ncols * nrows;
    g.vid = malloc(npts * sizeof *g.vid);
    g.v = malloc(npts * 3 * sizeof *g.v);
    uint32_t *idx = malloc(cells * 6 * 4 * sizeof *idx);
    uint32_t *start = malloc((cells * 6 + 1) * sizeof *start);
    geo_poly *p = NULL;
    if (!g.vid || !g.v || !idx || !start)
        goto done;
    memset(g.vid, 0xff, npts * sizeof *g.vid);
    uint32_t c = 0, f = 0;
    for (uint32_t r = 0; r < nrows; r++)
        for (uint32_t col = 0; col < g.ncols; col++) {
            if (!solid(&g, (int)r, (int)col))
                continue;
            uint32_t x = col, y = nrows - 1 - r;
            /* corners counter-clockwise from above: (x,y) (x+1,y)
             * (x+1,y+1) (x,y+1) */
            uint32_t cx[4] = {x, x + 1, x + 1, x}, cy[4] = {y, y, y + 1, y + 1};
            start[f++] = c;
            for (int k = 0; k < 4; k++)
                idx[c++] = gv(&g, cx[k], cy[k], 1, h);
            start[f++] = c;
            for (int k = 4; k-- > 0;)
                idx[c++] = gv(&g, cx[k], cy[k], 0, h);
            /* sides k → k+1 run with the cell on their left; neighbours
             * south, east, north, west */
            static const int dr[4] = {1, 0, -1, 0}, dc[4] = {0, 1, 0, -1};
            for (int k = 0; k < 4; k++) {
                if (solid(&g, (int)r + dr[k], (int)col + dc[k]))
                    continue;
                int k1 = (k + 1) % 4;
                start[f++] = c;
                idx[c++] = gv(&g, cx[k], cy[k], 0, h);
                idx[c++] = gv(&g, cx[k1], cy[k1], 0, h);
                idx[c++] = gv(&g, cx[k1], cy[k1], 1, h);
                idx[c++] = gv(&g, cx[k], cy[k], 1, h);
            }
        }
    start[f] = c;
    p = geo_poly_from_arrays(g.nv, g.v, f, start, idx, NULL, NULL);
done:
    free(g.vid), free(g.v), free(idx), free(start);
    return p;
}

geo_poly *hs_hollow_box(const double lo[3], const double hi[3],
                        const double ilo[3], const double ihi[3])
{
    double v[16][3];
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++) {
            v[i][k] = (i >> k) & 1 ? hi[k] : lo[k];
            v[8 + i][k] = (i >> k) & 1 ? ihi[k] : ilo[k];
        }
    /* counter-clockwise seen from outside the box */
    static const uint32_t box[24] = {0, 2, 3, 1, 4, 5, 7, 6, 0, 1, 5, 4,
                                     2, 6, 7, 3, 0, 4, 6, 2, 1, 3, 7, 5};
    uint32_t idx[48], start[13];
    for (uint32_t f = 0; f < 12; f++)
        start[f] = 4 * f;
    start[12] = 48;
    for (int i = 0; i < 24; i++)
        idx[i] = box[i];
    /* the cavity's facets reversed: they face into the cavity */
    for (int f = 0; f < 6; f++)
        for (int k = 0; k < 4; k++)
            idx[24 + 4 * f + k] = 8 + box[4 * f + 3 - k];
    return geo_poly_from_arrays(16, &v[0][0], 12, start, idx, NULL, NULL);
}

geo_poly *hs_saddle_ring(void)
{
    static const double v[19][3] = {
        {0, 0, 0}, {10, 0, 0}, {10, 10, 0}, {0, 10, 0},   /* outer bottom */
        {3, 3, 0}, {7, 3, 0},  {7, 7, 0},   {3, 7, 0},    /* inner bottom */
        {0, 0, 4}, {10, 0, 4}, {10, 10, 4}, {0, 10, 4},   /* outer top */
        {3, 3, 4}, {7, 3, 4},  {7, 7, 4},   {3, 7, 4},    /* inner top */
        {5, 1.5, 2},                                      /* the saddle */
        {5, 0, 1}, {5, 3, 1}};   /* dips of the outer and inner top edge */
    uint32_t idx[96], start[32], c = 0, f = 0;
    for (uint32_t i = 0; i < 4; i++) {
        uint32_t j = (i + 1) % 4;
        start[f++] = c; /* bottom trapezoid */
        idx[c++] = j, idx[c++] = i, idx[c++] = 4 + i, idx[c++] = 4 + j;
        start[f++] = c; /* outer wall, with the dip on the south */
        idx[c++] = i, idx[c++] = j, idx[c++] = 8 + j;
        if (i == 0)
            idx[c++] = 17;
        idx[c++] = 8 + i;
        start[f++] = c; /* inner wall, facing into the hole */
        idx[c++] = 4 + j, idx[c++] = 4 + i, idx[c++] = 12 + i;
        if (i == 0)
            idx[c++] = 18;
        idx[c++] = 12 + j;
        if (i == 0)
            continue;
        start[f++] = c; /* top trapezoid */
        idx[c++] = 8 + i, idx[c++] = 8 + j, idx[c++] = 12 + j, idx[c++] = 12 + i;
    }
    /* the south bar's top: a fan around the saddle, counter-clockwise
     * from above */
    static const uint32_t ring[6] = {17, 9, 13, 18, 12, 8};
    for (int k = 0; k < 6; k++) {
        start[f++] = c;
        idx[c++] = HS_SADDLE, idx[c++] = ring[k], idx[c++] = ring[(k + 1) % 6];
    }
    start[f] = c;
    return geo_poly_from_arrays(19, &v[0][0], f, start, idx, NULL, NULL);
}

geo_poly *hs_torus(uint32_t nu, uint32_t nv, double R, double r)
{
    size_t nvert = (size_t)nu * nv, nf = 2 * nvert;
    double *v = malloc(nvert * 3 * sizeof *v);
    uint32_t *idx = malloc(nf * 3 * sizeof *idx);
    uint32_t *start = malloc((nf + 1) * sizeof *start);
    geo_poly *p = NULL;
    if (!v || !idx || !start)
        goto done;
    for (uint32_t i = 0; i < nu; i++)
        for (uint32_t j = 0; j < nv; j++) {
            double u = 2 * M_PI * i / nu, w = 2 * M_PI * (j + 0.5) / nv;
            size_t k = 3 * ((size_t)i * nv + j);
            v[k] = (R + r * cos(w)) * cos(u);
            v[k + 1] = (R + r * cos(w)) * sin(u);
            v[k + 2] = r * sin(w);
        }
    size_t c = 0, f = 0;
    for (uint32_t i = 0; i < nu; i++)
        for (uint32_t j = 0; j < nv; j++) {
            uint32_t a = i * nv + j, b = ((i + 1) % nu) * nv + j;
            uint32_t a1 = i * nv + (j + 1) % nv, b1 = ((i + 1) % nu) * nv + (j + 1) % nv;
            start[f++] = (uint32_t)c;
            idx[c++] = a, idx[c++] = b, idx[c++] = b1;
            start[f++] = (uint32_t)c;
            idx[c++] = a, idx[c++] = b1, idx[c++] = a1;
        }
    start[f] = (uint32_t)c;
    p = geo_poly_from_arrays((uint32_t)nvert, v, (uint32_t)nf, start, idx, NULL,
                             NULL);
done:
    free(v), free(idx), free(start);
    return p;
}
