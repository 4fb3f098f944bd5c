/* store_sqlite.c — the embedded job store: one SQLite database,
 * STATE_DIR/facetd.db, in WAL mode (readers never wait for the writer).
 *
 * Invariants:
 * - Each thread uses its own connection (made on first use, kept in a
 *   pthread key, all closed by store_close), so reads run in parallel.
 * - Writes are serialised in-process by one mutex and run as BEGIN
 *   IMMEDIATE transactions, so our own threads never meet SQLITE_BUSY and
 *   its backoff sleeps; busy_timeout covers other processes (the sqlite3
 *   shell).
 * - store_put returns only once its commit is on disk (the caller
 *   answers 202 after it), by group commit: the transaction commits with
 *   synchronous=NORMAL under the write lock, then, outside it, one thread
 *   fdatasyncs the WAL for every commit made so far while later ones
 *   wait for it (wait_durable) — what synchronous=FULL does at each
 *   commit, but concurrent submissions share one sync and the write lock
 *   is not held during it. store_cancel commits with synchronous=FULL;
 *   other changes commit with synchronous=NORMAL, which survives a crash
 *   of the process, and after a power loss at worst re-runs a job
 *   (store_recover).
 * - A lock file (flock) keeps a second facetd off the same directory: the
 *   store assumes it is the only node, so its recover can requeue every
 *   running job.
 * - Schema versioned by PRAGMA user_version and migrated step by step at
 *   open; a newer version than this code knows is refused.
 * - Blobs live in their own table keyed by seq*4 + kind, so the jobs
 *   table stays small and dense for listing and claiming. A succeeded job
 *   without a model blob (seq*4+1) has its input (seq*4) as result. */
#include "store.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <sqlite3.h>

#define SCHEMA_VERSION 1

enum stmt_id {
    S_GET, S_COUNT_QUEUED, S_FIND_IDEM, S_INSERT_JOB, S_INSERT_BLOB,
    S_CLAIM, S_PROGRESS, S_FINISH, S_REQUEUE, S_CANCEL, S_SEQ_STATE,
    S_DELETE_JOB, S_DELETE_BLOBS, S_GET_BLOB, S_LIST, S_RECOVER,
    S_EXPIRED, S_OLDEST_DONE, S_TOTAL_BYTES, S_COUNTS, S_PING,
    S_BEGIN, S_COMMIT, S_ROLLBACK, S_SYNC_FULL, S_SYNC_NORMAL,
    NSTMT
};

#define COLS "id,state,priority,source,label,pipeline,error,summary," \
             "progress,created_ms,started_ms,finished_ms,version," \
             "cancel_requested,attempts,input_bytes,result_bytes," \
             "result_hash,idem_hash"

static const char *const sql[NSTMT] = {
    [S_GET] = "SELECT " COLS " FROM jobs WHERE id=?1",
    [S_COUNT_QUEUED] = "SELECT count(*) FROM jobs WHERE state=0",
    [S_FIND_IDEM] = "SELECT " COLS " FROM jobs WHERE idem_key=?1",
    [S_INSERT_JOB] =
        "INSERT INTO jobs(id,state,priority,source,label,pipeline,idem_key,"
        "idem_hash,created_ms,input_bytes) VALUES(?1,0,?2,?3,?4,?5,?6,?7,?8,?9)",
    [S_INSERT_BLOB] = "INSERT OR REPLACE INTO blobs(key,data) VALUES(?1,?2)",
    [S_CLAIM] =
        "UPDATE jobs SET state=1, started_ms=?1, attempts=attempts+1, "
        "progress=0, version=version+1 WHERE seq=(SELECT seq FROM jobs "
        "WHERE state=0 ORDER BY priority DESC, seq LIMIT 1) RETURNING " COLS,
    [S_PROGRESS] =
        "UPDATE jobs SET progress=?2, version=version+1 WHERE id=?1 AND "
        "state=1 RETURNING cancel_requested",
    [S_FINISH] =
        "UPDATE jobs SET state=?2, finished_ms=?3, error=?4, summary=?5, "
        "result_bytes=?6, result_hash=?7, version=version+1, progress="
        "CASE WHEN ?2=2 THEN 1.0 ELSE progress END WHERE id=?1 AND state=1 "
        "RETURNING seq",
    [S_REQUEUE] =
        "UPDATE jobs SET state=0, progress=0, version=version+1 "
        "WHERE id=?1 AND state=1",
    [S_CANCEL] =
        "UPDATE jobs SET cancel_requested=1, version=version+1, "
        "state=CASE WHEN state=0 THEN 4 ELSE state END, "
        "finished_ms=CASE WHEN state=0 THEN ?2 ELSE finished_ms END, "
        "error=CASE WHEN state=0 THEN 'canceled before it started' "
        "ELSE error END WHERE id=?1 AND state IN (0,1)",
    [S_SEQ_STATE] = "SELECT seq,state FROM jobs WHERE id=?1",
    [S_DELETE_JOB] = "DELETE FROM jobs WHERE seq=?1",
    [S_DELETE_BLOBS] = "DELETE FROM blobs WHERE key BETWEEN ?1*4 AND ?1*4+3",
    /* a succeeded job without a model blob has its input as result */
    [S_GET_BLOB] =
        "SELECT b.data FROM jobs j JOIN blobs b ON b.key IN (j.seq*4+?2, "
        "CASE WHEN ?2=1 AND j.state=2 THEN j.seq*4 END) WHERE j.id=?1 "
        "ORDER BY b.key DESC LIMIT 1",
    [S_LIST] =
        "SELECT " COLS " FROM jobs WHERE (?1<0 OR state=?1) AND "
        "(?2 IS NULL OR source=?2) AND (?3 IS NULL OR id<?3) "
        "ORDER BY id DESC LIMIT ?4",
    [S_RECOVER] =
        "UPDATE jobs SET state=0, progress=0, version=version+1 WHERE state=1",
    [S_EXPIRED] =
        "SELECT seq FROM jobs WHERE state>=2 AND finished_ms<?1 "
        "ORDER BY finished_ms LIMIT 500",
    [S_OLDEST_DONE] =
        "SELECT seq, input_bytes+result_bytes FROM jobs WHERE state>=2 "
        "ORDER BY finished_ms LIMIT 200",
    [S_TOTAL_BYTES] =
        "SELECT coalesce(sum(input_bytes+result_bytes),0) FROM jobs",
    [S_COUNTS] = "SELECT state, count(*) FROM jobs GROUP BY state",
    [S_PING] = "SELECT 1",
    [S_BEGIN] = "BEGIN IMMEDIATE",
    [S_COMMIT] = "COMMIT",
    [S_ROLLBACK] = "ROLLBACK",
    [S_SYNC_FULL] = "PRAGMA synchronous=FULL",
    [S_SYNC_NORMAL] = "PRAGMA synchronous=NORMAL",
};

