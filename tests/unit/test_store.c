/* test_store.c — the SQLite job store keeps the contract of store.h:
 * committed jobs survive a reopen, claims follow priority then age and
 * hand each job out once, the queue bound and idempotency keys hold,
 * state transitions are the allowed ones only, listing pages newest first,
 * recovery requeues running jobs, and retention deletes oldest finished
 * jobs first and never a queued one. Each test runs in its own temporary
 * directory. */
#include "testutil.h"

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <sqlite3.h>

#include "store.h"

typedef struct fixture {
    char dir[64];
    store *s;
} fixture;

static int setup(void **state)
{
    fixture *f = calloc(1, sizeof *f);
    snprintf(f->dir, sizeof f->dir, "/tmp/facet-store-XXXXXX");
    assert_non_null(mkdtemp(f->dir));
    geo_err err = {{0}};
    f->s = store_sqlite_open(f->dir, &err);
    if (!f->s)
        fail_msg("open: %s", err.msg);
    *state = f;
    return 0;
}

static int teardown(void **state)
{
    fixture *f = *state;
    store_close(f->s);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", f->dir);
    assert_int_equal(system(cmd), 0);
    free(f);
    return 0;
}

/* Adds a job with a fresh id; returns its id in ret_id. */
static int put(store *s, job_priority prio, const char *source,
               const char *idem, char ret_id[JOB_ID_LEN + 1],
               unsigned max_queued)
{
    static int64_t clock_ms = 1700000000000;
    job_id_new(ret_id, ++clock_ms);
    store_new_job j = {
        .id = ret_id, .priority = prio, .source = source, .label = "t",
        .pipeline = "[\"inspect\"]", .input = "{\"m\":1}", .input_len = 7,
        .idem_key = idem, .idem_hash = 42, .created_ms = clock_ms,
    };
    job_rec old;
    int r = store_put(s, &j, max_queued, &old, NULL);
    if (r == -EEXIST) {
        memcpy(ret_id, old.id, sizeof old.id);
        job_rec_clear(&old);
    }
    return r;
}

static void test_put_is_committed_and_survives_reopen(void **state)
{
    fixture *f = *state;
    char id[JOB_ID_LEN + 1];
    assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", NULL, id, 10), 0);
    job_rec r;
    assert_int_equal(store_get(f->s, id, &r, NULL), 0);
    assert_string_equal(r.id, id);
    assert_int_equal(r.state, JOB_QUEUED);
    assert_int_equal(r.version, 1);
    assert_string_equal(r.source, "http");
    assert_string_equal(r.pipeline, "[\"inspect\"]");
    assert_int_equal(r.input_bytes, 7);
    job_rec_clear(&r);
    f->s = store_close(f->s);
    f->s = store_sqlite_open(f->dir, NULL);
    assert_non_null(f->s);
    assert_int_equal(store_get(f->s, id, &r, NULL), 0);
    assert_int_equal(r.state, JOB_QUEUED);
    job_rec_clear(&r);
    void *blob;
    size_t len;
    assert_int_equal(store_get_blob(f->s, id, STORE_BLOB_INPUT, &blob, &len,
                                    NULL), 0);
    assert_int_equal(len, 7);
    assert_memory_equal(blob, "{\"m\":1}", 7);
    free(blob);
}

static void test_second_open_of_one_directory_is_refused(void **state)
{
    fixture *f = *state;
    geo_err err = {{0}};
    assert_null(store_sqlite_open(f->dir, &err));
    assert_non_null(strstr(err.msg, "another facetd"));
}

static void test_claim_takes_high_priority_first_then_oldest(void **state)
{
    fixture *f = *state;
    char a[27], b[27], c[27], d[27];
    assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", NULL, a, 10), 0);
    assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", NULL, b, 10), 0);
    assert_int_equal(put(f->s, JOB_PRIO_HIGH, "usb:SN-1", NULL, c, 10), 0);
    assert_int_equal(put(f->s, JOB_PRIO_HIGH, "usb:SN-1", NULL, d, 10), 0);
    const char *order[] = {c, d, a, b};
    for (int i = 0; i < 4; i++) {
        job_rec r;
        assert_int_equal(store_claim(f->s, &r, NULL), 0);
        assert_string_equal(r.id, order[i]);
        assert_int_equal(r.state, JOB_RUNNING);
        assert_int_equal(r.attempts, 1);
        assert_true(r.started_ms > 0);
        job_rec_clear(&r);
    }
    job_rec r;
    assert_int_equal(store_claim(f->s, &r, NULL), -ENOENT);
}

