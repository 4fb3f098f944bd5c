/* test_job_pool.c — the worker pool runs queued jobs and records their
 * outcome, turns a cancel (local or flagged in the store) into the
 * canceled state, enforces the time limit, on shutdown puts an
 * unfinished job back in the queue instead of ending it, and gives a job
 * the shared parallel_for only while it runs alone. */
#include "testutil.h"

#include <errno.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "job_pool.h"
#include "store.h"

typedef struct fixture {
    char dir[64];
    store *s;
    atomic_int notified;
    atomic_int done;
} fixture;

/* Loops the pool's parallel_for was given (fake_parallel_for). */
static atomic_int pool_loops;

static void fake_parallel_for(void *user, size_t n,
                              void (*fn)(void *arg, size_t i), void *arg)
{
    (void)user;
    atomic_fetch_add(&pool_loops, 1);
    for (size_t i = 0; i < n; i++)
        fn(arg, i);
}

static void count_index(void *arg, size_t i)
{
    (void)i;
    atomic_fetch_add((atomic_int *)arg, 1);
}

/* Input "ok" succeeds, "fail" fails, "par" runs a loop of 4 through the
 * context and says in its summary how many indices ran, "spin" reports
 * progress every millisecond until canceled. A primed input (a string) is used in place
 * of the stored one; "take" is taken over (and freed here) and read as
 * "ok", any other is left to the pool. */
static int exec(void *user, const job_rec *job, const void *input,
                size_t len, job_decoded *decoded, const geo_ctx *ctx,
                job_outcome *ret)
{
    (void)user;
    (void)job;
    if (decoded) {
        assert_null(input);
        input = decoded->data;
        len = strlen(decoded->data);
        if (strcmp(decoded->data, "take") == 0) {
            free(decoded->data);
            decoded->data = NULL;
            input = "ok";
            len = 2;
        }
    }
    if (len == 2 && memcmp(input, "ok", 2) == 0) {
        ret->model = strdup("MODEL");
        ret->model_len = 5;
        ret->summary = strdup("{\"facets\":1}");
        return 0;
    }
    if (len == 3 && memcmp(input, "par", 3) == 0) {
        atomic_int ran = 0;
        geo_ctx_parallel_for(ctx, 4, count_index, &ran);
        char text[32];
        snprintf(text, sizeof text, "{\"ran\":%d}", atomic_load(&ran));
        ret->summary = strdup(text);
        return 0;
    }
    if (len == 4 && memcmp(input, "fail", 4) == 0) {
        ret->error = strdup("facets[3]: broken");
        return -EINVAL;
    }
    for (int i = 0;; i++) {
        if (geo_ctx_progress(ctx, (i % 1000) / 1000.0) < 0)
            return -ECANCELED;
        usleep(1000);
    }
}

static void on_notify(void *user, const char *id, bool progress_only)
{
    (void)id;
    (void)progress_only;
    atomic_fetch_add(&((fixture *)user)->notified, 1);
}

static void on_done(void *user, const job_rec *job, job_state st, double s)
{
    (void)job;
    (void)st;
    (void)s;
    atomic_fetch_add(&((fixture *)user)->done, 1);
}