/* Schema steps: migrations[v] takes a database from user_version v to
 * v+1 (migrate() sets auto_vacuum before the first one). */
static const char *const migrations[SCHEMA_VERSION] = {
    "CREATE TABLE jobs("
    " seq INTEGER PRIMARY KEY,"
    " id TEXT NOT NULL UNIQUE,"
    " state INTEGER NOT NULL,"
    " priority INTEGER NOT NULL,"
    " source TEXT NOT NULL,"
    " label TEXT NOT NULL DEFAULT '',"
    " pipeline TEXT NOT NULL,"
    " idem_key TEXT UNIQUE,"
    " idem_hash INTEGER NOT NULL DEFAULT 0,"
    " progress REAL NOT NULL DEFAULT 0,"
    " version INTEGER NOT NULL DEFAULT 1,"
    " cancel_requested INTEGER NOT NULL DEFAULT 0,"
    " attempts INTEGER NOT NULL DEFAULT 0,"
    " created_ms INTEGER NOT NULL,"
    " started_ms INTEGER NOT NULL DEFAULT 0,"
    " finished_ms INTEGER NOT NULL DEFAULT 0,"
    " error TEXT, summary TEXT,"
    " input_bytes INTEGER NOT NULL DEFAULT 0,"
    " result_bytes INTEGER NOT NULL DEFAULT 0,"
    " result_hash INTEGER NOT NULL DEFAULT 0);"
    "CREATE INDEX jobs_queue ON jobs(priority DESC, seq) WHERE state=0;"
    "CREATE INDEX jobs_state ON jobs(state, id);"
    "CREATE INDEX jobs_done ON jobs(finished_ms) WHERE state>=2;"
    "CREATE TABLE blobs(key INTEGER PRIMARY KEY, data BLOB NOT NULL);",
};

typedef struct conn {
    sqlite3 *db;
    sqlite3_stmt *st[NSTMT];
    bool sync_full;
    struct conn *next;
} conn;

typedef struct sq_store {
    store base;
    char path[PATH_MAX];
    int lock_fd;
    pthread_key_t key;
    pthread_mutex_t conns_lock; /* guards conns */
    conn *conns;
    pthread_mutex_t write_lock; /* one write transaction at a time */
    /* group commit (wait_durable) */
    char wal[PATH_MAX + 8];     /* the WAL file, path + "-wal" */
    atomic_uint_fast64_t committed; /* durable commits made so far */
    pthread_mutex_t sync_lock;  /* guards the fields below */
    pthread_cond_t sync_done;
    uint64_t synced;            /* commits known to be on disk */
    bool syncing;               /* a thread is syncing the WAL */
    bool dir_synced;            /* the directory entry of the WAL is */
} sq_store;

static int db_err(sqlite3 *db, geo_err *err, const char *what)
{
    int code = sqlite3_extended_errcode(db);
    int r = (code & 0xff) == SQLITE_NOMEM ? -ENOMEM
            : (code & 0xff) == SQLITE_FULL ? -ENOSPC : -EIO;
    return geo_err_set(err, r, "store: %s: %s", what, sqlite3_errmsg(db));
}

static void conn_free(conn *c)
{
    for (int i = 0; i < NSTMT; i++)
        sqlite3_finalize(c->st[i]);
    sqlite3_close_v2(c->db);
    free(c);
}

static int exec_all(sqlite3 *db, const char *text, geo_err *err)
{
    char *msg = NULL;
    if (sqlite3_exec(db, text, NULL, NULL, &msg) != SQLITE_OK) {
        geo_err_set(err, -EIO, "store: %s", msg ? msg : "exec failed");
        sqlite3_free(msg);
        return -EIO;
    }
    return 0;
}