static void test_queue_bound_rejects_without_writing(void **state)
{
    fixture *f = *state;
    char id[27];
    for (int i = 0; i < 3; i++)
        assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", NULL, id, 3), 0);
    assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", NULL, id, 3), -EAGAIN);
    store_counts n;
    assert_int_equal(store_count(f->s, &n, NULL), 0);
    assert_int_equal(n.by_state[JOB_QUEUED], 3);
    /* A running job no longer counts against the queue. */
    job_rec r;
    assert_int_equal(store_claim(f->s, &r, NULL), 0);
    job_rec_clear(&r);
    assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", NULL, id, 3), 0);
}

static void test_idempotency_key_returns_the_first_job(void **state)
{
    fixture *f = *state;
    char a[27], b[27];
    assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", "key-1", a, 10), 0);
    assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", "key-1", b, 10),
                     -EEXIST);
    assert_string_equal(a, b);
    store_counts n;
    assert_int_equal(store_count(f->s, &n, NULL), 0);
    assert_int_equal(n.by_state[JOB_QUEUED], 1);
    job_rec r;
    assert_int_equal(store_get(f->s, a, &r, NULL), 0);
    assert_int_equal(r.idem_hash, 42);
    job_rec_clear(&r);
}

static void test_finish_keeps_results_and_ends_the_job(void **state)
{
    fixture *f = *state;
    char id[27];
    assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", NULL, id, 10), 0);
    int cancel = -1;
    assert_int_equal(store_progress(f->s, id, 0.5, &cancel, NULL), -EBUSY);
    job_rec r;
    assert_int_equal(store_claim(f->s, &r, NULL), 0);
    int64_t v = r.version;
    job_rec_clear(&r);
    assert_int_equal(store_progress(f->s, id, 0.25, &cancel, NULL), 0);
    assert_int_equal(cancel, 0);
    assert_int_equal(store_get(f->s, id, &r, NULL), 0);
    assert_true(r.version > v);
    assert_true(r.progress == 0.25);
    job_rec_clear(&r);
    assert_int_equal(store_finish(f->s, id, JOB_SUCCEEDED, NULL, "{\"ok\":1}",
                                  "MODEL", 5, "STATS!", 6, NULL), 0);
    assert_int_equal(store_get(f->s, id, &r, NULL), 0);
    assert_int_equal(r.state, JOB_SUCCEEDED);
    assert_true(r.progress == 1.0);
    assert_string_equal(r.summary, "{\"ok\":1}");
    assert_int_equal(r.result_bytes, 11);
    assert_true(r.result_hash == job_digest64("MODEL", 5));
    assert_true(r.finished_ms >= r.started_ms);
    job_rec_clear(&r);
    void *b;
    size_t n;
    assert_int_equal(store_get_blob(f->s, id, STORE_BLOB_STATS, &b, &n, NULL), 0);
    assert_int_equal(n, 6);
    assert_string_equal(b, "STATS!");
    free(b);
    /* A finished job cannot finish again or report progress. */
    assert_int_equal(store_finish(f->s, id, JOB_FAILED, "x", NULL, NULL, 0,
                                  NULL, 0, NULL), -EBUSY);
    assert_int_equal(store_progress(f->s, id, 0.5, NULL, NULL), -EBUSY);
}

static void test_unchanged_result_is_the_input_kept_once(void **state)
{
    fixture *f = *state;
    char id[27], failed[27];
    assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", NULL, id, 10), 0);
    assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", NULL, failed, 10), 0);
    job_rec r;
    assert_int_equal(store_claim(f->s, &r, NULL), 0);
    job_rec_clear(&r);
    assert_int_equal(store_claim(f->s, &r, NULL), 0);
    job_rec_clear(&r);
    assert_int_equal(store_finish(f->s, id, JOB_SUCCEEDED, NULL, "{}", NULL,
                                  0, "STATS", 5, NULL), 0);
    assert_int_equal(store_finish(f->s, failed, JOB_FAILED, "no", NULL, NULL,
                                  0, NULL, 0, NULL), 0);
    assert_int_equal(store_get(f->s, id, &r, NULL), 0);
    assert_int_equal(r.result_bytes, 5);
    assert_true(r.result_hash == job_digest64(id, strlen(id)));
    job_rec_clear(&r);
    void *b;
    size_t n;
    assert_int_equal(store_get_blob(f->s, id, STORE_BLOB_MODEL, &b, &n, NULL),
                     0);
    assert_int_equal(n, 7);
    assert_memory_equal(b, "{\"m\":1}", 7);
    free(b);
    /* a failed job has no result, not its input */
    assert_int_equal(store_get_blob(f->s, failed, STORE_BLOB_MODEL, &b, &n,
                                    NULL), -ENOENT);
    assert_int_equal(store_get(f->s, failed, &r, NULL), 0);
    assert_true(r.result_hash == 0);
    job_rec_clear(&r);
}

