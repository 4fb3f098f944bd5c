/* edit.h — an editable polyhedron for local surgery (facet merging,
 * Palachev 2012, §2; vertex-cluster collapse, §4.1): facets whose vertex cycles can
 * grow and shrink one vertex at a time, the facets of every vertex kept up
 * to date, and transactions that undo a failed edit exactly.
 *
 * Representation. Vertex and facet ids are stable: a facet that is
 * removed stays as a dead id (falive 0) and a vertex that no facet uses
 * any more stays as an orphan, until geo_edit_to_poly drops both. Every
 * list (a facet's vertex cycle, a vertex's facets) is a slice of one
 * arena; a list that outgrows its slice moves to the arena's end, and the
 * hole it leaves is garbage until geo_edit_gc. Facet cycles follow the
 * conventions of lib/core/poly.h (counter-clockwise seen from outside, unit
 * outward plane). A vertex's facet list is unordered and holds each facet
 * once.
 *
 * Transactions. Between geo_edit_begin and geo_edit_commit/rollback,
 * the first change of a facet or vertex saves its old state and moves its
 * list to fresh arena space (copy on write), so rollback restores every
 * list, plane, position and count bit for bit and truncates what was
 * appended. The saved ids are also the set of what the transaction
 * touched (geo_edit_touched_*), which the local validity checks use.
 *
 * Pointers returned by geo_edit_fv / geo_edit_vf stay valid only until
 * the next change of the edit. Every change that needs memory returns 0
 * or -ENOMEM; after -ENOMEM inside a transaction, rollback still restores
 * the state at begin. Not thread-safe; one edit per thread. */
#ifndef GEO_EDIT_H
#define GEO_EDIT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ctx.h"
#include "poly.h"
#include "topo.h"

typedef struct geo_slice {
    uint32_t off, n, cap; /* list = arena[off .. off+n), room for cap */
} geo_slice;

/* A facet's state saved by a transaction. */
typedef struct geo_edit_fsave {
    uint32_t id;
    geo_slice s;
    double plane[4];
    uint8_t alive;
} geo_edit_fsave;

/* A vertex's state saved by a transaction. */
typedef struct geo_edit_vsave {
    uint32_t id;
    geo_slice s;
    double pos[3];
} geo_edit_vsave;

typedef struct geo_edit {
    uint32_t nverts, nfacets;     /* ids in use, dead and orphans included */
    uint32_t cap_verts, cap_facets;
    double (*verts)[3];
    geo_slice *vf;                /* per vertex: its facets */
    geo_slice *fv;                /* per facet: its vertex cycle */
    double (*planes)[4];
    uint8_t *falive;
    uint32_t *arena;
    size_t alen, acap;

    /* transaction state */
    bool in_txn;
    uint32_t txn;                 /* current transaction number (≥ 1) */
    uint32_t *fstamp, *vstamp;    /* txn that saved the facet / vertex */
    geo_edit_fsave *fsaved;
    size_t nfsaved, capfsaved;
    geo_edit_vsave *vsaved;
    size_t nvsaved, capvsaved;
    uint32_t txn_nverts, txn_nfacets;
    size_t txn_alen;
} geo_edit;

/* A copy of p as an edit (facet lists, planes, positions, each vertex's
 * facets). p must have valid indices. NULL on out-of-memory (err set). */
geo_edit *geo_edit_from_poly(const geo_poly *p, geo_err *err);

/* Releases e; accepts NULL; returns NULL. */
geo_edit *geo_edit_free(geo_edit *e);

/* Writes the live facets (in id order) and the vertices they use (in id
 * order) into out, replacing its contents. ret_vmap (e->nverts entries,
 * caller-allocated, may be NULL) receives each vertex id's index in out
 * or GEO_NONE (UINT32_MAX); ret_fmap likewise for facets. 0 or -ENOMEM
 * (out then empty). Must not be called inside a transaction. */
int geo_edit_to_poly(const geo_edit *e, geo_poly *out, uint32_t *ret_vmap,
                     uint32_t *ret_fmap);

/* Compacts the arena (drops the holes left by moved lists). Outside a
 * transaction only. 0 or -ENOMEM (e unchanged). */
