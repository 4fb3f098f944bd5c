/* gen_garbage.c — random garbage polyhedra (gen_garbage.h). */
#include "gen_garbage.h"

#include "ctx.h"

geo_poly *gen_garbage_model(uint64_t *rng)
{
    geo_poly *p = geo_poly_new();
    if (!p)
        return NULL;
    uint32_t nv = 4 + (uint32_t)(geo_rand_next(rng) % 12);
    for (uint32_t v = 0; v < nv; v++) {
        double x[3];
        for (int k = 0; k < 3; k++)
            x[k] = (double)(geo_rand_next(rng) % 3);
        if (geo_poly_add_vertex(p, x) < 0)
            return geo_poly_free(p);
    }
    uint32_t nf = 1 + (uint32_t)(geo_rand_next(rng) % 20);
    for (uint32_t f = 0; f < nf; f++) {
        uint32_t n = 3 + (uint32_t)(geo_rand_next(rng) % 5), idx[8];
        for (uint32_t i = 0; i < n; i++) {
            idx[i] = (uint32_t)(geo_rand_next(rng) % nv);
            if (i && idx[i] == idx[i - 1])
                idx[i] = (idx[i] + 1) % nv;
        }
        if (idx[n - 1] == idx[0])
            n--;
        if (n >= 3 && idx[n - 1] != idx[0] && geo_poly_add_facet(p, idx, n) < 0)
            return geo_poly_free(p);
    }
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    return p;
}