static void test_cancel_queued_ends_it_running_flags_it(void **state)
{
    fixture *f = *state;
    char a[27], b[27];
    assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", NULL, a, 10), 0);
    assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", NULL, b, 10), 0);
    job_rec r;
    assert_int_equal(store_claim(f->s, &r, NULL), 0);
    assert_string_equal(r.id, a);
    job_rec_clear(&r);
    /* b is queued: canceled at once. */
    assert_int_equal(store_cancel(f->s, b, &r, NULL), 0);
    assert_int_equal(r.state, JOB_CANCELED);
    assert_true(r.finished_ms > 0);
    job_rec_clear(&r);
    /* a is running: flagged, its next progress report says so. */
    assert_int_equal(store_cancel(f->s, a, &r, NULL), 0);
    assert_int_equal(r.state, JOB_RUNNING);
    assert_true(r.cancel_requested);
    job_rec_clear(&r);
    int cancel = 0;
    assert_int_equal(store_progress(f->s, a, 0.1, &cancel, NULL), 0);
    assert_int_equal(cancel, 1);
    assert_int_equal(store_finish(f->s, a, JOB_CANCELED, "canceled", NULL,
                                  NULL, 0, NULL, 0, NULL), 0);
    /* Terminal: cancel changes nothing but still reports the job. */
    assert_int_equal(store_cancel(f->s, a, &r, NULL), -EBUSY);
    assert_int_equal(r.state, JOB_CANCELED);
    job_rec_clear(&r);
    char missing[27];
    job_id_new(missing, 1);
    assert_int_equal(store_cancel(f->s, missing, NULL, NULL), -ENOENT);
    assert_int_equal(store_cancel(f->s, "not-an-id", NULL, NULL), -ENOENT);
}

static void test_remove_only_deletes_finished_jobs(void **state)
{
    fixture *f = *state;
    char id[27];
    assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", NULL, id, 10), 0);
    assert_int_equal(store_remove(f->s, id, NULL), -EBUSY);
    job_rec r;
    assert_int_equal(store_claim(f->s, &r, NULL), 0);
    job_rec_clear(&r);
    assert_int_equal(store_remove(f->s, id, NULL), -EBUSY);
    assert_int_equal(store_finish(f->s, id, JOB_FAILED, "boom", NULL, NULL, 0,
                                  NULL, 0, NULL), 0);
    assert_int_equal(store_remove(f->s, id, NULL), 0);
    assert_int_equal(store_get(f->s, id, &r, NULL), -ENOENT);
    void *b;
    size_t n;
    assert_int_equal(store_get_blob(f->s, id, STORE_BLOB_INPUT, &b, &n, NULL),
                     -ENOENT);
    assert_int_equal(store_remove(f->s, id, NULL), -ENOENT);
}

static void test_list_pages_newest_first_with_filters(void **state)
{
    fixture *f = *state;
    char ids[7][27];
    for (int i = 0; i < 7; i++)
        assert_int_equal(put(f->s, JOB_PRIO_NORMAL, i % 2 ? "usb:SN-7" : "http",
                             NULL, ids[i], 100), 0);
    job_rec r;
    assert_int_equal(store_claim(f->s, &r, NULL), 0); /* ids[0] runs */
    job_rec_clear(&r);
    store_filter flt = {.state = -1, .limit = 3};
    job_rec *v;
    size_t n;
    assert_int_equal(store_list(f->s, &flt, &v, &n, NULL), 0);
    assert_int_equal(n, 3);
    assert_string_equal(v[0].id, ids[6]);
    assert_string_equal(v[2].id, ids[4]);
    char after[27];
    memcpy(after, v[2].id, sizeof after);
    for (size_t i = 0; i < n; i++)
        job_rec_clear(&v[i]);
    free(v);
    flt.after = after;
    flt.limit = 10;
    assert_int_equal(store_list(f->s, &flt, &v, &n, NULL), 0);
    assert_int_equal(n, 4);
    assert_string_equal(v[0].id, ids[3]);
    assert_string_equal(v[3].id, ids[0]);
    for (size_t i = 0; i < n; i++)
        job_rec_clear(&v[i]);
    free(v);
    store_filter by_source = {.state = -1, .source = "usb:SN-7", .limit = 10};
    assert_int_equal(store_list(f->s, &by_source, &v, &n, NULL), 0);
    assert_int_equal(n, 3);
    for (size_t i = 0; i < n; i++) {
        assert_string_equal(v[i].source, "usb:SN-7");
        job_rec_clear(&v[i]);
    }
    free(v);
    store_filter running = {.state = JOB_RUNNING, .limit = 10};
    assert_int_equal(store_list(f->s, &running, &v, &n, NULL), 0);
    assert_int_equal(n, 1);
    assert_string_equal(v[0].id, ids[0]);
    job_rec_clear(&v[0]);
    free(v);
    store_filter bad = {.state = -1, .limit = 0};
    assert_int_equal(store_list(f->s, &bad, &v, &n, NULL), -EINVAL);
}

