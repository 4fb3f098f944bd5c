/* replanar_json.c — iteration logs, move results and inversion tables as
 * JSON (shapes in replanar_json.h). Builds with jansson's steal-reference
 * setters; any allocation failure makes the whole value NULL. */
#include "replanar_json.h"

#include <inttypes.h>
#include <math.h>
#include <stdio.h>

/* Sets key on obj from a new value; marks *ok false when either fails. */
static void put(json_t *obj, const char *key, json_t *val, bool *ok)
{
    if (!val || json_object_set_new(obj, key, val) < 0)
        *ok = false;
}

static json_t *num(double x)
{
    return isfinite(x) ? json_real(x) : json_null();
}

static json_t *count(int64_t n)
{
    return n < 0 ? json_null() : json_integer((json_int_t)n);
}

static json_t *finish(json_t *obj, bool ok)
{
    if (!ok) {
        json_decref(obj);
        return NULL;
    }
    return obj;
}

static json_t *proto_replanar_step_to_json(const geo_replanar_step *row)
{
    json_t *o = json_object();
    bool ok = o != NULL;
    if (!ok)
        return NULL;
    put(o, "step", json_integer(row->step), &ok);
    put(o, "outer", json_integer(row->outer), &ok);
    put(o, "inner", json_integer(row->inner), &ok);
    put(o, "delta", num(row->delta), &ok);
    put(o, "s1", num(row->s1), &ok);
    put(o, "s2", num(row->s2), &ok);
    put(o, "s2sum", num(row->s2sum), &ok);
    put(o, "eps0", num(row->eps0), &ok);
    put(o, "k", num(row->k), &ok);
    put(o, "selfint", count(row->nselfint), &ok);
    put(o, "active_vertices", json_integer(row->active_vertices), &ok);
    put(o, "active_facets", json_integer(row->active_facets), &ok);
    return finish(o, ok);
}

json_t *proto_replanar_log_to_json(const geo_replanar_log *log)
{
    json_t *a = json_array();
    if (!a)
        return NULL;
    for (size_t i = 0; i < log->n; i++)
        if (json_array_append_new(a, proto_replanar_step_to_json(
                                         &log->rows[i])) < 0) {
            json_decref(a);
            return NULL;
        }
    return a;
}

json_t *proto_replanar_result_to_json(const geo_replanar_result *r,
                                      enum geo_replanar_schedule schedule)
{
    json_t *o = json_object();
    bool ok = o != NULL;
    if (!ok)
        return NULL;
    put(o, "schedule", json_string(geo_replanar_schedule_name(schedule)),
        &ok);
    put(o, "converged", json_boolean(r->converged), &ok);
    put(o, "valid", json_boolean(geo_replanar_result_valid(r)), &ok);
    put(o, "steps", json_integer(r->steps), &ok);
    put(o, "s1", num(r->s1), &ok);
    put(o, "s2", num(r->s2), &ok);
    put(o, "k", num(r->k), &ok);
    put(o, "active_vertices", json_integer(r->active_vertices), &ok);
    put(o, "active_facets", json_integer(r->active_facets), &ok);
    put(o, "selfint", count(r->nselfint), &ok);
    put(o, "inverted_facets", count(r->ninverted), &ok);
    put(o, "volume", num(r->volume), &ok);
    put(o, "first_selfint_step", count(r->first_selfint_step), &ok);
    put(o, "fixed_residual", num(r->fixed_resid), &ok);
    return finish(o, ok);
}

static json_t *row_to_json(const geo_inversion_row *row)
{
    json_t *o = json_object();
    bool ok = o != NULL;
    if (!ok)
        return NULL;
    put(o, "m", num(row->m), &ok);
    put(o, "runs", json_integer(row->runs), &ok);
    put(o, "inverted", json_integer(row->inverted), &ok);
    put(o, "p", num(row->p), &ok);
    put(o, "ci95", json_pack("[ff]", row->lo, row->hi), &ok);
    put(o, "not_converged", json_integer(row->not_converged), &ok);
    put(o, "selfint", json_integer(row->selfint), &ok);
    put(o, "inverted_facets", json_integer(row->inverted_facets), &ok);
    put(o, "nonpositive_volume", json_integer(row->nonpositive_volume), &ok);
    return finish(o, ok);
}

static json_t *run_to_json(const geo_inversion_run *r)
{
    json_t *o = json_object();
    bool ok = o != NULL;
    if (!ok)
        return NULL;
    put(o, "sample", json_integer(r->sample), &ok);
    put(o, "vertex", json_integer(r->vertex), &ok);
    put(o, "m", num(r->m), &ok);
    put(o, "delta", num(r->delta), &ok);
    put(o, "dir", json_pack("[fff]", r->dir[0], r->dir[1], r->dir[2]), &ok);
    put(o, "inverted", json_boolean(r->inverted), &ok);
    put(o, "converged", json_boolean(r->converged), &ok);
    put(o, "steps", json_integer(r->steps), &ok);
    put(o, "selfint", count(r->nselfint), &ok);
    put(o, "inverted_facets", count(r->ninverted), &ok);
    put(o, "volume", num(r->volume), &ok);
    put(o, "first_selfint_step", count(r->first_selfint_step), &ok);
    return finish(o, ok);
}

json_t *proto_inversion_stats_to_json(const geo_inversion_stats *s)
{
    json_t *o = json_object();
    bool ok = o != NULL;
    if (!ok)
        return NULL;
    put(o, "samples", json_integer(s->samples), &ok);
    if (s->seed <= (uint64_t)INT64_MAX) {
        put(o, "seed", json_integer((json_int_t)s->seed), &ok);
    } else {
        char buf[24];
        snprintf(buf, sizeof buf, "%" PRIu64, s->seed);
        put(o, "seed", json_string(buf), &ok);
    }
    put(o, "schedule", json_string(geo_replanar_schedule_name(s->schedule)),
        &ok);
    json_t *table = json_array();
    for (uint32_t i = 0; table && i < s->nrows; i++)
        if (json_array_append_new(table, row_to_json(&s->rows[i])) < 0)
            ok = false;
    put(o, "table", table, &ok);
    if (s->runs) {
        json_t *runs = json_array();
        for (uint32_t i = 0; runs && i < s->nruns; i++)
            if (json_array_append_new(runs, run_to_json(&s->runs[i])) < 0)
                ok = false;
        put(o, "runs", runs, &ok);
    }
    return finish(o, ok);
}
