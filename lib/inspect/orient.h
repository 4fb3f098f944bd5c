/* orient.h — consistency and outward orientation of a polyhedron's facets
 * (spec algorithms.md §2), and the repair that flips the facets at fault.
 *
 * Consistency. Two facets on an edge with exactly two corners agree when
 * they run along it in opposite directions (GEO_EDGE_INTERIOR) and
 * disagree when in the same direction (GEO_EDGE_FLIPPED). A breadth-first
 * 2-colouring over such edges (same colour across an agreeing edge,
 * different across a disagreeing one) splits each shell (a connected
 * component across two-corner edges) into the facets to keep and the
 * facets to flip; the smaller colour class of each shell is the
 * inconsistent set (ties: the class without the shell's lowest facet index).
 * The colouring is impossible when a cycle of facets crosses an odd number
 * of disagreeing edges — a non-orientable (Möbius-like) shell. Then the
 * edges the colouring violates are counted, the shell is reported
 * inconsistent, and repair refuses (-EINVAL): no set of flips can fix it.
 *
 * Outward. Once consistent, a shell's signed volume (divergence theorem
 * about the model's bounding-box centre) must be positive, unless the
 * shell lies inside an odd number of other closed shells — then it bounds
 * a cavity and must be negative. Nesting is decided, when there are
 * several shells, by the parity of an exact ray from one of the shell's
 * vertices (geo_segment_meets_facet over a BVH; a ray that touches a
 * facet other than through its interior is shot again in another
 * direction or from another vertex). A shell with the wrong sign is
 * turned inside out. The model is "outward" when every shell is
 * consistent and rightly signed, "inward" when every shell is consistent
 * and turned inside out, "inconsistent" otherwise. For an open shell
 * (with holes) the volume is that of the surface closed through the
 * centre: still the right sign for a nearly closed stone; open shells do
 * not enclose anything.
 *
 * Complexity O(corners) after the topology, plus for several shells a
 * BVH (O(F log F)) and one ray query per shell. Reentrant. */
#ifndef GEO_ORIENT_H
#define GEO_ORIENT_H

#include <stdbool.h>
#include <stdint.h>

#include "ctx.h"
#include "poly.h"
#include "topo.h"

enum geo_orientation {
    GEO_ORIENT_OUTWARD = 0,
    GEO_ORIENT_INWARD = 1,
    GEO_ORIENT_INCONSISTENT = 2,
};

/* "outward", "inward", "inconsistent". */
const char *geo_orientation_name(enum geo_orientation o);

typedef struct geo_orient_report {
    enum geo_orientation orientation;
    uint32_t nshells;          /* components across two-corner edges */
    uint32_t ninconsistent;    /* facets in the minority class of a shell */
    uint32_t ninverted_shells; /* shells whose volume has the wrong sign
                                  (negative, or positive for a cavity) */
    uint32_t nconflict_edges;  /* edges no 2-colouring satisfies */
    bool orientable;           /* nconflict_edges == 0 */
    double volume;             /* signed volume with the minority flipped
                                  (mm³; negative when turned inside out) */
    uint32_t nflipped;         /* geo_orient_repair: facets it reversed */
} geo_orient_report;

/* Analyses p with its topology t (built from p as it is). If ret_flip is
 * non-NULL (p->nfacets bytes, caller-allocated) it receives 1 for every
 * facet the repair would reverse (the minority of each shell, and every
 * facet of a shell turned inside out), else 0. 0 or -ENOMEM. */
int geo_orient_analyze(const geo_poly *p, const geo_topo *t,
                       uint8_t *ret_flip, geo_orient_report *ret,
                       geo_err *err);

/* Makes p consistent and outward: reverses the minority facets of each
 * shell, then every facet of a shell that is still turned inside out
 * (cavities end up inward-facing, i.e. with their normals pointing out of
 * the solid); each reversal also negates the facet's plane. Builds its own topology. ret may be
 * NULL. Returns 0 (p changed in place, ret->nflipped facets), -EINVAL
 * for invalid indices or a non-orientable model (p unchanged, err names
 * the conflicting edge count), or -ENOMEM (p unchanged). */
int geo_orient_repair(geo_poly *p, geo_orient_report *ret, geo_err *err);

#endif
