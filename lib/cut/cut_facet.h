/* cut_facet.h — the per-facet stages of the plane cut (Palachev 2012, §3),
 * shared by geo_cut (lib/cut/cut.c) and the merge's local cut
 * (lib/correct/merge_cut.c, the §3.4 variant); not part of the library's
 * interface.
 *
 * One facet crossing the plane π is cut into its kept pieces (the side
 * below π) and the segments of l = facet ∩ π that bound them, which are,
 * reversed, edges of the section. The caller decides everything that
 * differs between the two cuts: the side of every vertex (exact in
 * geo_cut, the merge's tolerance within it), the vertex standing for each
 * crossed edge (one per edge, shared by its two facets), which facets are
 * visited, and what is done with the pieces. Not thread-safe: one
 * geo_cutf per thread. */
#ifndef GEO_CUT_FACET_H
#define GEO_CUT_FACET_H

#include <stddef.h>
#include <stdint.h>

#include "grow.h"

/* A node of the facet's boundary: a vertex, or the crossing point of the
 * edge that follows vertex i. */
typedef struct geo_cutf_node {
    uint32_t i;      /* position of the vertex in the facet */
    uint32_t vout;   /* vertex id in the result */
    uint8_t crossing;
    uint8_t in, out; /* kept/removed type of the boundary before / after */
    int32_t ev;      /* index of its event in the sorted list, or -1 */
} geo_cutf_node;

typedef struct geo_cutf_event {
    uint8_t type;
    uint32_t node;
    const double *p0, *p1; /* the point: p0, or the crossing of p0p1 */
    int32_t partner;       /* EXIT/DOUBLE: sorted index of its ENTRY */
} geo_cutf_event;

typedef struct geo_cutf {
    /* set by the caller before the first facet (pointers borrowed) */
    const double *plane; /* π as given: orders the points of l exactly */
    const double *frame; /* π's normal in the caller's scaling: picks the
                            axis along which l is ordered */

    /* section edges (src, dst) in result vertex ids, appended by every
     * facet and by the caller (geo_cutf_push_section) */
    uint32_t (*sec)[2];
    size_t nsec, capsec;

    /* the last facet's kept pieces: piece p is
     * piece[pstart[p] .. pstart[p + 1]), in result vertex ids */
    uint32_t *piece, *pstart;
    size_t cappiece, cappstart;
    /* the last facet's positions i whose edge i → i+1 lies in π and
     * borders a kept piece, in the order cycle B walked them */
    uint32_t *inplane;
    size_t ninplane, capinplane;

    /* why the last facet was refused (-EINVAL), a static string */
    const char *why;

    /* scratch of one facet */
    int axis, esign, drop, osign;
    geo_cutf_node *nodes;
    size_t capnodes;
    geo_cutf_event *ev;
    size_t capev;
    uint8_t *used;
    size_t capused;
} geo_cutf;


/* The coordinate axis on which |v| is largest (the first of ties). */
int geo_cutf_dominant_axis(const double v[3]);

/* The crossing of edge a–b (ends on opposite sides of plane) computed
 * from the end nearer to the plane, so the parameter is at most 1/2 and
 * the same edge gives the same bits whichever facet asks; each coordinate
 * is clamped to the edge's box. Returns a bound on how far, in each
 * coordinate, the exact crossing lies from ret when plane is the given
 * plane normalised (see cut.c). */
double geo_cutf_crossing_point(const double plane[4], const double a[3],
                               const double b[3], double ret[3]);

/* Appends the section edge a → b. 0 or -ENOMEM. */
int geo_cutf_push_section(geo_cutf *k, uint32_t a, uint32_t b);

/* Fixes the facet's frame from its area vector (any positive scale):
 * l is ordered along e = frame × area, and 2D turns are taken dropping
 * area's dominant axis. -EINVAL (k->why set) when the facet is parallel
 * to π. Must precede geo_cutf_facet for the same facet. */
int geo_cutf_frame(geo_cutf *k, const double area[3]);

/* Cuts the facet with vertex cycle vs[0..n) (counter-clockwise seen from
 * outside), positions verts[vs[i]]; side[i] is the side of vs[i] (−1
 * kept, 0 on π, +1 removed; decided once by the caller, never
 * recomputed); xv[i] is the result vertex on edge i → i+1 where side[i]
 * and side[i+1] have opposite signs (read nowhere else). Fills piece /
 * pstart with the kept pieces and inplane, and appends to sec the
 * segments of l walked by cycle A. Returns the number of pieces (≥ 1),
 * -EINVAL with k->why set when the pattern along l is not that of a
 * simple planar facet, or -ENOMEM. */
int geo_cutf_facet(geo_cutf *k, const double (*verts)[3], const uint32_t *vs,
                   const int8_t *side, const uint32_t *xv, uint32_t n);

/* Frees every buffer of k (not the borrowed pointers); k must not be
 * used afterwards. A zeroed geo_cutf holds no buffers. */
void geo_cutf_free(geo_cutf *k);

#endif