static conn *conn_open(sq_store *s, geo_err *err)
{
    conn *c = calloc(1, sizeof *c);
    if (!c) {
        geo_err_set(err, -ENOMEM, "store: out of memory");
        return NULL;
    }
    int rc = sqlite3_open_v2(s->path, &c->db,
                             SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE |
                                 SQLITE_OPEN_NOMUTEX,
                             NULL);
    if (rc != SQLITE_OK) {
        if (c->db)
            db_err(c->db, err, s->path);
        else
            geo_err_set(err, -ENOMEM, "store: out of memory");
        conn_free(c);
        return NULL;
    }
    sqlite3_busy_timeout(c->db, 5000);
    if (exec_all(c->db,
                 "PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL;"
                 "PRAGMA foreign_keys=OFF; PRAGMA cache_size=-4096;"
                 "PRAGMA temp_store=MEMORY;",
                 err) < 0) {
        conn_free(c);
        return NULL;
    }
    return c;
}

/* The calling thread's connection, opened on first use; NULL with err. */
static conn *my_conn(sq_store *s, geo_err *err)
{
    conn *c = pthread_getspecific(s->key);
    if (c)
        return c;
    c = conn_open(s, err);
    if (!c)
        return NULL;
    pthread_mutex_lock(&s->conns_lock);
    c->next = s->conns;
    s->conns = c;
    pthread_mutex_unlock(&s->conns_lock);
    pthread_setspecific(s->key, c);
    return c;
}

/* A reset prepared statement of c, prepared on first use. */
static sqlite3_stmt *stmt(conn *c, enum stmt_id id, geo_err *err)
{
    if (!c->st[id]) {
        if (sqlite3_prepare_v3(c->db, sql[id], -1, SQLITE_PREPARE_PERSISTENT,
                               &c->st[id], NULL) != SQLITE_OK) {
            db_err(c->db, err, "prepare");
            return NULL;
        }
    }
    return c->st[id];
}

static void done(sqlite3_stmt *st)
{
    sqlite3_reset(st);
    sqlite3_clear_bindings(st);
}

/* Runs a statement that returns no rows. */
static int run(conn *c, enum stmt_id id, geo_err *err)
{
    sqlite3_stmt *st = stmt(c, id, err);
    if (!st)
        return -EIO;
    int rc = sqlite3_step(st);
    done(st);
    return rc == SQLITE_DONE || rc == SQLITE_ROW ? 0 : db_err(c->db, err, sql[id]);
}

static int set_sync(conn *c, bool full, geo_err *err)
{
    if (c->sync_full == full)
        return 0;
    int r = run(c, full ? S_SYNC_FULL : S_SYNC_NORMAL, err);
    if (r == 0)
        c->sync_full = full;
    return r;
}

/* Starts a write transaction: takes the write mutex (released by
 * end_write whatever happens). */
static int begin_write(sq_store *s, conn *c, bool durable, geo_err *err)
{
    pthread_mutex_lock(&s->write_lock);
    int r = set_sync(c, durable, err);
    if (r == 0)
        r = run(c, S_BEGIN, err);
    if (r < 0)
        pthread_mutex_unlock(&s->write_lock);
    return r;
}

/* Commits when r == 0, else rolls back; returns r or the commit error. */
static int end_write(sq_store *s, conn *c, int r, geo_err *err)
{
    if (r == 0) {
        r = run(c, S_COMMIT, err);
        if (r < 0)
            run(c, S_ROLLBACK, NULL);
    } else {
        run(c, S_ROLLBACK, NULL);
    }
    pthread_mutex_unlock(&s->write_lock);
    return r;
}

static char *dup_col(sqlite3_stmt *st, int i, int *oom)
{
    const unsigned char *t = sqlite3_column_text(st, i);
    if (!t)
        return NULL;
    char *d = strdup((const char *)t);
    if (!d)
        *oom = 1;
    return d;
}

static void copy_col(sqlite3_stmt *st, int i, char *buf, size_t size)
{
    const unsigned char *t = sqlite3_column_text(st, i);
    snprintf(buf, size, "%s", t ? (const char *)t : "");
}

/* Reads a row of COLS into *r. 0 or -ENOMEM (r cleared). */
static int read_row(sqlite3_stmt *st, job_rec *r)
{
    int oom = 0;
    memset(r, 0, sizeof *r);
    copy_col(st, 0, r->id, sizeof r->id);
    r->state = (job_state)sqlite3_column_int(st, 1);
    r->priority = (job_priority)sqlite3_column_int(st, 2);
    copy_col(st, 3, r->source, sizeof r->source);
    copy_col(st, 4, r->label, sizeof r->label);
    r->pipeline = dup_col(st, 5, &oom);
    r->error = dup_col(st, 6, &oom);
    r->summary = dup_col(st, 7, &oom);
    r->progress = sqlite3_column_double(st, 8);
    r->created_ms = sqlite3_column_int64(st, 9);
    r->started_ms = sqlite3_column_int64(st, 10);
    r->finished_ms = sqlite3_column_int64(st, 11);
    r->version = sqlite3_column_int64(st, 12);
    r->cancel_requested = sqlite3_column_int(st, 13) != 0;
    r->attempts = sqlite3_column_int(st, 14);
    r->input_bytes = (uint64_t)sqlite3_column_int64(st, 15);
    r->result_bytes = (uint64_t)sqlite3_column_int64(st, 16);
    r->result_hash = (uint64_t)sqlite3_column_int64(st, 17);
    r->idem_hash = (uint64_t)sqlite3_column_int64(st, 18);
    if (oom) {
        job_rec_clear(r);
        return -ENOMEM;
    }
    return 0;
}