int geo_edit_gc(geo_edit *e);

/* Transactions (see above). begin outside a transaction; commit keeps the
 * changes, rollback undoes them. */
void geo_edit_begin(geo_edit *e);
void geo_edit_commit(geo_edit *e);
void geo_edit_rollback(geo_edit *e);

/* Ids touched by the running transaction: saved facets and vertices
 * (changed ones) plus every id created since begin. The callbacks-free
 * form: fills ret (caller-allocated, room for geo_edit_ntouched_*) and
 * returns the count. */
uint32_t geo_edit_ntouched_facets(const geo_edit *e);
uint32_t geo_edit_touched_facets(const geo_edit *e, uint32_t *ret);
uint32_t geo_edit_ntouched_verts(const geo_edit *e);
uint32_t geo_edit_touched_verts(const geo_edit *e, uint32_t *ret);

static inline uint32_t *geo_edit_fv(const geo_edit *e, uint32_t f)
{
    return e->arena + e->fv[f].off;
}
static inline uint32_t geo_edit_fn(const geo_edit *e, uint32_t f)
{
    return e->fv[f].n;
}
static inline uint32_t *geo_edit_vf(const geo_edit *e, uint32_t v)
{
    return e->arena + e->vf[v].off;
}
/* The number of facets containing v (its degree in Palachev 2012, §2.6.4). */
static inline uint32_t geo_edit_vn(const geo_edit *e, uint32_t v)
{
    return e->vf[v].n;
}

/* Position of v in facet f's cycle, or GEO_NONE. */
uint32_t geo_edit_find(const geo_edit *e, uint32_t f, uint32_t v);

/* The live facet other than f that has the directed edge b→a (the facet
 * across f's edge a→b), or GEO_NONE when none or several. */
uint32_t geo_edit_across(const geo_edit *e, uint32_t f, uint32_t a,
                         uint32_t b);

/* Appends a vertex; its id or a negative errno (-ENOMEM, -ERANGE). */
int64_t geo_edit_add_vertex(geo_edit *e, const double xyz[3]);

/* Moves vertex v (saved first inside a transaction). 0 or -ENOMEM. */
int geo_edit_move_vertex(geo_edit *e, uint32_t v, const double xyz[3]);

/* Appends a live facet with cycle vs[0..n) and the given plane; its id or
 * a negative errno. */
int64_t geo_edit_add_facet(geo_edit *e, const uint32_t *vs, uint32_t n,
                           const double plane[4]);

/* Marks f dead and removes it from its vertices' lists. 0 or -ENOMEM. */
int geo_edit_kill_facet(geo_edit *e, uint32_t f);

/* Replaces f's cycle by vs[0..n) (may alias nothing of e's arena), keeping
 * the vertices' facet lists right. 0 or -ENOMEM. */
int geo_edit_set_facet(geo_edit *e, uint32_t f, const uint32_t *vs,
                       uint32_t n);

/* Sets f's plane. 0 or -ENOMEM. */
int geo_edit_set_plane(geo_edit *e, uint32_t f, const double plane[4]);

/* Inserts v into f's cycle at position pos (0..n; the old entries from
 * pos on move up one). 0 or -ENOMEM. */
int geo_edit_insert(geo_edit *e, uint32_t f, uint32_t pos, uint32_t v);

/* Removes the entry at position pos of f's cycle. 0 or -ENOMEM. */
int geo_edit_remove(geo_edit *e, uint32_t f, uint32_t pos);

/* Replaces the entry at position pos of f's cycle by v (v not yet in f).
 * 0 or -ENOMEM. */
int geo_edit_replace(geo_edit *e, uint32_t f, uint32_t pos, uint32_t v);

/* Signed volume of the live facets (mm³, divergence theorem about
 * origin o), as geo_poly_volume. */
double geo_edit_facet_volume(const geo_edit *e, uint32_t f, const double o[3]);

/* Newell area vector of facet f (as geo_poly_facet_area_vector). */
void geo_edit_area_vector(const geo_edit *e, uint32_t f, double ret[3]);

#endif
