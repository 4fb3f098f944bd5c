/* fill.h — closing the holes of any polygon mesh, each fill checked: the
 * driver around lib/mesh/hole_fill.h for meshes that are not being
 * triangulated from a surface (scans, stitched meshes, models with
 * missing facets).
 *
 * 0. An open mesh whose facets disagree with their neighbours' winding
 *    has them reversed where the shell is orientable, as `orient` would
 *    (lib/inspect/orient.h: the minority of each shell, and a shell whose
 *    signed volume is negative whole; step 5 turns a closed result
 *    outward again), since no patch could make it a solid
 *    and its loops would split at every flipped edge (rep->nreversed).
 *    Vertices no facet uses are removed (rep->nunused): meshes from
 *    other tools often carry them, and a solid cannot. Seams whose sides
 *    repeat their vertices are welded (lib/mesh/weld.h, rep->nwelded):
 *    they read as holes whose sides coincide, which no patch fills.
 * 1. Loops: the boundary loops of lib/core/topo.h (split at non-manifold
 *    vertices, so two holes touching at a vertex are two holes). Each is
 *    handled on its own, in loop order.
 * 2. A planar hole — a missing facet — gets ONE facet: when every loop
 *    vertex lies within geo_poly_eps(p) of the loop's least-squares plane
 *    and the loop, as a polygon, is simple and not degenerate (decided
 *    exactly by geo_facet_self_intersects / geo_facet_shape_of in
 *    lib/inspect/selfint.h), the new facet is the loop reversed, with its
 *    least-squares plane (outward like the facets around it). Any other
 *    loop is triangulated.
 * 3. Otherwise the loop is filled by lib/hole_fill (minimum-weight
 *    triangulation, refinement to the surrounding density, fairing with
 *    the loop and the mesh around it fixed) on a local copy: the facets
 *    touching the loop's vertices (all the hole filler reads: the loop
 *    vertices' edges give the chords it must not repeat and the desired
 *    lengths, their neighbours the fixed ring of the U² operator), so the
 *    cost of a hole does not grow with the mesh.
 * 4. Every patch is checked before it is kept: none of its facets may
 *    intersect (lib/inspect/selfint.h, exact) a facet of the mesh, of a patch
 *    kept earlier, or of itself, other than along shared edges and
 *    vertices. Candidates come from a BVH of the mesh's facets and the
 *    kept patches' boxes, so the check is local. A rejected patch is
 *    taken back and, when opts.fallback, the hole is tried again with
 *    Liepa's dihedral-angle weight, then without fairing, then without
 *    refinement, then steered (GEO_ATTEMPT_AVOID*): the bare
 *    triangulation is searched again and again with the triangles that
 *    crossed forbidden (geo_fill_opts.admit), so it takes other
 *    diagonals, splitting the hole into other sub-holes, until a patch
 *    crosses nothing; that triangulation is then refined and faired,
 *    refined, or kept bare, whichever first crosses nothing. Last, the
 *    refined patch (or a fan from the loop's centroid, when the patch has
 *    a facet with every corner on the loop, which no lift can move) is
 *    bent into a dome along the loop's normal (GEO_ATTEMPT_LIFT, then
 *    _LOWER; the added vertices move by 0.1 to 4 times the loop's mean
 *    radius, scaled by their distance in edges from the loop over the
 *    largest), which clears an open sheet or a thin wall a flat lid
 *    would lie on. A hole that no attempt
 *    fills validly stays open with status GEO_HOLE_INTERSECTS. No hole
 *    is ever reported filled with nothing added. With parts_overlap the
 *    check lets a patch cross a facet of another shell (component across
 *    two-corner edges) that its own shell already crossed in p — the
 *    exact self-intersection pairs of p, found once — and nothing else.
 *
 * 5. When every hole is closed, a shell that is consistent but turned
 *    inside out (an open mesh had no inside to face) has all its facets
 *    reversed (rep->nreversed).
 *
 * Output: vertices and facets of p keep their indices (unless
 * remove_crossing removed some, or an open p had vertices no facet used
 * or welded;
 * a facet split_nonplanar splits keeps its index as its first triangle);
 * new vertices and facets are appended, hole after hole. Ownership: p is
 * modified in place (left unchanged on error); rep->holes is malloc'd (release with
 * geo_mesh_fill_report_clear). Errors: -EINVAL (invalid indices or
 * options), -ENOMEM, -ECANCELED. Not thread-safe for one p. */
#ifndef GEO_FILL_H
#define GEO_FILL_H

#include <stdbool.h>
#include <stdint.h>

#include "ctx.h"
#include "hole_fill.h"
#include "poly.h"

/* The attempts, in the order they are tried. */
enum geo_fill_attempt {
    GEO_ATTEMPT_PLANAR = 0,   /* one planar facet */
    GEO_ATTEMPT_AS_ASKED = 1, /* the caller's weight, refinement, fairing */
    GEO_ATTEMPT_ANGLE = 2,    /* Liepa's dihedral-angle weight */
    GEO_ATTEMPT_NO_FAIR = 3,  /* angle weight, refined, not faired */
    GEO_ATTEMPT_PLAIN = 4,    /* angle weight, the bare triangulation */
    /* the search steered around the triangles that crossed (fill.c,
     * try_avoid), then refined and faired, refined, or bare */
    GEO_ATTEMPT_AVOID_FAIRED = 5,
    GEO_ATTEMPT_AVOID_REFINED = 6,
    GEO_ATTEMPT_AVOID = 7,
    /* the patch (or, without added vertices, a fan from the centroid)
     * bent into a dome along the loop's normal, outward or inward */
    GEO_ATTEMPT_LIFT = 8,
    GEO_ATTEMPT_LOWER = 9,
    /* a flat fan from the loop's centroid: the one new vertex makes no
     * chord that repeats an edge of the mesh, so it closes loops every
     * triangulation of whose vertices would (GEO_HOLE_NO_TRIANGULATION) */
    GEO_ATTEMPT_FAN = 10,
};

