/* stitch.h — joining two open meshes into one closed one by a bridging
 * mesh (Nesterenko, "The algorithm for polygonal networks of
 * cross-linking", i.e. stitching polygonal meshes).
 *
 * 1. Free edges (algorithm 1). An edge with a facet on one side only
 *    (condition (3)) is a free edge; the free-edge polylines are the
 *    boundary loops of lib/core/topo.h, walked through the corner-based
 *    half-edge structure: a corner is the paper's oriented edge MN with
 *    its facet on the left, its mate the same edge seen from the facet
 *    on the right (none for a free edge), the next/previous corners of
 *    both facets the paper's b, c, d, e links — so the walk "to the
 *    opposite vertex, then the next free edge there" is a turn within the
 *    vertex's fan. Loops run with their mesh's facets on the left (seen
 *    from outside) and are split at pinch vertices.
 * 2. The pair of loops to join: of all loop pairs (one per mesh), the one
 *    whose centres C (vertex means, (5)) are closest.
 * 3. Vertices to connect (algorithm 2): a1 = C2 − C1, a2 = C1 − C2;
 *    loop 1 keeps the vertices with (V − C1)·a1 > 0, loop 2 those with
 *    (V − C2)·a2 > 0 — the sides facing each other; the longest run of
 *    consecutive kept vertices is the arc that is bridged. The test is
 *    made for contours lying side by side (the paper's fig. 3). Loops
 *    that face each other across the gap, as the two halves of a body —
 *    mean planes (Newell normals) within 45° of parallel and C2 off
 *    loop 1's axis by less than half the smaller mean loop radius (the
 *    offset taken between length-weighted centres, which crowded
 *    vertices do not pull aside) — are joined whole, as a closed band
 *    (every vertex connected). So are loops within 45° of parallel that
 *    are each planar and wholly beyond the other's plane (the walls of
 *    step 5b), however far a small loop sits off-axis (a cut near a
 *    culet).
 * 4. Orientation. Facing loops of consistently oriented meshes run in
 *    opposite directions (side by side: their Newell normals agree;
 *    across a gap: they point away from each other). When they do not,
 *    mesh 2 is turned over (every facet reversed) before joining. The
 *    line of loop 2 is then taken backwards so both lines run the same
 *    way, as in the paper's fig. 4.
 * 5. Meridians (the matrix H). With A the line of N vertices and B the
 *    line of M ≤ N (the roles swap when needed), A_i joins a B_j: every
 *    A_i gets one meridian, each B_j at least one, consecutive
 *    meridians' B ends differ by at most one. The paper picks j by rank
 *    (D_ij = |(M−1)(i−1) − (N−1)(j−1)| minimal); here j steps to the next
 *    B point when that one lies nearer A_i by arc length along the lines
 *    (or when the steps left require it), so lines sampled unevenly — a
 *    cut through many small facets on one side — are matched by where
 *    their points lie (on 24 brilliants cut at random planes with bands
 *    of 0.05–0.5 mm removed, the worst Hausdorff distance to the stone
 *    went from 436 to 262 µm).
 *    For a closed band the lines are the loops closed by their first
 *    vertex, and the start of B is the rotation (twist) that minimises
 *    the total meridian length, tried for every one of the M starts.
 * 5a. Loops that coincide — lines of equal length whose every meridian
 *    is within geo_poly_eps of the merged mesh long, as the two halves
 *    of one plane cut — are welded instead: a band of zero width would
 *    be zero-area facets. Mesh 2's loop vertices are replaced by mesh
 *    1's and dropped (the vertices after them move down in order); no
 *    band is made. Any other pair of loops (one per mesh) that coincides
 *    — a torus cut across its hole has two on each half — is welded the
 *    same way, whatever was done with the chosen pair. Facing loops on
 *    one polyline but sampled differently (each vertex within
 *    geo_poly_eps of a vertex or an edge of the other loop: halves of
 *    one cut, one of them with its rim facets split) are welded too:
 *    each loop's vertices are put into the other's edges (those edges'
 *    facets take them, in order along the edge), then the vertices that
 *    coincide are welded (report: inserted).
 * 5b. Loops facing across a gap that are planar, each edge on its facet's
 *    plane, are first joined by the facet planes extended into the gap:
 *    the planes along both loops (those within 0.05° and through the
 *    same edge ends, as the pieces of one facet on both sides of a cut,
 *    taken once) and the two loops' planes, as walls of the slab
 *    between them, are intersected exactly (lib/core/halfspace.h). When
 *    each wall of that convex gap is its loop — every wall corner a loop
 *    vertex, every loop vertex on the wall's border — the walls are
 *    dropped, the gap's side facets take the loops' vertices, and a
 *    facet cut on both sides comes back whole between its pieces,
 *    neighbouring planes meeting in the true edges (a girdle). The
 *    result, with the openings left filled, is kept only if geo_inspect
 *    finds it valid; otherwise (loops not planar, a pair not convex
 *    about the gap, no valid solid) steps 6–8 build the band
 *    (report: method).
 * 5c. Halves that overlap — planar loops, each wholly inside the other's
 *    body — are first cut back to the plane midway between the loops
 *    (lib/mesh/stitch_trim.h), then stitched as halves that meet there
 *    (report: trimmed).
 * 6. The vertex matrix P: row 0 the A ends, the last row the B ends
 *    (B_j repeated where several meridians meet it), between them K rows
 *    of points dividing each meridian evenly, K + 1 = round(mean meridian
 *    length / mean edge length of the two meshes) (at least 1), so the
 *    segments match the meshes' edges.
 * 7. Facets: each quadruple of adjacent P entries (two meridians, two
 *    rows) gives two triangles (split along the shorter diagonal), a
 *    triangle where the two B ends coincide; orientation so that every
 *    loop edge is used once more in the opposite direction. The links of
 *    the new edges (the paper's last step) are the topology of the merged
 *    mesh, rebuilt by lib/core/topo.h wherever it is needed.
 * 8. Openings left at the band's ends (the loop vertices algorithm 2 did
 *    not choose) and any other loop are closed by lib/mesh/fill.h.
 *
 * Output: mesh 1's vertices and facets first (same indices), then mesh
 * 2's (turned over if needed; welded vertices dropped), then the band's
 * new vertices and facets, then the fill's. Ownership: out is overwritten (callers pass an empty
 * geo_poly); rep->fill.holes is malloc'd (geo_stitch_report_clear).
 * Errors: -EINVAL (a mesh without a free-edge loop, loops of fewer than
 * 2 chosen vertices, invalid indices), -ENOMEM, -ECANCELED; out is then
 * empty. Thread-safe for distinct outputs. */
