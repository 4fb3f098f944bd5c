/* pipeline.h — the job pipeline of the Job API (formats.md): a JSON array
 * of operations, or the string "correct", parsed into structs with every
 * parameter checked and defaulted, and written back in canonical form.
 *
 * An operation is either its name as a string ("inspect", "stitch") or an
 * object {"op": NAME, PARAM: VALUE, ...}. Unknown operations and unknown
 * parameters are errors (a typo must not silently run with a default).
 * Errors name the place: `pipeline[2].max_angle_deg: expected a number`.
 * Each op has one name, the same as the `facet` command that runs it
 * (inversion_stats is `facet inversion-stats`).
 *
 * Operations and parameters (lengths in the model's units, mm):
 *   inspect {keep_invalid [false]} — after an op that changed the model,
 *                 an invalid model fails the job unless keep_invalid
 *   collapse {radius ≥ 0 [0: 2e-4 × the model's size]}
 *   merge {max_angle_deg in (0, 90) [60], max_deviation ≥ 0
 *                 [0: 5e-4 × the model's size], views ≥ 0 (the scanner's
 *                 contours over 180°) [0: read off the model], groups?:
 *                 [[facet, facet, ...], ...]}
 *   correct {radius, max_angle_deg, max_deviation, views: as above,
 *                 convex [false]} — the
 *                 whole post-scan correction of lib/correct/correct.h
 *   cut {plane: [a, b, c, d]} — keeps plane(p) ≤ 0; (a,b,c) non-zero,
 *                 normalised to unit length (d scaled with it) unless
 *                 already unit to rounding, so that the canonical JSON
 *                 parses back to the same bits
 *   move {vertex, to: [x,y,z] | by: [dx,dy,dz], schedule
 *                 "local-exp"|"scaled"|"global-exp" ["local-exp"],
 *                 max_steps ≥ 1 [10000]}
 *   inversion_stats {samples 1..100000 [100], magnitudes: [m > 0, ...]
 *                 [1, .5, .1, .05, .01, .005, .001, .0005, .0001, .00005],
 *                 seed [1], schedule ["local-exp"]}
 *   triangulate {quad_levels 1..11 [9], binary_levels 1..20 [10],
 *                 fill "area"|"edges" ["area"], refine [true],
 *                 fair "uniform"|"length"|"none" ["uniform"],
 *                 sharpen [true]} — an F-rep input (lib/frep/triangulate.h)
 *                 to a mesh; only as the first op of a job whose input is
 *                 a frep-object/1
 *   fill {weight "area"|"length" ["area"], refine [true], fair [true],
 *         parts_overlap [false], remove_crossing [false]}
 *   stitch
 *   report {gear 1..100000 [96], axis?: [x, y, z], scan [false]} — the
 *                 stone's tiers, proportions and facet table
 *                 (lib/gem/report.h); with scan, each facet's deviation
 *                 from the job's input model (the raw scan a correction
 *                 started from); reads the model, changes nothing
 *   compare {reference: facet-model/1, axis?: [x, y, z]} — lays the job's
 *                 model onto the reference (its design, an earlier scan)
 *                 and measures them (lib/gem/compare.h); the reference is
 *                 read with the limits of a job's model and must have a
 *                 table unless an axis is given; changes nothing
 * The pipeline "correct" is the post-scan correction: inspect → correct →
 * inspect, with the defaults above; the correct op merges (automatic
 * groups) and collapses clusters, repeating both until nothing changes (in
 * the order and with the repeats that lib/correct/correct.h explains).
 *
 * Deprecated names, accepted for one release (each use is reported by
 * proto_pipeline_deprecations): "auto" (correct), merge_facets,
 * fill_holes, move_vertex, collapse_clusters, "inversion-stats".
 *
 * Ownership: a proto_pipeline owns its arrays; proto_pipeline_free
 * releases them. Functions are reentrant and thread-safe. */
#ifndef PROTO_PIPELINE_H
#define PROTO_PIPELINE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <jansson.h>

#include "ctx.h"
#include "poly.h"

typedef enum proto_op_kind {
    PROTO_OP_INSPECT = 0,
    PROTO_OP_COLLAPSE,
    PROTO_OP_MERGE,
    PROTO_OP_CUT,
    PROTO_OP_MOVE,
    PROTO_OP_INVERSION_STATS,
    PROTO_OP_TRIANGULATE,
    PROTO_OP_FILL,
    PROTO_OP_STITCH,
    PROTO_OP_CORRECT,
    PROTO_OP_REPORT,
    PROTO_OP_COMPARE,
    PROTO_OP_COUNT
} proto_op_kind;

