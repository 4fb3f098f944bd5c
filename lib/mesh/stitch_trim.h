/* stitch_trim.h — halves that overlap, made to meet (step 5c of
 * lib/mesh/stitch.h).
 *
 * Two open meshes whose chosen loops are planar and lie each inside the
 * other's body — the plane of loop 1 has loop 2 wholly on mesh 1's side
 * and the other way round, both beyond tol — overlap: two scans of one
 * stone that both reach past the joint. Each is closed by its loop as one
 * facet, cut (lib/cut/cut.h, exact sides) at the plane midway between the
 * two loops' planes, and opened again by dropping the cut's new facets:
 * both now end on one plane, in loops of one polyline where they are the
 * same surface there, which step 5a welds.
 *
 * Not trimmed (returns 0, nothing allocated): loops off their plane by
 * more than tol, planes more than 45° from facing each other, loops not
 * each inside the other's body, or a half the cut refuses (one that is
 * not closed by its loop: other holes; one the plane leaves empty). */
#ifndef GEO_STITCH_TRIM_H
#define GEO_STITCH_TRIM_H

#include <stdint.h>

#include "poly.h"

/* The plane of the n vertices v of p (Newell normal, unit, through their
 * mean) into pl. False when the loop has no area. */
bool geo_loop_plane(const geo_poly *p, const uint32_t *v, uint32_t n,
                    double pl[4]);

/* 1 when the loops overlap as above: *t1 and *t2 are the trimmed copies
 * of m1 and m2 (release with geo_poly_free), their loops on the plane
 * mid[4] (positive towards mesh 2's side). 0 when not, -ENOMEM. l1 and
 * l2 run along their meshes' facets (each edge v[q] → v[q + 1] a
 * facet's). */
int geo_stitch_trim(const geo_poly *m1, const uint32_t *l1, uint32_t n1,
                    const geo_poly *m2, const uint32_t *l2, uint32_t n2,
                    double tol, geo_poly **t1, geo_poly **t2,
                    double mid[4]);

#endif