static int setup(void **state)
{
    fixture *f = calloc(1, sizeof *f);
    snprintf(f->dir, sizeof f->dir, "/tmp/facet-pool-XXXXXX");
    assert_non_null(mkdtemp(f->dir));
    f->s = store_sqlite_open(f->dir, NULL);
    assert_non_null(f->s);
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

static job_pool *start(fixture *f, unsigned workers, uint64_t timeout_ms)
{
    job_pool_config c = {
        .workers = workers, .job_timeout_ms = timeout_ms,
        .progress_every_ms = 10, .parallel_for = fake_parallel_for,
        .exec = exec, .notify = on_notify, .done = on_done, .cb_user = f,
    };
    geo_err err;
    job_pool *p = job_pool_start(f->s, &c, &err);
    if (!p)
        fail_msg("%s", err.msg);
    return p;
}

static void submit(fixture *f, job_pool *p, const char *input,
                   char id[JOB_ID_LEN + 1])
{
    job_id_new(id, job_now_ms());
    store_new_job j = {.id = id, .source = "http", .pipeline = "[]",
                       .input = input, .input_len = strlen(input),
                       .created_ms = job_now_ms()};
    assert_int_equal(store_put(f->s, &j, 1000, NULL, NULL), 0);
    if (p)
        job_pool_wake(p);
}

/* Waits up to 10 s for job id to reach state; returns its record. */
static job_rec wait_state(fixture *f, const char *id, job_state want)
{
    job_rec r;
    for (int i = 0; i < 1000; i++) {
        assert_int_equal(store_get(f->s, id, &r, NULL), 0);
        if (r.state == want)
            return r;
        job_rec_clear(&r);
        usleep(10000);
    }
    fail_msg("job %s never became %s", id, job_state_name(want));
    return r;
}

static void test_jobs_run_and_outcomes_are_recorded(void **state)
{
    fixture *f = *state;
    job_pool *p = start(f, 2, 10000);
    char ok[27], bad[27];
    submit(f, p, "ok", ok);
    submit(f, p, "fail", bad);
    job_rec r = wait_state(f, ok, JOB_SUCCEEDED);
    assert_string_equal(r.summary, "{\"facets\":1}");
    assert_true(r.result_hash == job_digest64("MODEL", 5));
    job_rec_clear(&r);
    r = wait_state(f, bad, JOB_FAILED);
    assert_string_equal(r.error, "facets[3]: broken");
    job_rec_clear(&r);
    job_pool_stop(p, 1000);
    assert_true(atomic_load(&f->notified) >= 4);
    assert_int_equal(atomic_load(&f->done), 2);
}

static job_decoded text_input(const char *text, size_t bytes)
{
    return (job_decoded){strdup(text), bytes, free};
}

static void expect_state(fixture *f, const char *id, job_state want)
{
    job_rec r = wait_state(f, id, want);
    job_rec_clear(&r);
}

/* A primed input replaces the stored one for the job's run; an entry
 * pushed out by the budget, in bytes or in count, leaves the job to its
 * stored input; whatever the executor does not take, and what is still
 * held when the pool stops, the pool releases (the sanitizer build
 * checks that nothing leaks). */
static void test_primed_inputs_replace_the_stored_ones(void **state)
{
    fixture *f = *state;
    char a[27], b[27], c[27], d[27], e[27], g[27];
    job_pool *p = start(f, 1, 10000);
    job_pool_set_paused(p, true);
    submit(f, p, "fail", a);
    job_pool_prime(p, a, text_input("ok", 2));
    submit(f, p, "fail", b);
    job_pool_prime(p, b, text_input("take", 4));
    submit(f, p, "ok", c);
    /* larger than the budget alone: released at once, the rest stays */
    job_pool_prime(p, c, text_input("fail", JOB_POOL_PRIMED_BYTES + 1));
    /* withdrawn: the stored input runs */
    char w[27];
    submit(f, p, "ok", w);
    job_pool_prime(p, w, text_input("fail", 4));
    job_pool_unprime(p, w);
    job_pool_set_paused(p, false);
    expect_state(f, a, JOB_SUCCEEDED);
    expect_state(f, b, JOB_SUCCEEDED);
    expect_state(f, c, JOB_SUCCEEDED);
    expect_state(f, w, JOB_SUCCEEDED);
    job_pool_stop(p, 1000);

    /* the budget in bytes: e's entry pushes d's out */
    p = start(f, 1, 10000);
    job_pool_set_paused(p, true);
    submit(f, p, "fail", d);
    job_pool_prime(p, d, text_input("ok", 2));
    submit(f, p, "ok", e);
    job_pool_prime(p, e, text_input("fail", JOB_POOL_PRIMED_BYTES));
    job_pool_set_paused(p, false);
    expect_state(f, d, JOB_FAILED);
    expect_state(f, e, JOB_FAILED);
    job_pool_stop(p, 1000);

    /* the budget in count: entries for jobs run elsewhere push g's out,
     * and the pool stops holding them */
    p = start(f, 1, 10000);
    job_pool_set_paused(p, true);
    submit(f, p, "fail", g);
    job_pool_prime(p, g, text_input("ok", 1));
    for (int i = 0; i < JOB_POOL_PRIMED_MAX; i++) {
        char id[JOB_ID_LEN + 1];
        snprintf(id, sizeof id, "elsewhere-%d", i);
        job_pool_prime(p, id, text_input("ok", 1));
    }
    job_pool_set_paused(p, false);
    expect_state(f, g, JOB_FAILED);
    job_pool_stop(p, 1000);
}

static void test_local_cancel_stops_a_running_job(void **state)
{
    fixture *f = *state;
    job_pool *p = start(f, 1, 60000);
    char id[27];
    submit(f, p, "spin", id);
    job_rec r = wait_state(f, id, JOB_RUNNING);
    job_rec_clear(&r);
    assert_int_equal(job_pool_cancel(p, id), 1);
    r = wait_state(f, id, JOB_CANCELED);
    job_rec_clear(&r);
    assert_int_equal(job_pool_cancel(p, id), 0);
    job_pool_stop(p, 1000);
}

static void test_cancel_flag_in_the_store_reaches_the_worker(void **state)
{
    fixture *f = *state;
    job_pool *p = start(f, 1, 60000);
    char id[27];
    submit(f, p, "spin", id);
    job_rec r = wait_state(f, id, JOB_RUNNING);
    job_rec_clear(&r);
    /* As another node would: only the store knows. */
    assert_int_equal(store_cancel(f->s, id, NULL, NULL), 0);
    r = wait_state(f, id, JOB_CANCELED);
    job_rec_clear(&r);
    job_pool_stop(p, 1000);
}

static void test_time_limit_fails_the_job(void **state)
{
    fixture *f = *state;
    job_pool *p = start(f, 1, 1000);
    char id[27];
    submit(f, p, "spin", id);
    job_rec r = wait_state(f, id, JOB_FAILED);
    assert_non_null(strstr(r.error, "time limit of 1 s exceeded"));
    assert_true(r.finished_ms - r.started_ms >= 1000);
    job_rec_clear(&r);
    job_pool_stop(p, 1000);
}

static void test_shutdown_requeues_unfinished_jobs(void **state)
{
    fixture *f = *state;
    job_pool *p = start(f, 1, 60000);
    char a[27], b[27];
    submit(f, p, "spin", a);
    job_rec r = wait_state(f, a, JOB_RUNNING);
    job_rec_clear(&r);
    submit(f, p, "ok", b);
    job_pool_stop(p, 100);
    assert_int_equal(store_get(f->s, a, &r, NULL), 0);
    assert_int_equal(r.state, JOB_QUEUED);
    job_rec_clear(&r);
    assert_int_equal(store_get(f->s, b, &r, NULL), 0);
    assert_int_equal(r.state, JOB_QUEUED);
    job_rec_clear(&r);
}

static void test_jobs_queued_before_start_are_found_without_a_wake(void **state)
{
    fixture *f = *state;
    char ids[20][27];
    for (int i = 0; i < 20; i++)
        submit(f, NULL, "ok", ids[i]);
    job_pool *p = start(f, 3, 10000);
    for (int i = 0; i < 20; i++) {
        job_rec r = wait_state(f, ids[i], JOB_SUCCEEDED);
        job_rec_clear(&r);
    }
    job_pool_stop(p, 1000);
}

/* A job alone gets the pool's parallel_for; one that runs beside another
 * runs its loops on its own thread, every index still run once. */
static void test_the_pool_serves_a_job_running_alone(void **state)
{
    fixture *f = *state;
    job_pool *p = start(f, 2, 60000);
    atomic_store(&pool_loops, 0);
    char a[27], b[27], c[27];
    submit(f, p, "par", a);
    job_rec r = wait_state(f, a, JOB_SUCCEEDED);
    assert_string_equal(r.summary, "{\"ran\":4}");
    job_rec_clear(&r);
    assert_int_equal(atomic_load(&pool_loops), 1);
    submit(f, p, "spin", b);
    r = wait_state(f, b, JOB_RUNNING);
    job_rec_clear(&r);
    submit(f, p, "par", c);
    r = wait_state(f, c, JOB_SUCCEEDED);
    assert_string_equal(r.summary, "{\"ran\":4}");
    job_rec_clear(&r);
    assert_int_equal(atomic_load(&pool_loops), 1);
    assert_int_equal(job_pool_cancel(p, b), 1);
    r = wait_state(f, b, JOB_CANCELED);
    job_rec_clear(&r);
    job_pool_stop(p, 1000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
#define T(name) cmocka_unit_test_setup_teardown(name, setup, teardown)
        T(test_jobs_run_and_outcomes_are_recorded),
        T(test_primed_inputs_replace_the_stored_ones),
        T(test_local_cancel_stops_a_running_job),
        T(test_cancel_flag_in_the_store_reaches_the_worker),
        T(test_time_limit_fails_the_job),
        T(test_shutdown_requeues_unfinished_jobs),
        T(test_jobs_queued_before_start_are_found_without_a_wake),
        T(test_the_pool_serves_a_job_running_alone),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
