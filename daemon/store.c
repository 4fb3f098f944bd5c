/* store.c — the store interface's dispatch to its backend (store.h).
 * Arguments are checked here once so that backends can assume them. */
#include "store.h"

#include <errno.h>
#include <string.h>

static int bad_id(const char *id, geo_err *err)
{
    return geo_err_set(err, -ENOENT, "no job '%.40s'", id ? id : "");
}

int store_put(store *s, const store_new_job *j, unsigned max_queued,
              job_rec *ret_existing, geo_err *err)
{
    if (!job_id_valid(j->id) || !j->source ||
        strlen(j->source) >= JOB_SOURCE_MAX ||
        (j->label && strlen(j->label) >= JOB_LABEL_MAX) || !j->pipeline ||
        (!j->input && j->input_len))
        return geo_err_set(err, -EINVAL, "store_put: invalid job");
    return s->ops->put(s, j, max_queued, ret_existing, err);
}

int store_claim(store *s, job_rec *ret, geo_err *err)
{
    return s->ops->claim(s, ret, err);
}

int store_progress(store *s, const char *id, double progress,
                   int *ret_cancel, geo_err *err)
{
    if (!job_id_valid(id))
        return bad_id(id, err);
    if (!(progress >= 0))
        progress = 0;
    if (progress > 1)
        progress = 1;
    return s->ops->progress(s, id, progress, ret_cancel, err);
}

int store_finish(store *s, const char *id, job_state state,
                 const char *error, const char *summary, const void *model,
                 size_t model_len, const void *stats, size_t stats_len,
                 geo_err *err)
{
    if (!job_id_valid(id))
        return bad_id(id, err);
    if (!job_state_terminal(state))
        return geo_err_set(err, -EINVAL, "store_finish: not a final state");
    return s->ops->finish(s, id, state, error, summary, model, model_len,
                          stats, stats_len, err);
}

int store_requeue(store *s, const char *id, geo_err *err)
{
    if (!job_id_valid(id))
        return bad_id(id, err);
    return s->ops->requeue(s, id, err);
}

int store_cancel(store *s, const char *id, job_rec *ret, geo_err *err)
{
    if (!job_id_valid(id))
        return bad_id(id, err);
    return s->ops->cancel(s, id, ret, err);
}

int store_remove(store *s, const char *id, geo_err *err)
{
    if (!job_id_valid(id))
        return bad_id(id, err);
    return s->ops->remove(s, id, err);
}

int store_get(store *s, const char *id, job_rec *ret, geo_err *err)
{
    if (!job_id_valid(id))
        return bad_id(id, err);
    return s->ops->get(s, id, ret, err);
}

int store_get_blob(store *s, const char *id, store_blob which, void **ret,
                   size_t *ret_len, geo_err *err)
{
    if (!job_id_valid(id))
        return bad_id(id, err);
    return s->ops->get_blob(s, id, which, ret, ret_len, err);
}

int store_list(store *s, const store_filter *f, job_rec **ret, size_t *ret_n,
               geo_err *err)
{
    if (f->limit < 1 || f->limit > 1000)
        return geo_err_set(err, -EINVAL, "limit: must be 1..1000");
    if (f->after && !job_id_valid(f->after))
        return geo_err_set(err, -EINVAL, "after: not a job id");
    return s->ops->list(s, f, ret, ret_n, err);
}

int store_recover(store *s, unsigned *ret_n, geo_err *err)
{
    return s->ops->recover(s, ret_n, err);
}

int store_retention(store *s, int64_t older_than_ms, uint64_t max_bytes,
                    unsigned *ret_deleted, geo_err *err)
{
    return s->ops->retention(s, older_than_ms, max_bytes, ret_deleted, err);
}

int store_count(store *s, store_counts *ret, geo_err *err)
{
    return s->ops->counts(s, ret, err);
}

int store_ping(store *s, geo_err *err)
{
    return s->ops->ping(s, err);
}

void store_set_events(store *s, const store_events *ev)
{
    if (s->ops->set_events)
        s->ops->set_events(s, ev);
}

const char *store_node(store *s)
{
    return s->ops->node ? s->ops->node(s) : NULL;
}

store *store_close(store *s)
{
    if (s)
        s->ops->close(s);
    return NULL;
}