/* Steps a statement expected to return at most one row of COLS. */
static int fetch_one(conn *c, sqlite3_stmt *st, job_rec *ret, geo_err *err)
{
    int rc = sqlite3_step(st), r;
    if (rc == SQLITE_ROW) {
        r = read_row(st, ret);
        if (r < 0)
            geo_err_set(err, r, "store: out of memory");
    } else if (rc == SQLITE_DONE) {
        r = -ENOENT;
    } else {
        r = db_err(c->db, err, "read");
    }
    done(st);
    return r;
}

static int get_locked(conn *c, const char *id, job_rec *ret, geo_err *err)
{
    sqlite3_stmt *st = stmt(c, S_GET, err);
    if (!st)
        return -EIO;
    sqlite3_bind_text(st, 1, id, -1, SQLITE_STATIC);
    int r = fetch_one(c, st, ret, err);
    if (r == -ENOENT)
        geo_err_set(err, r, "no job '%s'", id);
    return r;
}

#define S(base) ((sq_store *)(base))
#define CONN_OR_FAIL(s, c, err)            \
    conn *c = my_conn(S(s), err);          \
    if (!c)                                \
        return -EIO

static int insert_blob(conn *c, int64_t seq, store_blob kind,
                       const void *data, size_t len, geo_err *err)
{
    sqlite3_stmt *st = stmt(c, S_INSERT_BLOB, err);
    if (!st)
        return -EIO;
    sqlite3_bind_int64(st, 1, seq * 4 + kind);
    sqlite3_bind_blob64(st, 2, data ? data : "", len, SQLITE_STATIC);
    int rc = sqlite3_step(st);
    done(st);
    return rc == SQLITE_DONE ? 0 : db_err(c->db, err, "insert blob");
}