/* A stable name ("planar", "as_asked", "angle", "no_fair", "plain",
 * "avoid_faired", "avoid_refined", "avoid", "lift", "lower", "fan"). */
const char *geo_fill_attempt_name(enum geo_fill_attempt a);

typedef struct geo_mesh_fill_opts {
    geo_fill_opts fill; /* weight, refine, fair, ... (hole_fill.h) with
                           max_dp_vertices [600]: a loop of up to 600
                           vertices gets the exact O(n³) search (36·10⁶
                           triangles, ~16 MB of tables), a longer one is
                           cut by bridges first; select_loop is ignored */
    bool planar;        /* [true] planar simple loops get one facet */
    bool check;         /* [true] reject patches that intersect */
    bool fallback;      /* [true] retry rejected patches (see above) */
    bool parts_overlap; /* [false] the mesh is an assembly of parts that
                           overlap: a patch may cross a facet of another
                           shell when its own shell already crossed that
                           shell in p (no pair of parts comes to cross
                           that did not); it may still cross nothing of
                           its own shell, of other shells, or itself */
    bool split_nonplanar; /* [true] when p has a hole, every facet whose
                           vertices lie farther than geo_poly_eps from its
                           plane is split into triangles on its own
                           vertices first (lib/core/polygon_triangulate.h):
                           such a polygon cannot be a facet of a valid
                           solid, and meshes from other tools store
                           polygons planar to their 6 or 7 digits only.
                           The facet keeps its index as the first
                           triangle; the others are appended
                           (rep->nsplit) */
    bool remove_crossing; /* [false] first remove every facet that crosses
                           another (exact, lib/inspect/selfint.h) and has
                           a vertex on a hole's rim — a flap folded over
                           the opening — so that hole grows by it, then
                           fill; when crossings remain elsewhere or a hole
                           stays open, both facets of every crossing pair
                           go, then up to three rings around them (every
                           facet with a vertex of a removed one or on a
                           hole the choice before left open), the
                           first choice whose holes all close kept. Only
                           when every hole then closes and at most 5 % of
                           the facets go (else the plain fill's result).
                           The other facets and vertices move down in
                           order (geo_poly_compact; rep->nremoved) */
} geo_mesh_fill_opts;

/* Fills the defaults above (fill: geo_fill_opts_default). */
void geo_mesh_fill_opts_default(geo_mesh_fill_opts *o);

typedef struct geo_mesh_hole {
    uint32_t nverts;       /* loop vertices */
    uint32_t first_vertex; /* one loop vertex (index in p) */
    uint8_t status;        /* enum geo_hole_status: GEO_HOLE_FILLED,
                              GEO_HOLE_FILLED_PLANAR, or why it is open */
    uint8_t attempt;       /* enum geo_fill_attempt that filled it, or the
                              last one tried */
    uint32_t facets_added, verts_added;
    double planarity;      /* largest distance of a loop vertex from the
                              loop's least-squares plane (mm; INFINITY
                              when the loop has no plane) */
    double max_dihedral_deg; /* largest angle between the normals of a
                                patch facet and the mesh facet across a
                                loop edge (0 = the surface goes on flat) */
    double edge_ratio;     /* mean edge length inside the patch over the
                              mean length of the mesh edges at the loop's
                              vertices (0 for a single facet) */
} geo_mesh_hole;

typedef struct geo_mesh_fill_report {
    uint32_t nloops;       /* boundary loops found */
    uint32_t nfilled;      /* of which filled (planar ones included) */
    uint32_t nplanar;      /* filled with one planar facet */
    uint32_t nopen;        /* left open, each with its status */
    uint32_t nrejected;    /* patches taken back by the check */
    uint32_t nreversed;    /* facets reversed: wound against their
                              neighbours in an open p (step 0), or the
                              closed result turned inside out (step 5) */
    uint32_t nremoved;     /* crossing rim facets removed first
                              (remove_crossing) */
    uint32_t nsplit;       /* non-planar facets split into triangles
                              first (split_nonplanar) */
    uint32_t nunused;      /* vertices no facet used, removed first */
    uint32_t nwelded;      /* vertices welded into another at the same
                              point first (lib/mesh/weld.h) */
    uint32_t verts_added, facets_added;
    double max_dihedral_deg; /* over every filled hole */
    geo_mesh_hole *holes;  /* nloops entries, in loop order */
} geo_mesh_fill_report;

/* Fills the holes of p as described above. rep may be NULL; opts NULL
 * means defaults. 0 or a negative errno (see the file comment). */
int geo_fill(geo_poly *p, const geo_mesh_fill_opts *opts,
                  const geo_ctx *ctx, geo_mesh_fill_report *rep, geo_err *err);

/* Frees rep->holes and zeroes *rep; accepts NULL. */
void geo_mesh_fill_report_clear(geo_mesh_fill_report *rep);

#endif
