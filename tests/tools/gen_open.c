/* gen_open.c — open meshes for the hole-filling collection and the CGAL
 * benchmark, generated (so no large file is kept in the repository):
 *
 *   gen_open cup N OUT        a bowl of rows on a wavy sphere whose rim
 *                             is one hole of exactly N vertices
 *   gen_open scan SEED OUT    a bumpy scanned-like blob with 4–12 holes
 *                             of every size (a few facets to a third of
 *                             the surface)
 *   gen_open cad SEED OUT     a box whose faces carry a fine grid, with
 *                             holes across its sharp edges and corners
 *   gen_open thin SEED OUT    a thin slab (20:1) with holes cut across
 *                             its thin rim, where a flat lid can cross
 *                             the other side
 *   gen_open sheet SEED OUT   an open wavy sheet with inner holes
 *
 * Holes are made by removing the facets whose centroid lies within a
 * random radius of a random point on the surface. The format follows
 * OUT's extension. Exit 0, 1 on a write error, 2 on usage. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ctx.h"
#include "gen_sphere.h"
#include "model_io.h"
#include "poly.h"

/* An n×m grid of quads, each split in two, through corner(u, v). */
typedef void (*surf_fn)(double u, double v, const void *user, double out[3]);

static void add_grid(geo_poly *p, uint32_t n, uint32_t m, surf_fn f,
                     const void *user)
{
    uint32_t base = p->nverts;
    for (uint32_t j = 0; j <= m; j++)
        for (uint32_t i = 0; i <= n; i++) {
            double x[3];
            f((double)i / n, (double)j / m, user, x);
            geo_poly_add_vertex(p, x);
        }
    for (uint32_t j = 0; j < m; j++)
        for (uint32_t i = 0; i < n; i++) {
            uint32_t a = base + j * (n + 1) + i, b = a + 1, c = a + n + 2,
                     d = a + n + 1;
            uint32_t t1[3] = {a, b, c}, t2[3] = {a, c, d};
            geo_poly_add_facet(p, t1, 3);
            geo_poly_add_facet(p, t2, 3);
        }
}

/* Removes the facets whose centroid is within r of centre. */
static void punch(geo_poly *p, const double centre[3], double r)
{
    bool *keep = malloc(p->nfacets * sizeof *keep);
    for (uint32_t f = 0; f < p->nfacets; f++) {
        double c[3];
        geo_poly_facet_center(p, f, c);
        double d2 = 0;
        for (int k = 0; k < 3; k++)
            d2 += (c[k] - centre[k]) * (c[k] - centre[k]);
        keep[f] = d2 > r * r;
    }
    geo_poly_compact(p, keep, NULL, NULL);
    free(keep);
}

/* A random vertex of p: a point on its surface. */
static const double *random_point(const geo_poly *p, uint64_t *seed)
{
    return p->verts[geo_rand_next(seed) % p->nverts];
}

static geo_poly *gen_cup(uint32_t n)
{
    geo_poly *p = geo_poly_new();
    const uint32_t rows = 8;
    double d = 2 * M_PI / n;
    for (uint32_t j = 0; j < rows; j++)
        for (uint32_t i = 0; i < n; i++) {
            double a = d * i, phi = -d * j * 4;
            double x[3] = {cos(phi) * cos(a), cos(phi) * sin(a),
                           sin(phi) + 0.1 * cos(3 * a)};
            geo_poly_add_vertex(p, x);
        }
    double bottom[3] = {0, 0, -1.2};
    geo_poly_add_vertex(p, bottom);
    for (uint32_t j = 0; j + 1 < rows; j++)
        for (uint32_t i = 0; i < n; i++) {
            uint32_t a = j * n + i, b = j * n + (i + 1) % n, c = b + n,
                     e = a + n;
            uint32_t t1[3] = {a, e, c}, t2[3] = {a, c, b};
            geo_poly_add_facet(p, t1, 3);
            geo_poly_add_facet(p, t2, 3);
        }
    uint32_t last = (rows - 1) * n, apex = rows * n;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t t[3] = {last + i, apex, last + (i + 1) % n};
        geo_poly_add_facet(p, t, 3);
    }
    return p;
}

static geo_poly *gen_scan(uint64_t seed)
{
    geo_poly *p = gs_sphere(24, 10.0);
    double f1 = 2 + geo_rand_unit(&seed) * 3, f2 = 1 + geo_rand_unit(&seed) * 3;
    for (uint32_t v = 0; v < p->nverts; v++) {
        double *x = p->verts[v];
        double s = 1 + 0.08 * sin(f1 * x[0] / 10) * sin(f2 * x[1] / 10) +
                   0.04 * cos(3 * x[2] / 10);
        for (int k = 0; k < 3; k++)
            x[k] *= s;
    }
    uint32_t nh = 4 + (uint32_t)(geo_rand_next(&seed) % 9);
    for (uint32_t h = 0; h < nh && p->nverts > 0; h++) {
        double c[3];
        memcpy(c, random_point(p, &seed), sizeof c);
        /* sizes from a couple of facets (0.6 mm) to a third of the blob
         * across (7.5 mm of a 10 mm radius) */
        double r = 0.6 * pow(10.0, geo_rand_unit(&seed) * 1.1);
        punch(p, c, r);
    }
    return p;
}

typedef struct face_def {
    double o[3], u[3], v[3];
} face_def;

static void face_point(double u, double v, const void *user, double out[3])
{
    const face_def *fd = user;
    for (int k = 0; k < 3; k++)
        out[k] = fd->o[k] + u * fd->u[k] + v * fd->v[k];
}