typedef enum proto_schedule {
    PROTO_SCHED_LOCAL_EXP = 0, /* Palachev 2012, §4.3.1 */
    PROTO_SCHED_SCALED,        /* §4.3.2 */
    PROTO_SCHED_GLOBAL_EXP,    /* §4.3.3 */
    PROTO_SCHED_LEAST_NORM,    /* least sum of squares, planes free */
} proto_schedule;

typedef enum proto_fair {
    PROTO_FAIR_NONE = 0,
    PROTO_FAIR_UNIFORM, /* w = 1 (Vyatkin, closed form) */
    PROTO_FAIR_LENGTH,  /* w = edge length (gradient descent) */
} proto_fair;

enum { PROTO_PIPELINE_MAX_OPS = 64, PROTO_MAX_MAGNITUDES = 64,
       PROTO_MAX_VIEWS = 100000 };

typedef struct proto_op {
    proto_op_kind kind;
    const char *alias; /* the deprecated name it was given, or NULL */
    union {
        struct {
            /* an inspect after an op that changed the model fails the job
             * when the model is not valid, unless this is set */
            bool keep_invalid;
        } inspect;
        struct {
            double radius;
        } collapse;
        struct {
            double max_angle_deg, max_deviation;
            uint32_t views;      /* scanner views over 180°, 0: read off */
            uint32_t ngroups;    /* 0: find groups automatically */
            uint32_t *gstart;    /* ngroups + 1 offsets into gfacets */
            uint32_t *gfacets;   /* facet indices of every group */
        } merge;
        struct {
            double plane[4];     /* unit normal, offset */
        } cut;
        struct {
            double radius, max_angle_deg, max_deviation;
            uint32_t views;      /* scanner views over 180°, 0: read off */
            bool convex;         /* geo_correct_opts.convex */
        } correct;
        struct {
            uint32_t vertex;
            double xyz[3];
            bool relative;       /* xyz is "by" (else "to") */
            proto_schedule schedule;
            uint32_t max_steps;
        } move;
        struct {
            uint32_t samples;
            uint32_t nmagnitudes;
            double magnitudes[PROTO_MAX_MAGNITUDES];
            uint64_t seed;
            proto_schedule schedule;
        } inversion;
        struct {
            uint32_t quad_levels, binary_levels;
            bool fill_edges;     /* weight holes by edge length (else area) */
            bool refine, sharpen;
            proto_fair fair;
        } triangulate;
        struct {
            uint32_t gear;       /* teeth of the index gear */
            bool have_axis;
            double axis[3];      /* the main axis, when given */
            bool scan;           /* deviations from the job's input */
        } report;
        struct {
            geo_poly *reference; /* A, owned; the job's model is B */
            bool have_axis;
            double axis[3];      /* the main axis, when given */
        } compare;
        struct {
            bool weight_length;  /* weight by edge length (else area) */
            bool refine, fair;
            bool parts_overlap;  /* geo_mesh_fill_opts.parts_overlap */
            bool remove_crossing; /* geo_mesh_fill_opts.remove_crossing */
        } fill;
    } u;
} proto_op;

typedef struct proto_pipeline {
    size_t nops;
    proto_op *ops;
} proto_pipeline;

/* The operation's name as in the API ("merge"); NULL if invalid. */
const char *proto_op_name(proto_op_kind kind);

/* The current name of the op called name (itself, or what a deprecated
 * alias stands for); NULL for no op. */
const char *proto_op_canonical(const char *name);

/* Writes "op 'auto' is deprecated: use 'correct'; ..." into buf (size
 * bytes, always terminated) for each deprecated name p was given, and
 * returns how many there were (0: buf is ""). */
size_t proto_pipeline_deprecations(const proto_pipeline *p, char *buf,
                                   size_t size);

/* Parses a pipeline value (array or "correct") into *ret. where names the
 * value in messages (e.g. "pipeline"; NULL for none). 0, or -EINVAL with
 * err naming the place, or -ENOMEM; *ret is untouched on error. */
int proto_pipeline_from_json(const json_t *v, const char *where,
                             proto_pipeline *ret, geo_err *err);

/* The canonical JSON (an array of op objects with every parameter), or
 * NULL on out-of-memory. Parsing it gives the same pipeline. */
json_t *proto_pipeline_to_json(const proto_pipeline *p);

/* A deep copy of src into *ret (free with proto_pipeline_free). 0 or
 * -ENOMEM (*ret untouched). */
int proto_pipeline_copy(const proto_pipeline *src, proto_pipeline *ret);

/* Sets views (the scanner's contours over 180°) on every merge_facets and
 * auto op of p that would otherwise read them off the model. */
void proto_pipeline_set_views(proto_pipeline *p, uint32_t views);

/* Frees the arrays of p and zeroes it; accepts NULL. */
void proto_pipeline_free(proto_pipeline *p);

#endif