/* Puts the WAL (and, the first time, the directory holding it) on disk. */
static int sync_wal(sq_store *s, geo_err *err)
{
    int fd = open(s->wal, O_RDONLY | O_CLOEXEC);
    if (fd < 0 || fdatasync(fd) < 0) {
        int e = errno;
        if (fd >= 0)
            close(fd);
        return geo_err_set(err, -EIO, "store: syncing %s: %s", s->wal,
                           strerror(e));
    }
    close(fd);
    if (!s->dir_synced) {
        char dir[PATH_MAX];
        snprintf(dir, sizeof dir, "%s", s->path);
        char *slash = strrchr(dir, '/');
        if (slash)
            *slash = '\0';
        int dfd = open(slash ? dir : ".", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
        if (dfd >= 0) {
            if (fsync(dfd) == 0)
                s->dir_synced = true;
            close(dfd);
        }
    }
    return 0;
}

/* Returns once commit number seq (counted after its COMMIT returned) is
 * on disk: a thread that finds no sync running syncs the WAL for every
 * commit counted so far; the others wait for it, and one of them syncs
 * again if their commit came too late for it. */
static int wait_durable(sq_store *s, uint64_t seq, geo_err *err)
{
    int r = 0;
    pthread_mutex_lock(&s->sync_lock);
    while (s->synced < seq && r == 0) {
        if (s->syncing) {
            pthread_cond_wait(&s->sync_done, &s->sync_lock);
            continue;
        }
        s->syncing = true;
        uint64_t target = atomic_load(&s->committed);
        pthread_mutex_unlock(&s->sync_lock);
        r = sync_wal(s, err);
        pthread_mutex_lock(&s->sync_lock);
        s->syncing = false;
        if (r == 0 && target > s->synced)
            s->synced = target;
        pthread_cond_broadcast(&s->sync_done);
    }
    pthread_mutex_unlock(&s->sync_lock);
    return r;
}

static int sq_put(store *s, const store_new_job *j, unsigned max_queued,
                  job_rec *ret_existing, geo_err *err)
{
    CONN_OR_FAIL(s, c, err);
    int r = begin_write(S(s), c, false, err);
    if (r < 0)
        return r;
    sqlite3_stmt *st;
    if (j->idem_key) {
        if (!(st = stmt(c, S_FIND_IDEM, err))) {
            r = -EIO;
            goto out;
        }
        sqlite3_bind_text(st, 1, j->idem_key, -1, SQLITE_STATIC);
        job_rec old;
        r = fetch_one(c, st, &old, err);
        if (r == 0) {
            if (ret_existing)
                *ret_existing = old;
            else
                job_rec_clear(&old);
            r = -EEXIST;
            goto out;
        }
        if (r != -ENOENT)
            goto out;
        r = 0;
    }
    if (!(st = stmt(c, S_COUNT_QUEUED, err))) {
        r = -EIO;
        goto out;
    }
    int64_t queued = sqlite3_step(st) == SQLITE_ROW ? sqlite3_column_int64(st, 0)
                                                    : -1;
    done(st);
    if (queued < 0) {
        r = db_err(c->db, err, "count queued");
        goto out;
    }
    if ((uint64_t)queued >= max_queued) {
        r = geo_err_set(err, -EAGAIN, "the queue is full (%lld jobs)",
                        (long long)queued);
        goto out;
    }
    if (!(st = stmt(c, S_INSERT_JOB, err))) {
        r = -EIO;
        goto out;
    }
    sqlite3_bind_text(st, 1, j->id, -1, SQLITE_STATIC);
    sqlite3_bind_int(st, 2, j->priority);
    sqlite3_bind_text(st, 3, j->source, -1, SQLITE_STATIC);
    sqlite3_bind_text(st, 4, j->label ? j->label : "", -1, SQLITE_STATIC);
    sqlite3_bind_text(st, 5, j->pipeline, -1, SQLITE_STATIC);
    if (j->idem_key)
        sqlite3_bind_text(st, 6, j->idem_key, -1, SQLITE_STATIC);
    sqlite3_bind_int64(st, 7, (int64_t)j->idem_hash);
    sqlite3_bind_int64(st, 8, j->created_ms);
    sqlite3_bind_int64(st, 9, (int64_t)j->input_len);
    int rc = sqlite3_step(st);
    done(st);
    if (rc != SQLITE_DONE) {
        r = db_err(c->db, err, "insert job");
        goto out;
    }
    r = insert_blob(c, sqlite3_last_insert_rowid(c->db), STORE_BLOB_INPUT,
                    j->input, j->input_len, err);
out:
    r = end_write(S(s), c, r, err);
    if (r == 0)
        r = wait_durable(S(s), atomic_fetch_add(&S(s)->committed, 1) + 1,
                         err);
    return r;
}

static int sq_claim(store *s, job_rec *ret, geo_err *err)
{
    CONN_OR_FAIL(s, c, err);
    int r = begin_write(S(s), c, false, err);
    if (r < 0)
        return r;
    sqlite3_stmt *st = stmt(c, S_CLAIM, err);
    job_rec rec;
    if (!st) {
        r = -EIO;
    } else {
        sqlite3_bind_int64(st, 1, job_now_ms());
        r = fetch_one(c, st, &rec, err);
    }
    r = end_write(S(s), c, r, err);
    if (r == 0)
        *ret = rec;
    return r;
}

/* After an UPDATE … WHERE state=… touched no row: -ENOENT or -EBUSY. */
static int why_not(conn *c, const char *id, geo_err *err)
{
    sqlite3_stmt *st = stmt(c, S_SEQ_STATE, err);
    if (!st)
        return -EIO;
    sqlite3_bind_text(st, 1, id, -1, SQLITE_STATIC);
    int rc = sqlite3_step(st);
    int state = rc == SQLITE_ROW ? sqlite3_column_int(st, 1) : -1;
    done(st);
    if (rc == SQLITE_ROW)
        return geo_err_set(err, -EBUSY, "job %s is %s", id,
                           job_state_name((job_state)state));
    if (rc == SQLITE_DONE)
        return geo_err_set(err, -ENOENT, "no job '%s'", id);
    return db_err(c->db, err, "read");
}

static int sq_progress(store *s, const char *id, double progress,
                       int *ret_cancel, geo_err *err)
{
    CONN_OR_FAIL(s, c, err);
    int r = begin_write(S(s), c, false, err);
    if (r < 0)
        return r;
    sqlite3_stmt *st = stmt(c, S_PROGRESS, err);
    int cancel = 0;
    if (!st) {
        r = -EIO;
    } else {
        sqlite3_bind_text(st, 1, id, -1, SQLITE_STATIC);
        sqlite3_bind_double(st, 2, progress);
        int rc = sqlite3_step(st);
        if (rc == SQLITE_ROW)
            cancel = sqlite3_column_int(st, 0);
        done(st);
        if (rc == SQLITE_DONE)
            r = why_not(c, id, err);
        else if (rc != SQLITE_ROW)
            r = db_err(c->db, err, "progress");
    }
    r = end_write(S(s), c, r, err);
    if (r == 0 && ret_cancel)
        *ret_cancel = cancel;
    return r;
}

static int sq_finish(store *s, const char *id, job_state state,
                     const char *error, const char *summary,
                     const void *model, size_t model_len, const void *stats,
                     size_t stats_len, geo_err *err)
{
    CONN_OR_FAIL(s, c, err);
    int r = begin_write(S(s), c, false, err);
    if (r < 0)
        return r;
    sqlite3_stmt *st = stmt(c, S_FINISH, err);
    if (!st) {
        r = -EIO;
        goto out;
    }
    sqlite3_bind_text(st, 1, id, -1, SQLITE_STATIC);
    sqlite3_bind_int(st, 2, state);
    sqlite3_bind_int64(st, 3, job_now_ms());
    if (error)
        sqlite3_bind_text(st, 4, error, -1, SQLITE_STATIC);
    if (summary)
        sqlite3_bind_text(st, 5, summary, -1, SQLITE_STATIC);
    sqlite3_bind_int64(st, 6, (int64_t)((model ? model_len : 0) +
                                        (stats ? stats_len : 0)));
    /* a result that is the input is named by its job: a job's results
     * never change, so the id serves the ETags as well as a digest */
    uint64_t hash = model ? job_digest64(model, model_len)
                    : state == JOB_SUCCEEDED ? job_digest64(id, strlen(id))
                                             : 0;
    sqlite3_bind_int64(st, 7, (int64_t)hash);
    int rc = sqlite3_step(st);
    int64_t seq = rc == SQLITE_ROW ? sqlite3_column_int64(st, 0) : 0;
    done(st);
    if (rc == SQLITE_DONE) {
        r = why_not(c, id, err);
        goto out;
    }
    if (rc != SQLITE_ROW) {
        r = db_err(c->db, err, "finish");
        goto out;
    }
    if (model)
        r = insert_blob(c, seq, STORE_BLOB_MODEL, model, model_len, err);
    if (r == 0 && stats)
        r = insert_blob(c, seq, STORE_BLOB_STATS, stats, stats_len, err);
out:
    return end_write(S(s), c, r, err);
}

/* Runs an UPDATE bound to ?1 = id (and ?2 = now), mapping "no row" to
 * -ENOENT/-EBUSY. */
static int update_by_id(store *s, enum stmt_id which, const char *id,
                        bool durable, geo_err *err)
{
    CONN_OR_FAIL(s, c, err);
    int r = begin_write(S(s), c, durable, err);
    if (r < 0)
        return r;
    sqlite3_stmt *st = stmt(c, which, err);
    if (!st) {
        r = -EIO;
    } else {
        sqlite3_bind_text(st, 1, id, -1, SQLITE_STATIC);
        if (sqlite3_bind_parameter_count(st) >= 2)
            sqlite3_bind_int64(st, 2, job_now_ms());
        int rc = sqlite3_step(st);
        done(st);
        if (rc != SQLITE_DONE)
            r = db_err(c->db, err, "update");
        else if (sqlite3_changes(c->db) == 0)
            r = why_not(c, id, err);
    }
    return end_write(S(s), c, r, err);
}

static int sq_requeue(store *s, const char *id, geo_err *err)
{
    return update_by_id(s, S_REQUEUE, id, false, err);
}

static int sq_cancel(store *s, const char *id, job_rec *ret, geo_err *err)
{
    int r = update_by_id(s, S_CANCEL, id, true, err);
    if (r < 0 && r != -EBUSY)
        return r;
    if (ret) {
        geo_err e2;
        CONN_OR_FAIL(s, c, err);
        int r2 = get_locked(c, id, ret, &e2);
        if (r2 < 0) {
            if (err)
                *err = e2;
            return r2;
        }
    }
    return r;
}

static int delete_seq(conn *c, int64_t seq, geo_err *err)
{
    sqlite3_stmt *a = stmt(c, S_DELETE_BLOBS, err);
    sqlite3_stmt *b = stmt(c, S_DELETE_JOB, err);
    if (!a || !b)
        return -EIO;
    sqlite3_bind_int64(a, 1, seq);
    int rc = sqlite3_step(a);
    done(a);
    if (rc != SQLITE_DONE)
        return db_err(c->db, err, "delete blobs");
    sqlite3_bind_int64(b, 1, seq);
    rc = sqlite3_step(b);
    done(b);
    return rc == SQLITE_DONE ? 0 : db_err(c->db, err, "delete job");
}

static int sq_remove(store *s, const char *id, geo_err *err)
{
    CONN_OR_FAIL(s, c, err);
    int r = begin_write(S(s), c, true, err);
    if (r < 0)
        return r;
    sqlite3_stmt *st = stmt(c, S_SEQ_STATE, err);
    if (!st) {
        r = -EIO;
        goto out;
    }
    sqlite3_bind_text(st, 1, id, -1, SQLITE_STATIC);
    int rc = sqlite3_step(st);
    int64_t seq = rc == SQLITE_ROW ? sqlite3_column_int64(st, 0) : 0;
    int state = rc == SQLITE_ROW ? sqlite3_column_int(st, 1) : -1;
    done(st);
    if (rc == SQLITE_DONE)
        r = geo_err_set(err, -ENOENT, "no job '%s'", id);
    else if (rc != SQLITE_ROW)
        r = db_err(c->db, err, "read");
    else if (!job_state_terminal((job_state)state))
        r = geo_err_set(err, -EBUSY, "job %s is %s", id,
                        job_state_name((job_state)state));
    else
        r = delete_seq(c, seq, err);
out:
    return end_write(S(s), c, r, err);
}

static int sq_get(store *s, const char *id, job_rec *ret, geo_err *err)
{
    CONN_OR_FAIL(s, c, err);
    job_rec rec;
    int r = get_locked(c, id, &rec, err);
    if (r == 0)
        *ret = rec;
    return r;
}

static int sq_get_blob(store *s, const char *id, store_blob which, void **ret,
                       size_t *ret_len, geo_err *err)
{
    CONN_OR_FAIL(s, c, err);
    sqlite3_stmt *st = stmt(c, S_GET_BLOB, err);
    if (!st)
        return -EIO;
    sqlite3_bind_text(st, 1, id, -1, SQLITE_STATIC);
    sqlite3_bind_int(st, 2, which);
    int rc = sqlite3_step(st), r = 0;
    if (rc == SQLITE_ROW) {
        size_t n = (size_t)sqlite3_column_bytes(st, 0);
        const void *d = sqlite3_column_blob(st, 0);
        char *buf = malloc(n + 1);
        if (!buf) {
            r = geo_err_set(err, -ENOMEM, "store: out of memory");
        } else {
            if (n)
                memcpy(buf, d, n);
            buf[n] = '\0';
            *ret = buf;
            *ret_len = n;
        }
    } else if (rc == SQLITE_DONE) {
        r = geo_err_set(err, -ENOENT, "job '%s' has no such data", id);
    } else {
        r = db_err(c->db, err, "read blob");
    }
    done(st);
    return r;
}

static int sq_list(store *s, const store_filter *f, job_rec **ret,
                   size_t *ret_n, geo_err *err)
{
    CONN_OR_FAIL(s, c, err);
    sqlite3_stmt *st = stmt(c, S_LIST, err);
    if (!st)
        return -EIO;
    sqlite3_bind_int(st, 1, f->state);
    if (f->source)
        sqlite3_bind_text(st, 2, f->source, -1, SQLITE_STATIC);
    if (f->after)
        sqlite3_bind_text(st, 3, f->after, -1, SQLITE_STATIC);
    sqlite3_bind_int(st, 4, (int)f->limit);
    job_rec *v = calloc(f->limit, sizeof *v);
    size_t n = 0;
    int r = v ? 0 : -ENOMEM, rc;
    while (r == 0 && (rc = sqlite3_step(st)) == SQLITE_ROW && n < f->limit) {
        r = read_row(st, &v[n]);
        if (r == 0)
            n++;
    }
    if (r == 0 && rc != SQLITE_DONE && rc != SQLITE_ROW)
        r = db_err(c->db, err, "list");
    done(st);
    if (r < 0) {
        for (size_t i = 0; i < n; i++)
            job_rec_clear(&v[i]);
        free(v);
        if (r == -ENOMEM)
            geo_err_set(err, r, "store: out of memory");
        return r;
    }
    *ret = v;
    *ret_n = n;
    return 0;
}

static int sq_recover(store *s, unsigned *ret_n, geo_err *err)
{
    CONN_OR_FAIL(s, c, err);
    int r = begin_write(S(s), c, true, err);
    if (r < 0)
        return r;
    r = run(c, S_RECOVER, err);
    int n = sqlite3_changes(c->db);
    r = end_write(S(s), c, r, err);
    if (r == 0 && ret_n)
        *ret_n = (unsigned)n;
    return r;
}

/* Deletes up to one batch of rows selected by `which` (bound to arg when
 * which is S_EXPIRED); for S_OLDEST_DONE stops once *bytes ≤ max. */
static int delete_batch(sq_store *s, conn *c, enum stmt_id which, int64_t arg,
                        uint64_t *bytes, uint64_t max, unsigned *deleted,
                        geo_err *err)
{
    int64_t seqs[500];
    uint64_t sizes[500];
    int n = 0;
    int r = begin_write(s, c, false, err);
    if (r < 0)
        return r;
    sqlite3_stmt *st = stmt(c, which, err);
    if (!st) {
        r = -EIO;
        goto out;
    }
    if (which == S_EXPIRED)
        sqlite3_bind_int64(st, 1, arg);
    int rc;
    while (n < 500 && (rc = sqlite3_step(st)) == SQLITE_ROW) {
        seqs[n] = sqlite3_column_int64(st, 0);
        sizes[n] = which == S_OLDEST_DONE
                       ? (uint64_t)sqlite3_column_int64(st, 1) : 0;
        n++;
    }
    done(st);
    for (int i = 0; i < n && r == 0; i++) {
        if (which == S_OLDEST_DONE && *bytes <= max) {
            n = i;
            break;
        }
        r = delete_seq(c, seqs[i], err);
        if (r == 0) {
            (*deleted)++;
            *bytes -= sizes[i] < *bytes ? sizes[i] : *bytes;
        }
    }
out:
    r = end_write(s, c, r, err);
    return r < 0 ? r : n;
}

static int sq_retention(store *s, int64_t older_than_ms, uint64_t max_bytes,
                        unsigned *ret_deleted, geo_err *err)
{
    CONN_OR_FAIL(s, c, err);
    unsigned deleted = 0;
    uint64_t bytes = 0;
    int n;
    do
        n = delete_batch(S(s), c, S_EXPIRED, older_than_ms, &bytes, 0,
                         &deleted, err);
    while (n == 500);
    if (n < 0)
        return n;
    sqlite3_stmt *st = stmt(c, S_TOTAL_BYTES, err);
    if (!st)
        return -EIO;
    int rc = sqlite3_step(st);
    bytes = rc == SQLITE_ROW ? (uint64_t)sqlite3_column_int64(st, 0) : 0;
    done(st);
    if (rc != SQLITE_ROW)
        return db_err(c->db, err, "sum sizes");
    while (bytes > max_bytes) {
        n = delete_batch(S(s), c, S_OLDEST_DONE, 0, &bytes, max_bytes,
                         &deleted, err);
        if (n < 0)
            return n;
        if (n == 0)
            break; /* only queued/running jobs left: never deleted */
    }
    if (deleted) {
        pthread_mutex_lock(&S(s)->write_lock);
        int r = exec_all(c->db, "PRAGMA incremental_vacuum", err);
        pthread_mutex_unlock(&S(s)->write_lock);
        if (r < 0)
            return r;
    }
    if (ret_deleted)
        *ret_deleted = deleted;
    return 0;
}

static uint64_t file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (uint64_t)st.st_size : 0;
}

