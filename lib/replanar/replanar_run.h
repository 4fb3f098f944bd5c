/* replanar_run.h — the state of one re-planarisation run, shared by the
 * paper's schedules (replanar.c) and the least-norm driver
 * (replanar_least_norm.c); not part of the library's interface. */
#ifndef GEO_REPLANAR_RUN_H
#define GEO_REPLANAR_RUN_H

#include <stdbool.h>
#include <stdint.h>

#include "bvh.h"
#include "ctx.h"
#include "replanar.h"

struct geo_replanar_prep {
    geo_poly *poly;    /* start positions, fitted planes */
    uint32_t *vstart;  /* nverts + 1 offsets into vfacets */
    uint32_t *vfacets; /* facets of each vertex (one entry per corner) */
    double *resid;     /* per facet: max |plane(v)| at the start */
    double eps;        /* geo_poly_eps of the start */
    double volume;     /* signed volume of the start */
    geo_bvh *fbvh;     /* facet boxes of the start */
};

enum { V_ACTIVE = 1, V_FIXED = 2 };

typedef struct run {
    const geo_replanar_prep *prep;
    const geo_poly *p0;           /* prep->poly: facets, start positions */
    double (*x)[3];               /* current positions */
    double (*pl)[4];              /* current planes */
    double (*xn)[3];              /* new positions, by active-list slot */
    uint8_t *vflag;               /* V_ACTIVE | V_FIXED */
    uint8_t *fact;                /* facet active */
    uint32_t *av, nav;            /* active vertices (fixed ones included) */
    uint32_t *af, naf;            /* active facets */
    uint32_t *wake, nwake;        /* facets to activate after this step */
    uint8_t *fwake;               /* facet queued in wake */
    double wake_abs;              /* mm */
    bool fit_all;                 /* GEO_REPLANAR_FIT_ALL */
    double s1, s2, s2sum, delta;  /* of the last step */
} run;

static inline const double *rp_start_pos(const run *r, uint32_t v)
{
    return r->p0->verts[v];
}

/* Activates facet f and its vertices. */
void rp_activate_facet(run *r, uint32_t f);
/* Refits facet f's plane to positions x (through the vertices flagged
 * V_FIXED in vflag when vflag is given); prev: the plane before, and the
 * result. */
void rp_fit_plane(const geo_poly *p, double (*x)[3], const uint8_t *vflag,
                  uint32_t f, double prev[4]);
/* S2 and S2sum of r over its active free vertices. */
void rp_plane_errors(run *r);
/* Appends r's step figures to log (NULL: nothing); 0 or -ENOMEM. */
int rp_log_row(geo_replanar_log *log, const run *r, uint32_t stepno,
               uint32_t outer, uint32_t inner, double eps, double k,
               int64_t nselfint);
/* Self-intersections with a facet of the active region; 0 or -ENOMEM. */
int rp_count_selfint(const run *r, int64_t *ret);
/* The least-norm schedule on an initialised run (replanar_least_norm.c). */
int rp_least_norm_run(run *r, const geo_replanar_opts *o, const geo_ctx *ctx,
                      geo_replanar_log *log, uint32_t *ret_steps,
                      bool *ret_converged, int64_t *nsi,
                      geo_replanar_result *ret, geo_err *err);

#endif
