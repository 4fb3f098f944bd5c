/* gen_sphere.c — cube-sphere: lattice points (I, J, K) ∈ [0, n]³ on the
 * cube's surface are numbered once through a hash (edges and corners are
 * shared by the faces that meet there), so the mesh is closed. */
#include "gen_sphere.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "vec.h"

typedef struct lattice {
    uint64_t *keys;
    uint32_t *vals;
    size_t mask;
} lattice;

static uint64_t mix(uint64_t x)
{
    x ^= x >> 33;
    x *= 0xff51afd7ed558ccdULL;
    x ^= x >> 33;
    return x;
}

/* The vertex of lattice point ijk, adding it to p if new; −1 on OOM. */
static int64_t vertex_at(geo_poly *p, lattice *L, const uint32_t ijk[3],
                         uint32_t n, double radius)
{
    uint64_t key = ((uint64_t)ijk[0] << 42 | (uint64_t)ijk[1] << 21 | ijk[2]) + 1;
    size_t s = mix(key) & L->mask;
    while (L->keys[s] && L->keys[s] != key)
        s = (s + 1) & L->mask;
    if (L->keys[s])
        return L->vals[s];
    double x[3];
    for (int k = 0; k < 3; k++)
        x[k] = tan(M_PI / 4 * (-1.0 + 2.0 * ijk[k] / n));
    geo_vnormalize(x);
    geo_vscale(x, radius, x);
    int64_t v = geo_poly_add_vertex(p, x);
    if (v < 0)
        return -1;
    L->keys[s] = key;
    L->vals[s] = (uint32_t)v;
    return v;
}

geo_poly *gs_sphere(uint32_t n, double radius)
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
            /* u, v span the face with u × v = sign · e_axis (outward) */
            int u = (axis + 1) % 3, v = (axis + 2) % 3;
            if (sign < 0) {
                int t = u;
                u = v;
                v = t;
            }
            for (uint32_t a = 0; a < n; a++)
                for (uint32_t b = 0; b < n; b++) {
                    uint32_t q[4];
                    static const uint32_t da[4] = {0, 1, 1, 0},
                                          db[4] = {0, 0, 1, 1};
                    for (int c = 0; c < 4; c++) {
                        uint32_t ijk[3];
                        ijk[axis] = sign > 0 ? n : 0;
                        ijk[u] = a + da[c];
                        ijk[v] = b + db[c];
                        int64_t id = vertex_at(p, &L, ijk, n, radius);
                        if (id < 0)
                            goto oom;
                        q[c] = (uint32_t)id;
                    }
                    uint32_t t1[3] = {q[0], q[1], q[2]}, t2[3] = {q[0], q[2], q[3]};
                    if (geo_poly_add_facet(p, t1, 3) < 0 ||
                        geo_poly_add_facet(p, t2, 3) < 0)
                        goto oom;
                }
        }
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    free(L.keys);
    free(L.vals);
    return p;
oom:
    free(L.keys);
    free(L.vals);
    return geo_poly_free(p);
}
