/* poly.h — the polyhedron model H = {P, G} ("Tests of graphic elements"; Palachev 2012, §1.3).
 *
 * Vertices are double x,y,z (millimetres). Facets are index cycles stored
 * compactly (CSR): facet f's vertex indices are
 *   fidx[fstart[f]] .. fidx[fstart[f+1] − 1],
 * listed counter-clockwise seen from outside, so the right-hand normal
 * points outward. Each facet has a plane a,b,c,d with (a,b,c) the unit
 * outward normal: plane(p) = a·x+b·y+c·z+d is > 0 outside. A position in
 * fidx is called a corner; corner c belongs to one facet and one vertex.
 *
 * Tolerance model (the one place it is stated): a point "lies on" a plane
 * when |plane(p)| ≤ geo_poly_eps(p) = 1e-10 × (1 + the model's size), size
 * being its bounding-box diagonal; that tolerance measures planarity and
 * nothing else. Signs that decide topology use lib/core/predicates.h exactly.
 *
 * Implicit planes: a reader may leave planes NULL for a model whose every
 * facet is a triangle with no plane given (proto_limits.implicit_planes);
 * each plane is then the one geo_poly_facet_fit_plane computes, read
 * through geo_poly_facet_plane. Such a model is for reading only:
 * geo_inspect, geo_poly_max_nonplanarity and geo_poly_copy accept it; a
 * function that changes a model or reads p->planes directly does not.
 *
 * Ownership: a geo_poly owns all four arrays; geo_poly_free releases them.
 * Nothing here is thread-safe for concurrent mutation; concurrent readers
 * of an unchanging geo_poly are fine. */
#ifndef GEO_POLY_H
#define GEO_POLY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ctx.h"

typedef struct geo_poly {
    uint32_t nverts;    /* number of vertices */
    uint32_t nfacets;   /* number of facets */
    double (*verts)[3]; /* nverts positions */
    uint32_t *fstart;   /* nfacets + 1 offsets into fidx; fstart[0] = 0 */
    uint32_t *fidx;     /* fstart[nfacets] vertex indices (corners) */
    double (*planes)[4];/* nfacets planes: unit outward normal, offset;
                           NULL when implicit (above) */
    uint32_t cap_verts, cap_facets, cap_idx; /* allocated capacities */
} geo_poly;

/* Hard upper bounds of the representation (indices are uint32_t). */
#define GEO_POLY_MAX_VERTS 100000000u
#define GEO_POLY_MAX_CORNERS 1000000000u

/* An empty polyhedron, or NULL on out-of-memory. Free with geo_poly_free. */
geo_poly *geo_poly_new(void);

/* Releases p and its arrays; accepts NULL; returns NULL. */
geo_poly *geo_poly_free(geo_poly *p);

/* A deep copy, or NULL on out-of-memory. */
geo_poly *geo_poly_copy(const geo_poly *p);

/* Replaces dst's contents by a deep copy of src. 0 or -ENOMEM (dst is
 * unchanged on failure). */
int geo_poly_assign(geo_poly *dst, const geo_poly *src);

/* Empties p, keeping its allocations. */
void geo_poly_clear(geo_poly *p);

/* Grows capacities to at least nverts vertices, nfacets facets and ncorners
 * corners. 0 or -ENOMEM (p unchanged). */
int geo_poly_reserve(geo_poly *p, size_t nverts, size_t nfacets,
                     size_t ncorners);

/* Appends a vertex; returns its index (≥ 0) or -ENOMEM / -ERANGE. */
int64_t geo_poly_add_vertex(geo_poly *p, const double xyz[3]);

/* Appends a facet with n vertex indices (copied) and a zero plane; returns
 * its index (≥ 0) or -ENOMEM / -ERANGE. Indices are not validated here:
 * geo_poly_validate_indices does that. */
int64_t geo_poly_add_facet(geo_poly *p, const uint32_t *idx, uint32_t n);

/* Builds a polyhedron from arrays (copied): nv vertices (xyz, 3·nv
 * doubles), nf facets given as CSR (fstart has nf+1 entries, fidx
 * fstart[nf] indices), and optional planes (4·nf doubles; NULL means
 * "compute by least squares"). Validates indices (range, ≥ 3 per facet, no
 * repeated consecutive index). Returns NULL on error with err set
 * (naming the place, e.g. "facets[12].vertices[3]: index 9001 out of range
 * (8000 vertices)"), or on out-of-memory. */
geo_poly *geo_poly_from_arrays(uint32_t nv, const double *xyz, uint32_t nf,
                               const uint32_t *fstart, const uint32_t *fidx,
                               const double *planes, geo_err *err);