static int sq_counts(store *s, store_counts *ret, geo_err *err)
{
    CONN_OR_FAIL(s, c, err);
    store_counts out;
    memset(&out, 0, sizeof out);
    sqlite3_stmt *st = stmt(c, S_COUNTS, err);
    if (!st)
        return -EIO;
    int rc;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
        int state = sqlite3_column_int(st, 0);
        if (state >= 0 && state < JOB_NSTATES)
            out.by_state[state] = (uint64_t)sqlite3_column_int64(st, 1);
    }
    done(st);
    if (rc != SQLITE_DONE)
        return db_err(c->db, err, "count");
    if (!(st = stmt(c, S_TOTAL_BYTES, err)))
        return -EIO;
    rc = sqlite3_step(st);
    out.kept_bytes = rc == SQLITE_ROW ? (uint64_t)sqlite3_column_int64(st, 0) : 0;
    done(st);
    if (rc != SQLITE_ROW)
        return db_err(c->db, err, "sum sizes");
    char wal[PATH_MAX + 8];
    snprintf(wal, sizeof wal, "%s-wal", S(s)->path);
    out.file_bytes = file_size(S(s)->path) + file_size(wal);
    *ret = out;
    return 0;
}

static int sq_ping(store *s, geo_err *err)
{
    CONN_OR_FAIL(s, c, err);
    return run(c, S_PING, err);
}

