/* gen_scanmesh.c — writes a scanned-like triangle mesh for the inspection
 * benchmarks: a closed, star-shaped, lumpy surface (a statue-like blob)
 * sampled irregularly, as a laser or structured-light scan comes out of
 * surface reconstruction: no planes in the file, uneven triangles, random
 * edge directions, sub-millimetre noise on every vertex.
 *
 *   gen_scanmesh --triangles N [--seed S] [--radius R] [--sphere]
 *                OUT.json|OUT.obj...
 *
 * Construction: a cube-sphere lattice (n×n cells per cube face, 12·n²
 * triangles, n chosen so that the count is the nearest to N) whose points
 * are moved within their cell by up to 0.25 of a cell (tangentially, by a
 * hash of the lattice point, so the faces sharing a point agree), each
 * cell split along a random diagonal, then every point pushed radially to
 * r(u) = R·(1 + Σ bumps(u)) + noise. A radial displacement of a valid
 * spherical triangulation cannot fold it, so the mesh is closed, outward
 * and free of self-intersections, like a cleaned scan. The .json file is
 * facet-model/1 without planes (the reader fits them); any other
 * extension is written by proto_model_write_file. --sphere writes the
 * plain cube-sphere of tests/support/gen_sphere.h instead (the 1M-triangle
 * benchmark sphere: --triangles 1000000 gives 1,002,252). Prints
 * "triangles=T vertices=V" and exits 0; 1 on failure, 2 on bad usage. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gen_sphere.h"
#include "model_io.h"
#include "vec.h"

static int usage(const char *msg)
{
    fprintf(stderr, "gen_scanmesh: %s\nusage: gen_scanmesh --triangles N "
            "[--seed S] [--radius R] [--sphere] OUT.json|OUT.obj...\n", msg);
    return 2;
}

static uint64_t mix(uint64_t x)
{
    x ^= x >> 33;
    x *= 0xff51afd7ed558ccdULL;
    x ^= x >> 33;
    x *= 0xc4ceb9fe1a85ec53ULL;
    x ^= x >> 33;
    return x;
}

/* A uniform double in [-1, 1) from a key. */
static double signed_unit(uint64_t key)
{
    return (double)(mix(key) >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

typedef struct blob {
    double radius;
    uint64_t seed;
    double dir[12][3], amp[12], freq[12], phase[12];
} blob;

static void blob_init(blob *b, uint64_t seed, double radius)
{
    b->radius = radius;
    b->seed = seed;
    for (int k = 0; k < 12; k++) {
        double d[3];
        for (int i = 0; i < 3; i++)
            d[i] = signed_unit(seed * 131 + (uint64_t)(k * 3 + i));
        if (geo_vnormalize(d) == 0)
            d[0] = 1;
        memcpy(b->dir[k], d, sizeof d);
        /* a few broad lumps, then finer folds, as on a carved figure */
        b->freq[k] = 1.5 + k * 0.9;
        b->amp[k] = 0.12 / (1.0 + 0.6 * k);
        b->phase[k] = 3.0 * signed_unit(seed * 977 + (uint64_t)k);
    }
}

/* The surface point in unit direction u for lattice key `key`. */
static void blob_point(const blob *b, const double u[3], uint64_t key,
                       double ret[3])
{
    double r = 1.0;
    for (int k = 0; k < 12; k++)
        r += b->amp[k] * sin(b->freq[k] * geo_vdot(u, b->dir[k]) +
                             b->phase[k]);
    r = b->radius * r + 2e-4 * b->radius * signed_unit(key ^ (b->seed << 40));
    geo_vscale(u, r, ret);
}

typedef struct lattice {
    uint64_t *keys;
    uint32_t *vals;
    size_t mask;
} lattice;

/* The vertex of lattice point ijk, adding it to p if new; −1 on OOM. */
static int64_t vertex_at(geo_poly *p, lattice *L, const blob *b,
                         const uint32_t ijk[3], uint32_t n)
{
    uint64_t key =
        ((uint64_t)ijk[0] << 42 | (uint64_t)ijk[1] << 21 | ijk[2]) + 1;
    size_t s = mix(key) & L->mask;
    while (L->keys[s] && L->keys[s] != key)
        s = (s + 1) & L->mask;
    if (L->keys[s])
        return L->vals[s];
    double x[3];
    for (int k = 0; k < 3; k++) {
        /* the point moves within its cell along the two axes of the cube
         * faces it lies on (not along the axis it is pinned to) */
        double t = ijk[k];
        if (ijk[k] != 0 && ijk[k] != n)
            t += 0.25 * signed_unit(key * 7 + (uint64_t)k + (b->seed << 20));
        x[k] = tan(M_PI / 4 * (-1.0 + 2.0 * t / n));
    }
    geo_vnormalize(x);
    double y[3];
    blob_point(b, x, key, y);
    int64_t v = geo_poly_add_vertex(p, y);
    if (v < 0)
        return -1;
    L->keys[s] = key;
    L->vals[s] = (uint32_t)v;
    return v;
}

static geo_poly *scanmesh(uint32_t n, const blob *b)
{
    size_t nv = 6 * (size_t)n * n + 2, cap = 16;
    while (cap < 2 * nv)
        cap <<= 1;
    lattice L = {calloc(cap, sizeof *L.keys), malloc(cap * sizeof *L.vals),
                 cap - 1};
    geo_poly *p = geo_poly_new();
    if (!L.keys || !L.vals || !p ||
        geo_poly_reserve(p, nv, 12 * (size_t)n * n, 36 * (size_t)n * n) < 0)
        goto oom;
    for (int axis = 0; axis < 3; axis++)
        for (int sign = -1; sign <= 1; sign += 2) {
            int u = (axis + 1) % 3, v = (axis + 2) % 3;
            if (sign < 0) {
                int t = u;
                u = v;
                v = t;
            }
            for (uint32_t a = 0; a < n; a++)
                for (uint32_t c = 0; c < n; c++) {
                    static const uint32_t da[4] = {0, 1, 1, 0},
                                          dc[4] = {0, 0, 1, 1};
                    uint32_t q[4];
                    for (int k = 0; k < 4; k++) {
                        uint32_t ijk[3];
                        ijk[axis] = sign > 0 ? n : 0;
                        ijk[u] = a + da[k];
                        ijk[v] = c + dc[k];
                        int64_t id = vertex_at(p, &L, b, ijk, n);
                        if (id < 0)
                            goto oom;
                        q[k] = (uint32_t)id;
                    }
                    /* either diagonal of the cell, at random */
                    int d = (int)(mix(b->seed ^ ((uint64_t)axis << 50) ^
                                      ((uint64_t)(sign + 1) << 48) ^
                                      ((uint64_t)a << 24) ^ c) & 1);
                    uint32_t t1[3] = {q[d], q[d + 1], q[(d + 2) % 4]};
                    uint32_t t2[3] = {q[d], q[(d + 2) % 4], q[(d + 3) % 4]};
                    if (geo_poly_add_facet(p, t1, 3) < 0 ||
                        geo_poly_add_facet(p, t2, 3) < 0)
                        goto oom;
                }
        }
    free(L.keys);
    free(L.vals);
    return p;
oom:
    free(L.keys);
    free(L.vals);
    return geo_poly_free(p);
}

/* facet-model/1 without planes, as a scan comes from reconstruction. */
static int write_json(const geo_poly *p, const char *path)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return -errno;
    fputs("{\"format\":\"facet-model/1\",\"units\":\"mm\",\n\"vertices\":[\n",
          f);
    for (uint32_t v = 0; v < p->nverts; v++)
        fprintf(f, "[%.17g,%.17g,%.17g]%s\n", p->verts[v][0], p->verts[v][1],
                p->verts[v][2], v + 1 < p->nverts ? "," : "");
    fputs("],\n\"facets\":[\n", f);
    for (uint32_t t = 0; t < p->nfacets; t++) {
        const uint32_t *x = geo_poly_facet(p, t);
        fprintf(f, "{\"vertices\":[%u,%u,%u]}%s\n", x[0], x[1], x[2],
                t + 1 < p->nfacets ? "," : "");
    }
    fputs("]}\n", f);
    int bad = ferror(f);
    if (fclose(f) != 0 || bad)
        return -EIO;
    return 0;
}

int main(int argc, char **argv)
{
    unsigned long tris = 0, seed = 1;
    double radius = 50.0;
    int first_out = 0;
    bool sphere = false;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        char *end;
        if (strcmp(a, "--sphere") == 0) {
            sphere = true;
        } else if (strcmp(a, "--triangles") == 0 || strcmp(a, "--seed") == 0 ||
            strcmp(a, "--radius") == 0) {
            if (i + 1 == argc)
                return usage("an option needs a value");
            const char *val = argv[++i];
            errno = 0;
            if (a[2] == 'r') {
                radius = strtod(val, &end);
                if (errno || *end || !(radius > 0) || radius > 1e4)
                    return usage("--radius: expected 0 < R <= 10000 mm");
            } else {
                unsigned long x = strtoul(val, &end, 10);
                if (errno || end == val || *end || x > 100000000UL)
                    return usage("expected a number");
                *(a[2] == 't' ? &tris : &seed) = x;
            }
        } else if (a[0] == '-') {
            return usage("unknown option");
        } else {
            first_out = i;
            break;
        }
    }
    if (tris < 12 || !first_out)
        return usage("needs --triangles N (N >= 12) and an output file");
    uint32_t n = (uint32_t)lround(sqrt((double)tris / 12.0));
    if (n < 1)
        n = 1;
    blob b;
    blob_init(&b, seed, radius);
    geo_poly *p = sphere ? gs_sphere(n, radius) : scanmesh(n, &b);
    if (!p) {
        fprintf(stderr, "gen_scanmesh: out of memory\n");
        return 1;
    }
    for (int i = first_out; i < argc; i++) {
        const char *path = argv[i];
        size_t len = strlen(path);
        int r;
        geo_err err = {{0}};
        if (len > 5 && strcmp(path + len - 5, ".json") == 0)
            r = write_json(p, path);
        else
            r = proto_model_write_file(p, path, PROTO_FMT_UNKNOWN, &err);
        if (r < 0) {
            fprintf(stderr, "gen_scanmesh: %s: %s\n", path,
                    err.msg[0] ? err.msg : strerror(-r));
            geo_poly_free(p);
            return 1;
        }
    }
    printf("triangles=%u vertices=%u\n", p->nfacets, p->nverts);
    geo_poly_free(p);
    return 0;
}