/* Checks every facet: at least 3 vertices, indices < nverts, no index
 * repeated consecutively (cyclically). 0 or -EINVAL with err naming the
 * first offending place. */
int geo_poly_validate_indices(const geo_poly *p, geo_err *err);

static inline uint32_t geo_poly_facet_size(const geo_poly *p, uint32_t f)
{
    return p->fstart[f + 1] - p->fstart[f];
}

static inline const uint32_t *geo_poly_facet(const geo_poly *p, uint32_t f)
{
    return p->fidx + p->fstart[f];
}

static inline uint32_t geo_poly_ncorners(const geo_poly *p)
{
    return p->nfacets ? p->fstart[p->nfacets] : 0;
}

/* Newell's area vector of facet f: direction = right-hand normal of the
 * polygon as listed, length = twice its (projected) area. Exact for planar
 * polygons, robust for slightly non-planar ones. */
void geo_poly_facet_area_vector(const geo_poly *p, uint32_t f, double ret[3]);

/* Area of facet f (half the length of its Newell vector). */
double geo_poly_facet_area(const geo_poly *p, uint32_t f);

/* Centroid of the vertices of facet f (not the area centroid). */
void geo_poly_facet_center(const geo_poly *p, uint32_t f, double ret[3]);

/* Plane-fitting options for geo_poly_compute_planes. */
enum geo_plane_weight {
    GEO_PLANE_UNWEIGHTED = 0, /* plain least squares (Palachev 2012, §2.5.1) */
    GEO_PLANE_EDGE_WEIGHTED,  /* weight each vertex by half the length of its
                                 two facet edges (Palachev 2012, §2.5.2): clusters of
                                 close points do not pull the plane */
};

/* Recomputes the plane of every facet by least squares; the normal's sign
 * follows the facet's Newell vector (so it is outward for a correctly
 * listed facet). A degenerate facet (zero area, fewer than 3 distinct
 * points) gets its Newell direction or a zero normal. Always succeeds. */
void geo_poly_compute_planes(geo_poly *p, enum geo_plane_weight weight);

/* Least-squares plane of facet f into ret (see compute_planes). */
void geo_poly_facet_fit_plane(const geo_poly *p, uint32_t f,
                              enum geo_plane_weight weight, double ret[4]);

/* The plane of facet f into ret: the stored one, or for implicit planes
 * (p->planes NULL) the one a reader would have stored: the unweighted
 * fit, each -0 made +0. */
void geo_poly_facet_plane(const geo_poly *p, uint32_t f, double ret[4]);

/* Axis-aligned bounding box; an empty model gives lo = hi = 0. */
void geo_poly_bbox(const geo_poly *p, double ret_lo[3], double ret_hi[3]);

/* Bounding-box diagonal: the model's size for relative tolerances. */
double geo_poly_size(const geo_poly *p);

/* The planarity tolerance of a model of the given size (bounding-box
 * diagonal): 1e-10 × (1 + size), the one formula every kernel uses. */
double geo_eps_of_size(double size);

/* The planarity tolerance of p: geo_eps_of_size(geo_poly_size(p)). */
double geo_poly_eps(const geo_poly *p);

/* acc + 6 × the signed volume of the fan of the polygon x[v[0..n)] about
 * o, each triangle's o-relative triple product added to acc in turn (so a
 * caller summing several polygons gets the same bits as one loop). */
double geo_fan_volume6(double acc, const double (*x)[3], const uint32_t *v,
                       uint32_t n, const double o[3]);

/* Signed volume by the divergence theorem (positive for a closed model
 * listed counter-clockwise from outside); meaningful for closed models. */
double geo_poly_volume(const geo_poly *p);

/* Total facet area. */
double geo_poly_area(const geo_poly *p);

/* Largest |plane(v)| over every facet and each of its vertices. */
double geo_poly_max_nonplanarity(const geo_poly *p);

/* Reverses the vertex order of facet f and negates its plane. */
void geo_poly_flip_facet(geo_poly *p, uint32_t f);

/* Removes facets with keep_facet[f] == false (NULL keeps all), then
 * vertices no longer used by any facet, renumbering both densely and
 * keeping order. If ret_vmap is non-NULL it receives (caller-allocated,
 * old nverts entries) the new index of each old vertex or UINT32_MAX;
 * ret_fmap likewise for facets (old nfacets entries). 0 or -ENOMEM
 * (p unchanged). */
int geo_poly_compact(geo_poly *p, const bool *keep_facet, uint32_t *ret_vmap,
                     uint32_t *ret_fmap);

#endif