/* A box lo..hi whose faces carry grids of about cell mm, outward. The
 * shared edges repeat vertices: merged afterwards by welding. */
static geo_poly *grid_box(const double lo[3], const double hi[3], double cell)
{
    geo_poly *p = geo_poly_new();
    double s[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
    for (int ax = 0; ax < 3; ax++)
        for (int side = 0; side < 2; side++) {
            int a = (ax + 1) % 3, b = (ax + 2) % 3;
            face_def fd = {{0}, {0}, {0}};
            memcpy(fd.o, lo, sizeof fd.o);
            fd.o[ax] = side ? hi[ax] : lo[ax];
            /* u × v must point out of the box */
            int ua = side ? a : b, va = side ? b : a;
            fd.u[ua] = s[ua];
            fd.v[va] = s[va];
            uint32_t nu = (uint32_t)ceil(s[ua] / cell),
                     nv = (uint32_t)ceil(s[va] / cell);
            add_grid(p, nu, nv, face_point, &fd);
        }
    /* weld the repeated edge vertices (exact: the grids share them) */
    uint32_t *map = malloc(p->nverts * sizeof *map);
    for (uint32_t v = 0; v < p->nverts; v++) {
        map[v] = v;
        for (uint32_t w = 0; w < v; w++)
            if (map[w] == w && memcmp(p->verts[v], p->verts[w],
                                      sizeof p->verts[v]) == 0) {
                map[v] = w;
                break;
            }
    }
    for (size_t c = 0; c < geo_poly_ncorners(p); c++)
        p->fidx[c] = map[p->fidx[c]];
    free(map);
    geo_poly_compact(p, NULL, NULL, NULL);
    return p;
}

static geo_poly *gen_cad(uint64_t seed)
{
    double lo[3] = {0, 0, 0}, hi[3] = {20, 12, 8};
    geo_poly *p = grid_box(lo, hi, 1.0);
    uint32_t nh = 3 + (uint32_t)(geo_rand_next(&seed) % 4);
    for (uint32_t h = 0; h < nh; h++) {
        /* a point on one of the 12 edges (or a corner) */
        double c[3];
        int ax = (int)(geo_rand_next(&seed) % 3);
        for (int k = 0; k < 3; k++)
            c[k] = geo_rand_next(&seed) % 2 ? hi[k] : lo[k];
        c[ax] = lo[ax] + geo_rand_unit(&seed) * (hi[ax] - lo[ax]);
        punch(p, c, 1.2 + geo_rand_unit(&seed) * 2.5);
    }
    return p;
}

static geo_poly *gen_thin(uint64_t seed)
{
    double lo[3] = {0, 0, 0}, hi[3] = {20, 20, 1};
    geo_poly *p = grid_box(lo, hi, 0.5);
    uint32_t nh = 2 + (uint32_t)(geo_rand_next(&seed) % 3);
    for (uint32_t h = 0; h < nh; h++) {
        /* centred on the thin rim, or just inside it on top */
        double c[3] = {geo_rand_unit(&seed) * 20, 0, 1};
        c[1] = geo_rand_next(&seed) % 2 ? 0.2 : 1.5;
        punch(p, c, 1.0 + geo_rand_unit(&seed) * 1.5);
    }
    return p;
}

typedef struct wave {
    double a, b;
} wave;

static void sheet_point(double u, double v, const void *user, double out[3])
{
    const wave *w = user;
    out[0] = 30 * u;
    out[1] = 20 * v;
    out[2] = 2 * sin(w->a * u * 6) * cos(w->b * v * 4);
}

static geo_poly *gen_sheet(uint64_t seed)
{
    geo_poly *p = geo_poly_new();
    wave w = {0.5 + geo_rand_unit(&seed), 0.5 + geo_rand_unit(&seed)};
    add_grid(p, 60, 40, sheet_point, &w);
    uint32_t nh = 2 + (uint32_t)(geo_rand_next(&seed) % 4);
    for (uint32_t h = 0; h < nh; h++) {
        double c[3];
        sheet_point(0.15 + 0.7 * geo_rand_unit(&seed),
                    0.15 + 0.7 * geo_rand_unit(&seed), &w, c);
        punch(p, c, 0.8 + geo_rand_unit(&seed) * 2.5);
    }
    return p;
}

int main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: gen_open cup N OUT | "
                        "{scan|cad|thin|sheet} SEED OUT\n");
        return 2;
    }
    const char *kind = argv[1];
    uint64_t arg = strtoull(argv[2], NULL, 10);
    uint64_t seed = arg * 0x9e3779b97f4a7c15ull + 1;
    geo_poly *p = NULL;
    if (strcmp(kind, "cup") == 0 && arg >= 3)
        p = gen_cup((uint32_t)arg);
    else if (strcmp(kind, "scan") == 0)
        p = gen_scan(seed);
    else if (strcmp(kind, "cad") == 0)
        p = gen_cad(seed);
    else if (strcmp(kind, "thin") == 0)
        p = gen_thin(seed);
    else if (strcmp(kind, "sheet") == 0)
        p = gen_sheet(seed);
    else {
        fprintf(stderr, "gen_open: unknown kind '%s'\n", kind);
        return 2;
    }
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    geo_err err = {{0}};
    int r = proto_model_write_file(p, argv[3], PROTO_FMT_UNKNOWN, &err);
    geo_poly_free(p);
    if (r < 0) {
        fprintf(stderr, "gen_open: %s\n", err.msg);
        return 1;
    }
    return 0;
}