static void test_recover_requeues_running_jobs(void **state)
{
    fixture *f = *state;
    char a[27], b[27];
    assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", NULL, a, 10), 0);
    assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", NULL, b, 10), 0);
    job_rec r;
    assert_int_equal(store_claim(f->s, &r, NULL), 0);
    job_rec_clear(&r);
    f->s = store_close(f->s);
    f->s = store_sqlite_open(f->dir, NULL);
    unsigned n = 0;
    assert_int_equal(store_recover(f->s, &n, NULL), 0);
    assert_int_equal(n, 1);
    assert_int_equal(store_get(f->s, a, &r, NULL), 0);
    assert_int_equal(r.state, JOB_QUEUED);
    job_rec_clear(&r);
    /* It is claimed again first (it is the oldest) and counts attempts. */
    assert_int_equal(store_claim(f->s, &r, NULL), 0);
    assert_string_equal(r.id, a);
    assert_int_equal(r.attempts, 2);
    job_rec_clear(&r);
}

static void finish_one(store *s, const char *expect_id, size_t model_len)
{
    job_rec r;
    assert_int_equal(store_claim(s, &r, NULL), 0);
    assert_string_equal(r.id, expect_id);
    job_rec_clear(&r);
    char *model = calloc(1, model_len);
    assert_int_equal(store_finish(s, expect_id, JOB_SUCCEEDED, NULL, NULL,
                                  model, model_len, NULL, 0, NULL), 0);
    free(model);
}

static void test_retention_deletes_oldest_finished_first(void **state)
{
    fixture *f = *state;
    char ids[5][27];
    for (int i = 0; i < 5; i++)
        assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", NULL, ids[i], 10), 0);
    for (int i = 0; i < 4; i++) {
        finish_one(f->s, ids[i], 100000);
        usleep(2000); /* distinct finish times */
    }
    /* Age: nothing finished before the epoch. */
    unsigned del = 99;
    assert_int_equal(store_retention(f->s, 0, UINT64_MAX, &del, NULL), 0);
    assert_int_equal(del, 0);
    /* Size: keep ≤ 250,000 bytes → the two oldest finished go. */
    assert_int_equal(store_retention(f->s, 0, 250000, &del, NULL), 0);
    assert_int_equal(del, 2);
    job_rec r;
    assert_int_equal(store_get(f->s, ids[0], &r, NULL), -ENOENT);
    assert_int_equal(store_get(f->s, ids[1], &r, NULL), -ENOENT);
    assert_int_equal(store_get(f->s, ids[2], &r, NULL), 0);
    job_rec_clear(&r);
    /* Age: everything finished before now goes; the queued job stays. */
    assert_int_equal(store_retention(f->s, job_now_ms() + 1000, UINT64_MAX,
                                     &del, NULL), 0);
    assert_int_equal(del, 2);
    assert_int_equal(store_get(f->s, ids[4], &r, NULL), 0);
    assert_int_equal(r.state, JOB_QUEUED);
    job_rec_clear(&r);
    /* A size cap below the queued job's size deletes nothing more. */
    assert_int_equal(store_retention(f->s, 0, 1, &del, NULL), 0);
    assert_int_equal(del, 0);
}