#ifndef GEO_STITCH_H
#define GEO_STITCH_H

#include <stdbool.h>
#include <stdint.h>

#include "ctx.h"
#include "fill.h"
#include "poly.h"

typedef struct geo_stitch_opts {
    geo_mesh_fill_opts fill; /* for the openings (fill.h defaults) */
    double segment;          /* meridian segment length, mm; 0 means the
                                mean edge length of the two meshes */
} geo_stitch_opts;

/* Fills the defaults above. */
void geo_stitch_opts_default(geo_stitch_opts *o);

/* How the chosen pair of loops was closed. */
enum geo_stitch_method {
    GEO_STITCH_BAND = 0, /* the band of meridians, steps 6–7 */
    GEO_STITCH_PLANES,   /* the facet planes extended into the gap, 5b */
    GEO_STITCH_WELD,     /* the loops coincide and were welded, 5a */
};

/* "band", "planes", "weld". */
const char *geo_stitch_method_name(enum geo_stitch_method m);

typedef struct geo_stitch_report {
    enum geo_stitch_method method;
    uint32_t loops1, loops2;   /* free-edge loops of each mesh */
    uint32_t loop1, loop2;     /* the pair joined (index among each) */
    uint32_t nloop1, nloop2;   /* their vertices */
    uint32_t chosen1, chosen2; /* vertices bridged on each */
    bool band;                 /* joined whole as a closed band */
    bool flipped2;             /* mesh 2 was turned over */
    bool swapped;              /* line A (the longer) is mesh 2's */
    uint32_t twist;            /* start of B chosen (closed band) */
    uint32_t meridians;        /* meridians (columns of P) */
    uint32_t rows;             /* rows of P, both lines included */
    double meridian_length;    /* total length of the meridians, mm */
    double segment;            /* segment length used, mm */
    uint32_t planes;           /* distinct facet planes extended (5b) */
    uint32_t band_vertices, band_facets; /* added between the loops (by
                                  either method) */
    uint32_t welded;           /* loop vertex pairs welded (loops that
                                  coincide, see step 5a) */
    uint32_t welded_loops;     /* other loop pairs welded (step 5a) */
    uint32_t inserted;         /* loop vertices put into the other loop's
                                  edges (one polyline sampled differently,
                                  step 5a) */
    bool trimmed;              /* the halves overlapped and were cut back
                                  to the plane midway between their loops
                                  first (step 5c, lib/mesh/stitch_trim.h);
                                  the other fields are of the trimmed pair */
    geo_mesh_fill_report fill; /* the openings closed afterwards */
} geo_stitch_report;

/* Joins open meshes m1 and m2 into out as described above. rep may be
 * NULL; opts NULL means defaults. */
int geo_stitch(const geo_poly *m1, const geo_poly *m2,
               const geo_stitch_opts *opts, const geo_ctx *ctx, geo_poly *out,
               geo_stitch_report *rep, geo_err *err);

/* The pipeline form: p must consist of exactly two pieces (sets of
 * facets connected through shared vertices), which are stitched; out as
 * for geo_stitch (pieces in order of their lowest facet index). -EINVAL
 * with a message when p has another number of pieces. */
int geo_stitch_pieces(const geo_poly *p, const geo_stitch_opts *opts,
                      const geo_ctx *ctx, geo_poly *out,
                      geo_stitch_report *rep, geo_err *err);

/* Frees rep->fill's arrays and zeroes *rep; accepts NULL. */
void geo_stitch_report_clear(geo_stitch_report *rep);

#endif