static void sq_close(store *base)
{
    sq_store *s = S(base);
    conn *c = s->conns;
    while (c) {
        conn *next = c->next;
        conn_free(c);
        c = next;
    }
    pthread_key_delete(s->key);
    pthread_mutex_destroy(&s->conns_lock);
    pthread_mutex_destroy(&s->write_lock);
    pthread_mutex_destroy(&s->sync_lock);
    pthread_cond_destroy(&s->sync_done);
    if (s->lock_fd >= 0)
        close(s->lock_fd);
    free(s);
}

static const store_ops sqlite_ops = {
    .name = "sqlite",
    .put = sq_put,
    .claim = sq_claim,
    .progress = sq_progress,
    .finish = sq_finish,
    .requeue = sq_requeue,
    .cancel = sq_cancel,
    .remove = sq_remove,
    .get = sq_get,
    .get_blob = sq_get_blob,
    .list = sq_list,
    .recover = sq_recover,
    .retention = sq_retention,
    .counts = sq_counts,
    .ping = sq_ping,
    .close = sq_close,
};

static int migrate(conn *c, const char *path, geo_err *err)
{
    sqlite3_stmt *st;
    if (sqlite3_prepare_v2(c->db, "PRAGMA user_version", -1, &st, NULL) !=
        SQLITE_OK)
        return db_err(c->db, err, "user_version");
    int rc = sqlite3_step(st);
    int version = rc == SQLITE_ROW ? sqlite3_column_int(st, 0) : -1;
    sqlite3_finalize(st);
    if (version < 0)
        return db_err(c->db, err, "user_version");
    if (version > SCHEMA_VERSION)
        return geo_err_set(err, -EINVAL,
                           "%s: schema version %d is newer than this facetd "
                           "knows (%d)", path, version, SCHEMA_VERSION);
    for (int v = version; v < SCHEMA_VERSION; v++) {
        char bump[64];
        snprintf(bump, sizeof bump, "PRAGMA user_version=%d", v + 1);
        /* auto_vacuum only takes effect outside a transaction, before
         * the first table; the rest of the step is atomic. */
        const char *text = migrations[v];
        if (v == 0 && exec_all(c->db, "PRAGMA auto_vacuum=INCREMENTAL", err) < 0)
            return -EIO;
        if (exec_all(c->db, "BEGIN IMMEDIATE", err) < 0)
            return -EIO;
        if (exec_all(c->db, text, err) < 0 || exec_all(c->db, bump, err) < 0 ||
            exec_all(c->db, "COMMIT", err) < 0) {
            exec_all(c->db, "ROLLBACK", NULL);
            geo_err_prefix(err, path);
            return -EIO;
        }
    }
    return 0;
}

