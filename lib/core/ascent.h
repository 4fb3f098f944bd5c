/* ascent.h — the vertex of a convex polytope highest along a direction,
 * by ascent along its edges: a linear function on a convex polytope has
 * no local maximum but the global one, so from any vertex, moving to
 * the highest neighbour while one is higher ends at the top (one of
 * them, on a tie). The graph is the caller's, as offsets start[v] ..
 * start[v + 1] into the neighbour list adj (its own vertices, or
 * clusters of them). A few steps from a start near the top. */
#ifndef GEO_ASCENT_H
#define GEO_ASCENT_H

#include <stdint.h>

#include "vec.h"

/* The top along n reached from vertex from of the points x; *ret_h its
 * height n·x. */
static inline uint32_t geo_ascent_top(const uint32_t *start,
                                      const uint32_t *adj,
                                      const double (*x)[3], const double n[3],
                                      uint32_t from, double *ret_h)
{
    uint32_t top = from;
    double h = geo_vdot(n, x[top]);
    for (uint32_t at = UINT32_MAX; at != top;) {
        at = top;
        for (uint32_t a = start[at]; a < start[at + 1]; a++) {
            double s = geo_vdot(n, x[adj[a]]);
            if (s > h) {
                h = s;
                top = adj[a];
            }
        }
    }
    *ret_h = h;
    return top;
}

#endif