static void test_newer_schema_is_refused(void **state)
{
    fixture *f = *state;
    f->s = store_close(f->s);
    char path[128];
    snprintf(path, sizeof path, "%s/facetd.db", f->dir);
    sqlite3 *db;
    assert_int_equal(sqlite3_open(path, &db), SQLITE_OK);
    assert_int_equal(sqlite3_exec(db, "PRAGMA user_version=99", NULL, NULL,
                                  NULL), SQLITE_OK);
    sqlite3_close(db);
    geo_err err = {{0}};
    assert_null(store_sqlite_open(f->dir, &err));
    assert_non_null(strstr(err.msg, "schema version 99"));
}

typedef struct claimer {
    store *s;
    int claimed;
    char (*seen)[27];
} claimer;

static void *claim_all(void *arg)
{
    claimer *c = arg;
    job_rec r;
    while (store_claim(c->s, &r, NULL) == 0) {
        memcpy(c->seen[c->claimed++], r.id, 27);
        job_rec_clear(&r);
    }
    return NULL;
}

static void test_concurrent_claims_hand_out_each_job_once(void **state)
{
    fixture *f = *state;
    enum { N = 200, T = 4 };
    char ids[N][27];
    for (int i = 0; i < N; i++)
        assert_int_equal(put(f->s, JOB_PRIO_NORMAL, "http", NULL, ids[i], N), 0);
    pthread_t th[T];
    claimer c[T];
    for (int t = 0; t < T; t++) {
        c[t] = (claimer){f->s, 0, calloc(N, 27)};
        pthread_create(&th[t], NULL, claim_all, &c[t]);
    }
    int total = 0;
    for (int t = 0; t < T; t++) {
        pthread_join(th[t], NULL);
        total += c[t].claimed;
    }
    assert_int_equal(total, N);
    for (int i = 0; i < N; i++) {
        int hits = 0;
        for (int t = 0; t < T; t++)
            for (int k = 0; k < c[t].claimed; k++)
                hits += strcmp(c[t].seen[k], ids[i]) == 0;
        assert_int_equal(hits, 1);
    }
    for (int t = 0; t < T; t++)
        free(c[t].seen);
}

typedef struct putter {
    store *s;
    int base, fails;
} putter;

static void *put_many(void *arg)
{
    putter *p = arg;
    for (int i = 0; i < 40; i++) {
        char id[JOB_ID_LEN + 1];
        int64_t ms = 1800000000000 + p->base * 1000 + i;
        job_id_new(id, ms);
        store_new_job j = {
            .id = id, .priority = JOB_PRIO_NORMAL, .source = "http",
            .pipeline = "[\"inspect\"]", .input = "{}", .input_len = 2,
            .created_ms = ms,
        };
        p->fails += store_put(p->s, &j, 100000, NULL, NULL) != 0;
    }
    return NULL;
}

/* Submissions from several threads share WAL syncs (group commit); every
 * one returns committed, and all are there after reopening. */
static void test_concurrent_puts_are_all_committed(void **state)
{
    fixture *f = *state;
    enum { T = 6 };
    pthread_t th[T];
    putter p[T];
    for (int t = 0; t < T; t++) {
        p[t] = (putter){f->s, t, 0};
        pthread_create(&th[t], NULL, put_many, &p[t]);
    }
    for (int t = 0; t < T; t++) {
        pthread_join(th[t], NULL);
        assert_int_equal(p[t].fails, 0);
    }
    f->s = store_close(f->s);
    f->s = store_sqlite_open(f->dir, NULL);
    assert_non_null(f->s);
    store_counts c;
    assert_int_equal(store_count(f->s, &c, NULL), 0);
    assert_int_equal(c.by_state[JOB_QUEUED], T * 40);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
#define T(name) cmocka_unit_test_setup_teardown(name, setup, teardown)
        T(test_put_is_committed_and_survives_reopen),
        T(test_second_open_of_one_directory_is_refused),
        T(test_claim_takes_high_priority_first_then_oldest),
        T(test_queue_bound_rejects_without_writing),
        T(test_idempotency_key_returns_the_first_job),
        T(test_finish_keeps_results_and_ends_the_job),
        T(test_unchanged_result_is_the_input_kept_once),
        T(test_cancel_queued_ends_it_running_flags_it),
        T(test_remove_only_deletes_finished_jobs),
        T(test_list_pages_newest_first_with_filters),
        T(test_recover_requeues_running_jobs),
        T(test_retention_deletes_oldest_finished_first),
        T(test_newer_schema_is_refused),
        T(test_concurrent_claims_hand_out_each_job_once),
        T(test_concurrent_puts_are_all_committed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
