/* weld.h — closing the seams of a mesh whose facets do not share the
 * vertices they meet at: meshes from other tools often repeat a vertex
 * on each side of a seam (a texture seam of an OBJ, a face-by-face CAD
 * export), and the seam then reads as a hole no patch can fill (its two
 * sides coincide).
 *
 * Boundary vertices at exactly the same point (every coordinate equal)
 * become one, the lowest index; the vertices left unused are removed
 * and the others renumbered down in order (facets keep their indices).
 * The weld is all or nothing: it is kept only when it closes some
 * boundary edge and leaves no facet with a repeated vertex and no edge
 * or vertex non-manifold, and no edge flipped, beyond what p had; two
 * parts that only touch at a point stay apart. Exact equality, not a
 * tolerance: a weld never moves a vertex. */
#ifndef GEO_WELD_H
#define GEO_WELD_H

#include <stdint.h>

#include "ctx.h"
#include "poly.h"
#include "topo.h"

/* Welds p's coincident boundary vertices as above, t being p's topology
 * (no longer p's when a weld is kept); *ret_welded is the number of
 * vertices removed (0: p unchanged). 0 or -ENOMEM (err set, p
 * unchanged). */
int geo_weld_boundary(geo_poly *p, const geo_topo *t, uint32_t *ret_welded,
                      geo_err *err);

#endif