store *store_sqlite_open(const char *dir, geo_err *err)
{
    sq_store *s = calloc(1, sizeof *s);
    if (!s) {
        geo_err_set(err, -ENOMEM, "store: out of memory");
        return NULL;
    }
    s->base.ops = &sqlite_ops;
    s->lock_fd = -1;
    if ((size_t)snprintf(s->path, sizeof s->path, "%s/facetd.db", dir) >=
        sizeof s->path) {
        geo_err_set(err, -EINVAL, "%s: path too long", dir);
        free(s);
        return NULL;
    }
    if (mkdir(dir, 0750) < 0 && errno != EEXIST) {
        geo_err_set(err, -errno, "%s: %s", dir, strerror(errno));
        free(s);
        return NULL;
    }
    char lock[PATH_MAX + 8];
    snprintf(lock, sizeof lock, "%s/facetd.lock", dir);
    s->lock_fd = open(lock, O_RDWR | O_CREAT | O_CLOEXEC, 0640);
    if (s->lock_fd < 0) {
        geo_err_set(err, -errno, "%s: %s", lock, strerror(errno));
        free(s);
        return NULL;
    }
    if (flock(s->lock_fd, LOCK_EX | LOCK_NB) < 0) {
        geo_err_set(err, -EBUSY, "%s: another facetd uses this state "
                    "directory", dir);
        close(s->lock_fd);
        free(s);
        return NULL;
    }
    if (pthread_key_create(&s->key, NULL) != 0) {
        geo_err_set(err, -ENOMEM, "store: no thread key");
        close(s->lock_fd);
        free(s);
        return NULL;
    }
    pthread_mutex_init(&s->conns_lock, NULL);
    pthread_mutex_init(&s->write_lock, NULL);
    pthread_mutex_init(&s->sync_lock, NULL);
    pthread_cond_init(&s->sync_done, NULL);
    atomic_init(&s->committed, 0);
    snprintf(s->wal, sizeof s->wal, "%s-wal", s->path);
    conn *c = my_conn(s, err);
    if (!c || migrate(c, s->path, err) < 0) {
        sq_close(&s->base);
        return NULL;
    }
    return &s->base;
}
