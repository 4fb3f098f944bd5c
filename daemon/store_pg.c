/* store_pg.c — the job store shared by a cluster of facetd nodes: one
 * PostgreSQL database reached through libpq (store.h, docs/cluster.md).
 *
 * Invariants:
 * - Each thread uses its own connection (made on first use, kept in a
 *   pthread key, all closed by store_close); a broken one is dropped and
 *   made again by the next call. After a failed connect, calls fail fast
 *   with -ENOTCONN for a second instead of each waiting for a timeout.
 * - A claim gives the job a fresh claim token (a sequence) and a lease
 *   (lease_until, database clock). The node keeps its tokens in `claims`;
 *   progress, finish and requeue match on the token, so a node whose lease
 *   expired and whose job another node claimed again is refused (fencing):
 *   every job gets exactly one result.
 * - One thread per node (events_main) on its own connection: LISTENs on
 *   facetd_jobs, renews this node's leases every lease/3, and every second
 *   re-queues running jobs whose lease expired (their node died). A
 *   trigger NOTIFYs every change of a job's version, so every node's
 *   waiters and workers hear of every job ("ID KIND SOURCE").
 * - Schema versioned in facetd_schema, migrated at open under an advisory
 *   lock, so nodes starting together do not race; a newer version than
 *   this code knows is refused.
 * - Retention runs once for the cluster: a row lock on facetd_meta lets
 *   one node at a time in, and a run within the last RETENTION_GAP_MS
 *   makes the others skip theirs.
 * - Durability as store.h and the SQLite store: store_put, cancel and
 *   remove commit with synchronous_commit=on (on the server's disk when
 *   they return); every other change with it off, which survives facetd's
 *   crash at once and the server's after a fraction of a second — a
 *   change lost then re-runs a job at worst.
 * - Ids are stored with the C collation, so ORDER BY id is creation order
 *   as with SQLite. */
#include "store.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <libpq-fe.h>

#include "log.h"

#define SCHEMA_VERSION 1
#define MIGRATE_LOCK "7310553227840540001" /* advisory lock key */
#define RETENTION_GAP_MS 30000
#define SWEEP_EVERY_MS 1000
#define RETRY_CONNECT_MS 1000

#define COLS "id,state,priority,source,label,pipeline,error,summary," \
             "progress,created_ms,started_ms,finished_ms,version," \
             "cancel_requested,attempts,input_bytes,result_bytes," \
             "result_hash,idem_hash,node"
enum { NCOLS = 20 };

static const char *const migrations[SCHEMA_VERSION] = {
    "CREATE SEQUENCE facetd_claim_token;"
    "CREATE TABLE facetd_jobs("
    " seq bigserial PRIMARY KEY,"
    " id text COLLATE \"C\" NOT NULL UNIQUE,"
    " state smallint NOT NULL,"
    " priority smallint NOT NULL,"
    " source text NOT NULL,"
    " label text NOT NULL DEFAULT '',"
    " pipeline text NOT NULL,"
    " idem_key text UNIQUE,"
    " idem_hash bigint NOT NULL DEFAULT 0,"
    " progress double precision NOT NULL DEFAULT 0,"
    " version bigint NOT NULL DEFAULT 1,"
    " cancel_requested smallint NOT NULL DEFAULT 0,"
    " attempts integer NOT NULL DEFAULT 0,"
    " created_ms bigint NOT NULL,"
    " started_ms bigint NOT NULL DEFAULT 0,"
    " finished_ms bigint NOT NULL DEFAULT 0,"
    " error text, summary text,"
    " input_bytes bigint NOT NULL DEFAULT 0,"
    " result_bytes bigint NOT NULL DEFAULT 0,"
    " result_hash bigint NOT NULL DEFAULT 0,"
    " node text NOT NULL DEFAULT '',"
    " claim_token bigint NOT NULL DEFAULT 0,"
    " lease_until timestamptz);"
    "CREATE INDEX facetd_jobs_queue ON facetd_jobs(priority DESC, seq)"
    " WHERE state=0;"
    "CREATE INDEX facetd_jobs_leases ON facetd_jobs(lease_until)"
    " WHERE state=1;"
    "CREATE INDEX facetd_jobs_state ON facetd_jobs(state, id);"
    "CREATE INDEX facetd_jobs_done ON facetd_jobs(finished_ms)"
    " WHERE state>=2;"
    /* blobs apart, so the jobs table stays small for claims and lists;
     * models barely compress, so they are stored as they are */
    "CREATE TABLE facetd_blobs("
    " job_seq bigint NOT NULL REFERENCES facetd_jobs(seq) ON DELETE CASCADE,"
    " kind smallint NOT NULL,"
    " data bytea NOT NULL,"
    " PRIMARY KEY(job_seq, kind));"
    "ALTER TABLE facetd_blobs ALTER COLUMN data SET STORAGE EXTERNAL;"
    "CREATE TABLE facetd_meta(key text PRIMARY KEY, value bigint NOT NULL);"
    "INSERT INTO facetd_meta VALUES('retention_ms', 0);"
    /* q: now queued, p: progress only, e: ended, c: other change,
     * d: deleted; a lease renewal (no version change) says nothing */
    "CREATE FUNCTION facetd_notify() RETURNS trigger LANGUAGE plpgsql AS $$"
    "BEGIN"
    " IF TG_OP = 'DELETE' THEN"
    "  PERFORM pg_notify('facetd_jobs', OLD.id || ' d ' || OLD.source);"
    " ELSIF TG_OP = 'INSERT' OR NEW.version <> OLD.version THEN"
    "  PERFORM pg_notify('facetd_jobs', NEW.id || CASE"
    "   WHEN NEW.state = 0 THEN ' q '"
    "   WHEN NEW.state >= 2 THEN ' e '"
    "   WHEN NEW.state = OLD.state AND"
    "        NEW.cancel_requested = OLD.cancel_requested THEN ' p '"
    "   ELSE ' c ' END || NEW.source);"
    " END IF;"
    " RETURN NULL;"
    "END $$;"
    "CREATE TRIGGER facetd_jobs_notify AFTER INSERT OR UPDATE OR DELETE"
    " ON facetd_jobs FOR EACH ROW EXECUTE FUNCTION facetd_notify();",
};

/* Running jobs re-queued (or canceled, when a cancel was asked) whose
 * lease expired, or, with $1 not empty, that node $1 ran before it
 * restarted. */
static const char sql_expire[] =
    "WITH x AS (SELECT seq, node FROM facetd_jobs WHERE state=1 AND "
    "(node=$1 OR lease_until<clock_timestamp()) FOR UPDATE SKIP LOCKED) "
    "UPDATE facetd_jobs j SET "
    "state=CASE WHEN j.cancel_requested=1 THEN 4 ELSE 0 END, "
    "finished_ms=CASE WHEN j.cancel_requested=1 THEN $2::bigint ELSE 0 END, "
    "error=CASE WHEN j.cancel_requested=1 THEN 'canceled while running' "
    "ELSE j.error END, "
    "node=CASE WHEN j.cancel_requested=1 THEN j.node ELSE '' END, "
    "progress=0, version=j.version+1, claim_token=0, lease_until=NULL "
    "FROM x WHERE j.seq=x.seq RETURNING j.id, x.node";

typedef struct claim {
    char id[JOB_ID_LEN + 1];
    int64_t token;
    bool renew;        /* still running here: keep the lease */
    int64_t forget_at; /* monotonic ms; when !renew, dropped after it */
} claim;

typedef struct pconn {
    PGconn *pg;
    struct pconn *next;
} pconn;

typedef struct pg_store {
    store base;
    char url[1024];
    char passfile[512];
    char node[JOB_NODE_MAX];
    char appname[JOB_NODE_MAX + 8];
    uint64_t lease_ms;
    pthread_key_t key;
    pthread_mutex_t conns_lock; /* guards conns, down_msg */
    pconn *conns;
    char down_msg[sizeof(geo_err)]; /* why the last connect failed */
    atomic_int_fast64_t down_until; /* monotonic ms: fail fast before it */
    pthread_mutex_t claims_lock; /* guards claims */
    claim *claims;
    size_t nclaims, cap;
    pthread_mutex_t ev_lock;    /* guards ev; held while calling it */
    store_events ev;
    pthread_t thread;
    bool thread_started;
    atomic_bool stopping;
    int wake[2];                /* pipe: wakes the events thread to stop */
} pg_store;

#define P(base) ((pg_store *)(base))

static void quiet(void *arg, const char *msg)
{
    (void)arg;
    (void)msg; /* "relation exists, skipping" and the like */
}

/* libpq's message without its trailing newline. */
static const char *trimmed(const char *msg, char *buf, size_t size)
{
    snprintf(buf, size, "%s", msg && *msg ? msg : "unknown error");
    size_t n = strlen(buf);
    while (n && (buf[n - 1] == '\n' || buf[n - 1] == ' '))
        buf[--n] = '\0';
    return buf;
}

static PGconn *pg_connect(pg_store *s, geo_err *err)
{
    const char *kw[9], *val[9];
    int n = 0;
    kw[n] = "connect_timeout", val[n++] = "5";
    kw[n] = "keepalives_idle", val[n++] = "10";
    kw[n] = "keepalives_interval", val[n++] = "5";
    kw[n] = "application_name", val[n++] = s->appname;
    /* as the SQLite store's synchronous=NORMAL: a commit outlives facetd
     * at once and the server's crash within ~0.6 s; store_put, cancel and
     * remove ask for the flush (durable()) */
    kw[n] = "options", val[n++] = "-c synchronous_commit=off";
    kw[n] = "dbname", val[n++] = s->url; /* the URL overrides the above */
    if (s->passfile[0])
        kw[n] = "passfile", val[n++] = s->passfile;
    kw[n] = NULL, val[n] = NULL;
    PGconn *pg = PQconnectdbParams(kw, val, 1);
    if (!pg) {
        geo_err_set(err, -ENOMEM, "store: out of memory");
        return NULL;
    }
    if (PQstatus(pg) != CONNECTION_OK) {
        char buf[256];
        geo_err_set(err, -ENOTCONN, "store: the database is unreachable: %s",
                    trimmed(PQerrorMessage(pg), buf, sizeof buf));
        PQfinish(pg);
        return NULL;
    }
    PQsetNoticeProcessor(pg, quiet, NULL);
    return pg;
}

/* The calling thread's connection, made or made again when needed. */
static PGconn *conn(pg_store *s, geo_err *err)
{
    pconn *pc = pthread_getspecific(s->key);
    if (!pc) {
        pc = calloc(1, sizeof *pc);
        if (!pc) {
            geo_err_set(err, -ENOMEM, "store: out of memory");
            return NULL;
        }
        pthread_mutex_lock(&s->conns_lock);
        pc->next = s->conns;
        s->conns = pc;
        pthread_mutex_unlock(&s->conns_lock);
        pthread_setspecific(s->key, pc);
    }
    if (pc->pg && PQstatus(pc->pg) == CONNECTION_OK)
        return pc->pg;
    if (pc->pg) {
        PQfinish(pc->pg);
        pc->pg = NULL;
    }
    if (job_mono_ms() < atomic_load(&s->down_until)) {
        pthread_mutex_lock(&s->conns_lock);
        geo_err_set(err, -ENOTCONN, "%s", s->down_msg);
        pthread_mutex_unlock(&s->conns_lock);
        return NULL;
    }
    geo_err e;
    pc->pg = pg_connect(s, &e);
    if (pc->pg)
        atomic_store(&s->down_until, 0); /* back: nobody fails fast */
    if (!pc->pg) {
        pthread_mutex_lock(&s->conns_lock);
        snprintf(s->down_msg, sizeof s->down_msg, "%s", e.msg);
        pthread_mutex_unlock(&s->conns_lock);
        atomic_store(&s->down_until, job_mono_ms() + RETRY_CONNECT_MS);
        if (err)
            *err = e;
    }
    return pc->pg;
}

/* A failed command's errno: -ENOTCONN when the connection or the server
 * went away (class 08, shutdown 57P0x), -ENOMEM, else -EIO. */
static int pg_fail(PGconn *pg, const PGresult *res, const char *what,
                   geo_err *err)
{
    const char *state = res ? PQresultErrorField(res, PG_DIAG_SQLSTATE) : NULL;
    bool gone = PQstatus(pg) != CONNECTION_OK ||
                (state && (strncmp(state, "08", 2) == 0 ||
                           strncmp(state, "57P", 3) == 0));
    int code = gone ? -ENOTCONN
               : state && strcmp(state, "53200") == 0 ? -ENOMEM
                                                      : -EIO;
    char buf[256];
    const char *msg = res && *PQresultErrorMessage(res)
                          ? PQresultErrorMessage(res) : PQerrorMessage(pg);
    return geo_err_set(err, code, "store: %s%s: %s",
                       gone ? "the database is unreachable: " : "", what,
                       trimmed(msg, buf, sizeof buf));
}

/* Runs sql with n parameters (text unless len/fmt say binary); the result
 * when it succeeded, else NULL with *ret and err set. */
/* A connection the server dropped (it restarted) still looks fine until
 * it is used: a read or a BEGIN outside a transaction, which changed
 * nothing if it failed, is tried once more on a new connection. Writes
 * are not: one may have been done before the connection broke. */
static bool retry_on_new(PGconn *pg, const char *sql,
                         PGTransactionStatusType was)
{
    if (was != PQTRANS_IDLE || PQstatus(pg) == CONNECTION_OK ||
        (strncmp(sql, "SELECT", 6) != 0 && strncmp(sql, "BEGIN", 5) != 0))
        return false;
    PQreset(pg);
    return PQstatus(pg) == CONNECTION_OK;
}

static PGresult *exec(PGconn *pg, const char *what, const char *sql, int n,
                      const char *const *v, const int *len, const int *fmt,
                      int binary, int *ret, geo_err *err)
{
    PGTransactionStatusType was = PQtransactionStatus(pg);
    PGresult *res = PQexecParams(pg, sql, n, NULL, v, len, fmt, binary);
    ExecStatusType st = PQresultStatus(res);
    if (!(res && (st == PGRES_COMMAND_OK || st == PGRES_TUPLES_OK)) &&
        retry_on_new(pg, sql, was)) {
        PQclear(res);
        res = PQexecParams(pg, sql, n, NULL, v, len, fmt, binary);
        st = PQresultStatus(res);
    }
    if (res && (st == PGRES_COMMAND_OK || st == PGRES_TUPLES_OK)) {
        *ret = 0;
        return res;
    }
    *ret = pg_fail(pg, res, what, err);
    PQclear(res);
    return NULL;
}

/* A command whose result is not needed: 0 or the error. */
static int run(PGconn *pg, const char *what, const char *sql, int n,
               const char *const *v, geo_err *err)
{
    int r;
    PQclear(exec(pg, what, sql, n, v, NULL, NULL, 0, &r, err));
    return r;
}

/* Commits when r == 0, else rolls back; returns r or the commit error. */
static int end_tx(PGconn *pg, int r, geo_err *err)
{
    if (r == 0)
        return run(pg, "commit", "COMMIT", 0, NULL, err);
    run(pg, "rollback", "ROLLBACK", 0, NULL, NULL);
    return r;
}

/* Starts a transaction whose commit waits for the server's disk. */
static int begin_durable(PGconn *pg, geo_err *err)
{
    static const char sql[] = "BEGIN; SET LOCAL synchronous_commit=on";
    PGTransactionStatusType was = PQtransactionStatus(pg);
    PGresult *res = PQexec(pg, sql);
    if (PQresultStatus(res) != PGRES_COMMAND_OK && retry_on_new(pg, sql, was)) {
        PQclear(res);
        res = PQexec(pg, sql);
    }
    int r = PQresultStatus(res) == PGRES_COMMAND_OK ? 0
            : pg_fail(pg, res, "begin", err);
    PQclear(res);
    if (r < 0 && PQtransactionStatus(pg) == PQTRANS_INERROR)
        run(pg, "rollback", "ROLLBACK", 0, NULL, NULL);
    return r;
}

static int64_t col_i64(const PGresult *res, int row, int col)
{
    return strtoll(PQgetvalue(res, row, col), NULL, 10);
}

static char *col_dup(const PGresult *res, int row, int col, int *oom)
{
    if (PQgetisnull(res, row, col))
        return NULL;
    char *d = strdup(PQgetvalue(res, row, col));
    if (!d)
        *oom = 1;
    return d;
}

/* Reads a row of COLS into *r. 0 or -ENOMEM (r cleared). */
static int read_row(const PGresult *res, int row, job_rec *r)
{
    int oom = 0;
    memset(r, 0, sizeof *r);
    snprintf(r->id, sizeof r->id, "%s", PQgetvalue(res, row, 0));
    r->state = (job_state)col_i64(res, row, 1);
    r->priority = (job_priority)col_i64(res, row, 2);
    snprintf(r->source, sizeof r->source, "%s", PQgetvalue(res, row, 3));
    snprintf(r->label, sizeof r->label, "%s", PQgetvalue(res, row, 4));
    r->pipeline = col_dup(res, row, 5, &oom);
    r->error = col_dup(res, row, 6, &oom);
    r->summary = col_dup(res, row, 7, &oom);
    r->progress = strtod(PQgetvalue(res, row, 8), NULL);
    r->created_ms = col_i64(res, row, 9);
    r->started_ms = col_i64(res, row, 10);
    r->finished_ms = col_i64(res, row, 11);
    r->version = col_i64(res, row, 12);
    r->cancel_requested = col_i64(res, row, 13) != 0;
    r->attempts = (int)col_i64(res, row, 14);
    r->input_bytes = (uint64_t)col_i64(res, row, 15);
    r->result_bytes = (uint64_t)col_i64(res, row, 16);
    r->result_hash = (uint64_t)col_i64(res, row, 17);
    r->idem_hash = (uint64_t)col_i64(res, row, 18);
    snprintf(r->node, sizeof r->node, "%s", PQgetvalue(res, row, 19));
    if (oom) {
        job_rec_clear(r);
        return -ENOMEM;
    }
    return 0;
}

/* The first row of res into *ret: 0, -ENOENT (no row), -ENOMEM. */
static int one_row(const PGresult *res, job_rec *ret, geo_err *err)
{
    if (PQntuples(res) < 1)
        return -ENOENT;
    if (read_row(res, 0, ret) < 0)
        return geo_err_set(err, -ENOMEM, "store: out of memory");
    return 0;
}

#define CONN_OR_FAIL(s, pg, err)          \
    PGconn *pg = conn(P(s), err);         \
    if (!pg)                              \
        return -ENOTCONN

/* ---- claims held by this node ------------------------------------- */

static int claim_add(pg_store *s, const char *id, int64_t token)
{
    pthread_mutex_lock(&s->claims_lock);
    int r = 0;
    if (s->nclaims == s->cap) {
        size_t cap = s->cap ? s->cap * 2 : 16;
        claim *v = realloc(s->claims, cap * sizeof *v);
        if (!v)
            r = -ENOMEM;
        else
            s->claims = v, s->cap = cap;
    }
    if (r == 0) {
        claim *c = &s->claims[s->nclaims++];
        snprintf(c->id, sizeof c->id, "%s", id);
        c->token = token;
        c->renew = true;
        c->forget_at = 0;
    }
    pthread_mutex_unlock(&s->claims_lock);
    return r;
}

/* This node's token for id, 0 if it holds none. */
static int64_t claim_token(pg_store *s, const char *id)
{
    int64_t t = 0;
    pthread_mutex_lock(&s->claims_lock);
    for (size_t i = 0; i < s->nclaims; i++)
        if (strcmp(s->claims[i].id, id) == 0)
            t = s->claims[i].token;
    pthread_mutex_unlock(&s->claims_lock);
    return t;
}

/* The run of id ended here (done) or its outcome could not be written:
 * then the lease is left to lapse, and the token kept for a retry until
 * then. */
static void claim_release(pg_store *s, const char *id, bool done)
{
    pthread_mutex_lock(&s->claims_lock);
    for (size_t i = 0; i < s->nclaims; i++) {
        if (strcmp(s->claims[i].id, id) != 0)
            continue;
        if (done) {
            s->claims[i] = s->claims[--s->nclaims];
        } else {
            s->claims[i].renew = false;
            s->claims[i].forget_at = job_mono_ms() + (int64_t)s->lease_ms;
        }
        break;
    }
    pthread_mutex_unlock(&s->claims_lock);
}

/* After an UPDATE matching id and this node's token changed nothing:
 * -ENOENT, -ESTALE (with stale set, when another node claimed it again
 * after this node's lease expired) or -EBUSY (not running). */
static int why_not(PGconn *pg, const char *id, int64_t token, bool stale,
                   geo_err *err)
{
    const char *v[] = {id};
    int r;
    PGresult *res = exec(pg, "read", "SELECT state, claim_token FROM "
                         "facetd_jobs WHERE id=$1", 1, v, NULL, NULL, 0, &r,
                         err);
    if (!res)
        return r;
    if (PQntuples(res) < 1)
        r = geo_err_set(err, -ENOENT, "no job '%s'", id);
    else {
        job_state st = (job_state)col_i64(res, 0, 0);
        int64_t now_token = col_i64(res, 0, 1);
        bool lost = st == JOB_QUEUED ||
                    (st == JOB_RUNNING && now_token != token);
        if (lost && token)
            r = geo_err_set(err, stale ? -ESTALE : -EBUSY,
                            "job %s: this node's lease on it expired; %s", id,
                            st == JOB_QUEUED ? "it was queued again"
                                             : "another node runs it now");
        else
            r = geo_err_set(err, -EBUSY, "job %s is %s", id,
                            job_state_name(st));
    }
    PQclear(res);
    return r;
}

/* The end of a write under the claim token (finish, requeue): r, or why
 * the row was not written (res NULL: exec failed, r and err say why).
 * Refused for good (-EBUSY, -ENOENT) or written: the claim is forgotten;
 * a failed write keeps the token until the lease would lapse. */
static int claimed_write_end(pg_store *ps, PGconn *pg, PGresult *res,
                             const char *id, int64_t token, int r,
                             geo_err *err)
{
    if (res) {
        if (PQntuples(res) < 1)
            r = why_not(pg, id, token, false, err);
        PQclear(res);
    }
    claim_release(ps, id, r == 0 || r == -EBUSY || r == -ENOENT);
    return r;
}

/* ---- the operations ------------------------------------------------ */

/* Reads the job an idempotency key names: -EEXIST with *ret_existing,
 * -ENOENT, or the error. */
static int find_key(PGconn *pg, const char *key, job_rec *ret_existing,
                    geo_err *err)
{
    const char *v[] = {key};
    int r;
    PGresult *res = exec(pg, "find key", "SELECT " COLS " FROM facetd_jobs "
                         "WHERE idem_key=$1", 1, v, NULL, NULL, 0, &r, err);
    if (!res)
        return r;
    job_rec old;
    r = one_row(res, &old, err);
    PQclear(res);
    if (r < 0)
        return r;
    if (ret_existing)
        *ret_existing = old;
    else
        job_rec_clear(&old);
    return -EEXIST;
}

static int pg_put(store *s, const store_new_job *j, unsigned max_queued,
                  job_rec *ret_existing, geo_err *err)
{
    CONN_OR_FAIL(s, pg, err);
    int r = begin_durable(pg, err);
    if (r < 0)
        return r;
    char prio[8], hash[24], created[24], bytes[24], max[16];
    snprintf(prio, sizeof prio, "%d", (int)j->priority);
    snprintf(hash, sizeof hash, "%lld", (long long)(int64_t)j->idem_hash);
    snprintf(created, sizeof created, "%lld", (long long)j->created_ms);
    snprintf(bytes, sizeof bytes, "%zu", j->input_len);
    snprintf(max, sizeof max, "%u", max_queued);
    const char *v[] = {j->id, prio, j->source, j->label ? j->label : "",
                       j->pipeline, j->idem_key, hash, created, bytes, max,
                       j->input ? (const char *)j->input : ""};
    int len[11] = {[10] = (int)j->input_len};
    int fmt[11] = {[10] = 1};
    /* one round trip: the job and its input, unless the queue is full or
     * the key was used (ON CONFLICT also waits for another node's insert
     * of the same key to commit, then inserts nothing) */
    PGresult *res = exec(
        pg, "insert job",
        "WITH q AS (SELECT count(*) AS n FROM facetd_jobs WHERE state=0), "
        "j AS (INSERT INTO facetd_jobs(id,state,priority,source,label,"
        "pipeline,idem_key,idem_hash,created_ms,input_bytes) "
        "SELECT $1,0,$2,$3,$4,$5,$6,$7,$8,$9 FROM q WHERE q.n<$10::bigint "
        "ON CONFLICT (idem_key) DO NOTHING RETURNING seq), "
        "b AS (INSERT INTO facetd_blobs SELECT seq,0,$11::bytea FROM j "
        "RETURNING job_seq) "
        "SELECT (SELECT n FROM q), (SELECT job_seq FROM b)",
        11, v, len, fmt, 0, &r, err);
    if (!res)
        goto out;
    int64_t queued = col_i64(res, 0, 0);
    bool inserted = !PQgetisnull(res, 0, 1);
    PQclear(res);
    if (inserted)
        goto out;
    /* a used key answers with its job even when the queue is full */
    r = j->idem_key ? find_key(pg, j->idem_key, ret_existing, err) : -ENOENT;
    if (r == -ENOENT)
        r = (uint64_t)queued >= max_queued
                ? geo_err_set(err, -EAGAIN, "the queue is full (%lld jobs)",
                              (long long)queued)
                : geo_err_set(err, -EIO, "store: the job was not inserted");
out:
    return end_tx(pg, r, err);
}

static int pg_claim(store *s, job_rec *ret, geo_err *err)
{
    CONN_OR_FAIL(s, pg, err);
    char now[24], lease[24];
    snprintf(now, sizeof now, "%lld", (long long)job_now_ms());
    snprintf(lease, sizeof lease, "%llu", (unsigned long long)P(s)->lease_ms);
    const char *v[] = {now, P(s)->node, lease};
    int r;
    PGresult *res = exec(
        pg, "claim",
        "UPDATE facetd_jobs SET state=1, started_ms=$1, attempts=attempts+1, "
        "progress=0, version=version+1, node=$2, "
        "claim_token=nextval('facetd_claim_token'), "
        "lease_until=clock_timestamp()+$3::bigint*interval '1 millisecond' "
        "WHERE seq=(SELECT seq FROM facetd_jobs WHERE state=0 "
        "ORDER BY priority DESC, seq LIMIT 1 FOR UPDATE SKIP LOCKED) "
        "RETURNING " COLS ", claim_token",
        3, v, NULL, NULL, 0, &r, err);
    if (!res)
        return r;
    job_rec rec;
    r = one_row(res, &rec, err);
    int64_t token = r == 0 ? col_i64(res, 0, NCOLS) : 0;
    PQclear(res);
    if (r < 0)
        return r;
    if (claim_add(P(s), rec.id, token) < 0) {
        /* untracked, its lease would lapse mid-run: give it back */
        char tok[24];
        snprintf(tok, sizeof tok, "%lld", (long long)token);
        const char *q[] = {rec.id, tok};
        run(pg, "requeue", "UPDATE facetd_jobs SET state=0, node='', "
            "claim_token=0, lease_until=NULL, version=version+1 WHERE id=$1 "
            "AND claim_token=$2", 2, q, NULL);
        job_rec_clear(&rec);
        return geo_err_set(err, -ENOMEM, "store: out of memory");
    }
    *ret = rec;
    return 0;
}

static int pg_progress(store *s, const char *id, double progress,
                       int *ret_cancel, geo_err *err)
{
    CONN_OR_FAIL(s, pg, err);
    int64_t token = claim_token(P(s), id);
    char prog[32], tok[24];
    snprintf(prog, sizeof prog, "%.17g", progress);
    snprintf(tok, sizeof tok, "%lld", (long long)token);
    const char *v[] = {id, prog, tok};
    int r;
    PGresult *res = exec(pg, "progress", "UPDATE facetd_jobs SET progress=$2, "
                         "version=version+1 WHERE id=$1 AND state=1 AND "
                         "claim_token=$3 RETURNING cancel_requested", 3, v,
                         NULL, NULL, 0, &r, err);
    if (!res)
        return r;
    int n = PQntuples(res);
    int cancel = n ? (int)col_i64(res, 0, 0) : 0;
    PQclear(res);
    if (!n)
        return why_not(pg, id, token, true, err);
    if (ret_cancel)
        *ret_cancel = cancel;
    return 0;
}

static int pg_finish(store *s, const char *id, job_state state,
                     const char *error, const char *summary,
                     const void *model, size_t model_len, const void *stats,
                     size_t stats_len, geo_err *err)
{
    CONN_OR_FAIL(s, pg, err);
    int64_t token = claim_token(P(s), id);
    /* as store_sqlite.c: a result that is the input is named by its id */
    uint64_t hash = model ? job_digest64(model, model_len)
                    : state == JOB_SUCCEEDED ? job_digest64(id, strlen(id))
                                             : 0;
    char st[8], now[24], bytes[24], h[24], tok[24];
    snprintf(st, sizeof st, "%d", (int)state);
    snprintf(now, sizeof now, "%lld", (long long)job_now_ms());
    snprintf(bytes, sizeof bytes, "%zu",
             (model ? model_len : 0) + (stats ? stats_len : 0));
    snprintf(h, sizeof h, "%lld", (long long)(int64_t)hash);
    snprintf(tok, sizeof tok, "%lld", (long long)token);
    const char *v[] = {id, st, now, error, summary, bytes, h, tok, model,
                       stats};
    int len[10] = {[8] = (int)model_len, [9] = (int)stats_len};
    int fmt[10] = {[8] = 1, [9] = 1};
    int r;
    /* one statement, so one transaction: the state and the blobs, or
     * nothing when the token is not the job's any more */
    PGresult *res = exec(
        pg, "finish",
        "WITH u AS (UPDATE facetd_jobs SET state=$2, finished_ms=$3, "
        "error=$4, summary=$5, result_bytes=$6, result_hash=$7, "
        "version=version+1, "
        "progress=CASE WHEN $2::smallint=2 THEN 1.0 ELSE progress END, "
        "lease_until=NULL WHERE id=$1 AND state=1 AND claim_token=$8 "
        "RETURNING seq), "
        "m AS (INSERT INTO facetd_blobs SELECT seq,1,$9::bytea FROM u "
        "WHERE $9::bytea IS NOT NULL), "
        "t AS (INSERT INTO facetd_blobs SELECT seq,2,$10::bytea FROM u "
        "WHERE $10::bytea IS NOT NULL) "
        "SELECT seq FROM u",
        10, v, len, fmt, 0, &r, err);
    return claimed_write_end(P(s), pg, res, id, token, r, err);
}

static int pg_requeue(store *s, const char *id, geo_err *err)
{
    CONN_OR_FAIL(s, pg, err);
    int64_t token = claim_token(P(s), id);
    char tok[24];
    snprintf(tok, sizeof tok, "%lld", (long long)token);
    const char *v[] = {id, tok};
    int r;
    PGresult *res = exec(pg, "requeue", "UPDATE facetd_jobs SET state=0, "
                         "progress=0, version=version+1, node='', "
                         "claim_token=0, lease_until=NULL WHERE id=$1 AND "
                         "state=1 AND claim_token=$2 RETURNING seq", 2, v,
                         NULL, NULL, 0, &r, err);
    return claimed_write_end(P(s), pg, res, id, token, r, err);
}

static int get_row(PGconn *pg, const char *id, job_rec *ret, geo_err *err)
{
    const char *v[] = {id};
    int r;
    PGresult *res = exec(pg, "read", "SELECT " COLS " FROM facetd_jobs WHERE "
                         "id=$1", 1, v, NULL, NULL, 0, &r, err);
    if (!res)
        return r;
    r = one_row(res, ret, err);
    PQclear(res);
    if (r == -ENOENT)
        geo_err_set(err, r, "no job '%s'", id);
    return r;
}

static int pg_cancel(store *s, const char *id, job_rec *ret, geo_err *err)
{
    CONN_OR_FAIL(s, pg, err);
    char now[24];
    snprintf(now, sizeof now, "%lld", (long long)job_now_ms());
    const char *v[] = {id, now};
    int r = begin_durable(pg, err);
    if (r < 0)
        return r;
    PGresult *res = exec(
        pg, "cancel",
        "UPDATE facetd_jobs SET cancel_requested=1, version=version+1, "
        "state=CASE WHEN state=0 THEN 4 ELSE state END, "
        "finished_ms=CASE WHEN state=0 THEN $2::bigint ELSE finished_ms END, "
        "error=CASE WHEN state=0 THEN 'canceled before it started' "
        "ELSE error END WHERE id=$1 AND state IN (0,1) RETURNING " COLS,
        2, v, NULL, NULL, 0, &r, err);
    job_rec rec;
    if (res) {
        r = one_row(res, &rec, err);
        PQclear(res);
    }
    int rc = end_tx(pg, r == -ENOENT ? 0 : r, err);
    if (rc < 0) {
        if (r == 0)
            job_rec_clear(&rec);
        return rc;
    }
    if (r == 0) {
        if (ret)
            *ret = rec;
        else
            job_rec_clear(&rec);
        return 0;
    }
    if (r != -ENOENT)
        return r;
    r = get_row(pg, id, &rec, err);
    if (r < 0)
        return r;
    r = geo_err_set(err, -EBUSY, "job %s is %s", id, job_state_name(rec.state));
    if (ret)
        *ret = rec;
    else
        job_rec_clear(&rec);
    return r;
}

static int pg_remove(store *s, const char *id, geo_err *err)
{
    CONN_OR_FAIL(s, pg, err);
    const char *v[] = {id};
    int r = begin_durable(pg, err);
    if (r < 0)
        return r;
    PGresult *res = exec(pg, "delete", "DELETE FROM facetd_jobs WHERE id=$1 "
                         "AND state>=2 RETURNING seq", 1, v, NULL, NULL, 0,
                         &r, err);
    int n = res ? PQntuples(res) : 0;
    PQclear(res);
    r = end_tx(pg, r, err);
    if (r < 0)
        return r;
    return n ? 0 : why_not(pg, id, 0, false, err);
}

static int pg_get(store *s, const char *id, job_rec *ret, geo_err *err)
{
    CONN_OR_FAIL(s, pg, err);
    return get_row(pg, id, ret, err);
}

static int pg_get_blob(store *s, const char *id, store_blob which, void **ret,
                       size_t *ret_len, geo_err *err)
{
    CONN_OR_FAIL(s, pg, err);
    char kind[8];
    snprintf(kind, sizeof kind, "%d", (int)which);
    const char *v[] = {id, kind};
    int r;
    /* a succeeded job without a model blob has its input as result */
    PGresult *res = exec(
        pg, "read blob",
        "SELECT b.data FROM facetd_jobs j JOIN facetd_blobs b ON "
        "b.job_seq=j.seq WHERE j.id=$1 AND (b.kind=$2::smallint OR "
        "($2::smallint=1 AND j.state=2 AND b.kind=0)) "
        "ORDER BY b.kind DESC LIMIT 1",
        2, v, NULL, NULL, 1, &r, err);
    if (!res)
        return r;
    if (PQntuples(res) < 1) {
        PQclear(res);
        return geo_err_set(err, -ENOENT, "job '%s' has no such data", id);
    }
    size_t n = (size_t)PQgetlength(res, 0, 0);
    char *buf = malloc(n + 1);
    if (!buf) {
        PQclear(res);
        return geo_err_set(err, -ENOMEM, "store: out of memory");
    }
    if (n)
        memcpy(buf, PQgetvalue(res, 0, 0), n);
    buf[n] = '\0';
    PQclear(res);
    *ret = buf;
    *ret_len = n;
    return 0;
}

static int pg_list(store *s, const store_filter *f, job_rec **ret,
                   size_t *ret_n, geo_err *err)
{
    CONN_OR_FAIL(s, pg, err);
    char state[8], limit[8];
    snprintf(state, sizeof state, "%d", f->state);
    snprintf(limit, sizeof limit, "%u", f->limit);
    const char *v[] = {state, f->source, f->after, limit};
    int r;
    PGresult *res = exec(pg, "list", "SELECT " COLS " FROM facetd_jobs WHERE "
                         "($1::int<0 OR state=$1::int) AND ($2::text IS NULL "
                         "OR source=$2) AND ($3::text IS NULL OR id<$3) "
                         "ORDER BY id DESC LIMIT $4::int", 4, v, NULL, NULL,
                         0, &r, err);
    if (!res)
        return r;
    size_t n = (size_t)PQntuples(res);
    job_rec *out = calloc(n ? n : 1, sizeof *out);
    if (!out) {
        PQclear(res);
        return geo_err_set(err, -ENOMEM, "store: out of memory");
    }
    for (size_t i = 0; i < n; i++) {
        if (read_row(res, (int)i, &out[i]) < 0) {
            for (size_t k = 0; k < i; k++)
                job_rec_clear(&out[k]);
            free(out);
            PQclear(res);
            return geo_err_set(err, -ENOMEM, "store: out of memory");
        }
    }
    PQclear(res);
    *ret = out;
    *ret_n = n;
    return 0;
}

/* Re-queues this node's running jobs (node not empty) and those whose
 * lease expired; how many, or the error. */
static int expire(pg_store *s, PGconn *pg, const char *node, geo_err *err)
{
    char now[24];
    snprintf(now, sizeof now, "%lld", (long long)job_now_ms());
    const char *v[] = {node, now};
    int r;
    PGresult *res = exec(pg, "expire leases", sql_expire, 2, v, NULL, NULL, 0,
                         &r, err);
    if (!res)
        return r;
    int n = PQntuples(res);
    for (int i = 0; i < n; i++)
        log_msg(LOG_NOTICE, PQgetvalue(res, i, 0), "%s of node %s; queued "
                "again", node[0] ? "interrupted by the restart" :
                "lease expired", PQgetvalue(res, i, 1));
    PQclear(res);
    (void)s;
    return n;
}

static int pg_recover(store *s, unsigned *ret_n, geo_err *err)
{
    CONN_OR_FAIL(s, pg, err);
    int n = expire(P(s), pg, P(s)->node, err);
    if (n < 0)
        return n;
    if (ret_n)
        *ret_n = (unsigned)n;
    return 0;
}

static int pg_retention(store *s, int64_t older_than_ms, uint64_t max_bytes,
                        unsigned *ret_deleted, geo_err *err)
{
    CONN_OR_FAIL(s, pg, err);
    int r = run(pg, "begin", "BEGIN", 0, NULL, err);
    if (r < 0)
        return r;
    char gap[24], cutoff[24], max[24];
    snprintf(gap, sizeof gap, "%d", RETENTION_GAP_MS);
    snprintf(cutoff, sizeof cutoff, "%lld", (long long)older_than_ms);
    snprintf(max, sizeof max, "%llu", (unsigned long long)max_bytes);
    unsigned deleted = 0;
    /* the row lock lets one node in; the others then see its time */
    const char *g[] = {gap};
    PGresult *res = exec(
        pg, "retention turn",
        "UPDATE facetd_meta SET value=(extract(epoch FROM clock_timestamp())"
        "*1000)::bigint WHERE key='retention_ms' AND value < "
        "(extract(epoch FROM clock_timestamp())*1000)::bigint-$1::bigint "
        "RETURNING value", 1, g, NULL, NULL, 0, &r, err);
    if (!res)
        goto out;
    bool mine = PQntuples(res) > 0;
    PQclear(res);
    if (!mine)
        goto out;
    const char *a[] = {cutoff};
    res = exec(pg, "retention by age", "DELETE FROM facetd_jobs WHERE "
               "state>=2 AND finished_ms<$1", 1, a, NULL, NULL, 0, &r, err);
    if (!res)
        goto out;
    deleted += (unsigned)strtoul(PQcmdTuples(res), NULL, 10);
    PQclear(res);
    /* oldest first while the jobs left would keep more than $1 bytes */
    const char *b[] = {max};
    res = exec(pg, "retention by size",
               "DELETE FROM facetd_jobs WHERE seq IN (SELECT seq FROM "
               "(SELECT seq, sum(input_bytes+result_bytes) OVER (ORDER BY "
               "finished_ms, seq) - (input_bytes+result_bytes) AS before "
               "FROM facetd_jobs WHERE state>=2) d WHERE (SELECT "
               "coalesce(sum(input_bytes+result_bytes),0) FROM facetd_jobs) "
               "- d.before > $1::bigint)", 1, b, NULL, NULL, 0, &r, err);
    if (!res)
        goto out;
    deleted += (unsigned)strtoul(PQcmdTuples(res), NULL, 10);
    PQclear(res);
out:
    r = end_tx(pg, r, err);
    if (r == 0 && ret_deleted)
        *ret_deleted = deleted;
    return r;
}

static int pg_counts(store *s, store_counts *ret, geo_err *err)
{
    CONN_OR_FAIL(s, pg, err);
    int r;
    PGresult *res = exec(pg, "count", "SELECT state, count(*), "
                         "coalesce(sum(input_bytes+result_bytes),0) FROM "
                         "facetd_jobs GROUP BY state", 0, NULL, NULL, NULL, 0,
                         &r, err);
    if (!res)
        return r;
    store_counts out;
    memset(&out, 0, sizeof out);
    for (int i = 0; i < PQntuples(res); i++) {
        int64_t st = col_i64(res, i, 0);
        if (st >= 0 && st < JOB_NSTATES)
            out.by_state[st] = (uint64_t)col_i64(res, i, 1);
        out.kept_bytes += (uint64_t)col_i64(res, i, 2);
    }
    PQclear(res);
    res = exec(pg, "size", "SELECT pg_total_relation_size('facetd_jobs')+"
               "pg_total_relation_size('facetd_blobs')", 0, NULL, NULL, NULL,
               0, &r, err);
    if (!res)
        return r;
    out.file_bytes = (uint64_t)col_i64(res, 0, 0);
    PQclear(res);
    *ret = out;
    return 0;
}

static int pg_ping(store *s, geo_err *err)
{
    CONN_OR_FAIL(s, pg, err);
    return run(pg, "ping", "SELECT 1", 0, NULL, err);
}

static void pg_set_events(store *s, const store_events *ev)
{
    pthread_mutex_lock(&P(s)->ev_lock);
    P(s)->ev = *ev;
    pthread_mutex_unlock(&P(s)->ev_lock);
}

static const char *pg_node(store *s)
{
    return P(s)->node;
}

/* ---- the events thread: leases, expiry, notifications --------------- */

static void emit(pg_store *s, store_event ev, const char *id,
                 const char *source)
{
    pthread_mutex_lock(&s->ev_lock);
    if (s->ev.fn)
        s->ev.fn(s->ev.user, ev, id, source);
    pthread_mutex_unlock(&s->ev_lock);
}

/* "ID KIND SOURCE" from the trigger. */
static void dispatch(pg_store *s, const char *payload)
{
    char id[JOB_ID_LEN + 1];
    if (strlen(payload) < JOB_ID_LEN + 3 || payload[JOB_ID_LEN] != ' ')
        return;
    memcpy(id, payload, JOB_ID_LEN);
    id[JOB_ID_LEN] = '\0';
    const char *source = payload + JOB_ID_LEN + 2;
    if (*source == ' ')
        source++;
    store_event ev;
    switch (payload[JOB_ID_LEN + 1]) {
    case 'q': ev = STORE_EV_QUEUED; break;
    case 'p': ev = STORE_EV_PROGRESS; break;
    case 'e': ev = STORE_EV_ENDED; break;
    case 'd': ev = STORE_EV_DELETED; break;
    default: ev = STORE_EV_CHANGED; break;
    }
    emit(s, ev, id, source);
}

static void drain(pg_store *s, PGconn *pg)
{
    PGnotify *n;
    while ((n = PQnotifies(pg))) {
        dispatch(s, n->extra);
        PQfreemem(n);
    }
}

/* Extends the leases of the jobs running here; a claim whose lease is
 * gone (the database was away longer than the lease and another node
 * took the job) stops being renewed. */
static int renew(pg_store *s, PGconn *pg, geo_err *err)
{
    int64_t now = job_mono_ms();
    pthread_mutex_lock(&s->claims_lock);
    /* "{", each token (at most 20 digits and sign) with its comma, "}", NUL */
    size_t cap = 3 + s->nclaims * 22;
    char *arr = malloc(cap);
    size_t len = 0, n = 0;
    if (arr) {
        arr[len++] = '{';
        for (size_t i = 0; i < s->nclaims;) {
            claim *c = &s->claims[i];
            if (!c->renew && now >= c->forget_at) {
                *c = s->claims[--s->nclaims];
                continue;
            }
            if (c->renew)
                len += (size_t)snprintf(arr + len, cap - len, "%s%lld",
                                        n++ ? "," : "", (long long)c->token);
            i++;
        }
        arr[len++] = '}';
        arr[len] = '\0';
    }
    pthread_mutex_unlock(&s->claims_lock);
    if (!arr)
        return geo_err_set(err, -ENOMEM, "store: out of memory");
    if (!n) {
        free(arr);
        return 0;
    }
    char lease[24];
    snprintf(lease, sizeof lease, "%llu", (unsigned long long)s->lease_ms);
    const char *v[] = {arr, lease};
    int r;
    /* a job that just ended here keeps its token: not lost */
    PGresult *res = exec(pg, "renew leases", "UPDATE facetd_jobs SET "
                         "lease_until=CASE WHEN state=1 THEN clock_timestamp()"
                         "+$2::bigint*interval '1 millisecond' ELSE NULL END "
                         "WHERE claim_token=ANY($1::bigint[]) RETURNING "
                         "claim_token", 2, v, NULL, NULL, 0, &r, err);
    free(arr);
    if (!res)
        return r;
    int rows = PQntuples(res);
    pthread_mutex_lock(&s->claims_lock);
    for (size_t i = 0; i < s->nclaims; i++) {
        claim *c = &s->claims[i];
        if (!c->renew)
            continue;
        bool kept = false;
        for (int k = 0; k < rows && !kept; k++)
            kept = col_i64(res, k, 0) == c->token;
        if (!kept) {
            log_msg(LOG_WARNING, c->id, "this node's lease on the job was "
                    "lost; its result will be refused");
            c->renew = false;
            c->forget_at = now + (int64_t)s->lease_ms;
        }
    }
    pthread_mutex_unlock(&s->claims_lock);
    PQclear(res);
    return 0;
}

static void *events_main(void *arg)
{
    pg_store *s = arg;
    PGconn *pg = NULL;
    bool down = false;
    int64_t next_renew = 0, next_sweep = 0;
    int64_t renew_every = (int64_t)s->lease_ms / 3;
    while (!atomic_load(&s->stopping)) {
        geo_err err;
        int64_t now = job_mono_ms();
        if (!pg) {
            pg = pg_connect(s, &err);
            if (pg && run(pg, "listen", "LISTEN facetd_jobs", 0, NULL,
                          &err) < 0) {
                PQfinish(pg);
                pg = NULL;
            }
            if (!pg) {
                if (!down)
                    log_msg(LOG_ERR, NULL, "%s; workers wait for it", err.msg);
                down = true;
                struct pollfd w = {s->wake[0], POLLIN, 0};
                poll(&w, 1, RETRY_CONNECT_MS);
                continue;
            }
            atomic_store(&s->down_until, 0);
            if (down) {
                log_msg(LOG_NOTICE, NULL, "the database is reachable again");
                emit(s, STORE_EV_RESYNC, NULL, NULL);
            }
            down = false;
            next_renew = next_sweep = now;
        }
        if (now >= next_renew) {
            if (renew(s, pg, &err) < 0)
                log_msg(LOG_WARNING, NULL, "%s", err.msg);
            next_renew = now + renew_every;
        }
        if (now >= next_sweep) {
            if (expire(s, pg, "", &err) < 0)
                log_msg(LOG_WARNING, NULL, "%s", err.msg);
            next_sweep = now + SWEEP_EVERY_MS;
        }
        drain(s, pg);
        int64_t until = next_renew < next_sweep ? next_renew : next_sweep;
        int64_t wait = until - job_mono_ms();
        struct pollfd p[2] = {{PQsocket(pg), POLLIN, 0},
                              {s->wake[0], POLLIN, 0}};
        poll(p, 2, wait > 0 ? (int)wait : 0);
        if (p[0].revents && !PQconsumeInput(pg))
            log_msg(LOG_WARNING, NULL, "store: lost the database connection: "
                    "%s", PQerrorMessage(pg));
        drain(s, pg);
        if (PQstatus(pg) != CONNECTION_OK) {
            PQfinish(pg);
            pg = NULL;
            down = true;
        }
    }
    if (pg)
        PQfinish(pg);
    return NULL;
}

static void pg_close(store *base)
{
    pg_store *s = P(base);
    if (s->thread_started) {
        atomic_store(&s->stopping, true);
        if (write(s->wake[1], "x", 1) < 0) {
            /* the thread also sees `stopping` within a second */
        }
        pthread_join(s->thread, NULL);
    }
    pconn *c = s->conns;
    while (c) {
        pconn *next = c->next;
        if (c->pg)
            PQfinish(c->pg);
        free(c);
        c = next;
    }
    pthread_key_delete(s->key);
    pthread_mutex_destroy(&s->conns_lock);
    pthread_mutex_destroy(&s->claims_lock);
    pthread_mutex_destroy(&s->ev_lock);
    if (s->wake[0] >= 0)
        close(s->wake[0]);
    if (s->wake[1] >= 0)
        close(s->wake[1]);
    free(s->claims);
    free(s);
}

static const store_ops pg_ops = {
    .name = "postgresql",
    .put = pg_put,
    .claim = pg_claim,
    .progress = pg_progress,
    .finish = pg_finish,
    .requeue = pg_requeue,
    .cancel = pg_cancel,
    .remove = pg_remove,
    .get = pg_get,
    .get_blob = pg_get_blob,
    .list = pg_list,
    .recover = pg_recover,
    .retention = pg_retention,
    .counts = pg_counts,
    .ping = pg_ping,
    .close = pg_close,
    .set_events = pg_set_events,
    .node = pg_node,
};

/* Creates or migrates the schema; the advisory lock makes a second node
 * starting at the same time wait and then find it done. */
static int migrate(PGconn *pg, geo_err *err)
{
    int r = run(pg, "lock schema", "SELECT pg_advisory_lock(" MIGRATE_LOCK ")",
                0, NULL, err);
    if (r < 0)
        return r;
    r = run(pg, "schema table", "CREATE TABLE IF NOT EXISTS facetd_schema("
            "version integer NOT NULL)", 0, NULL, err);
    PGresult *res = NULL;
    if (r == 0)
        res = exec(pg, "schema version", "SELECT max(version) FROM "
                   "facetd_schema", 0, NULL, NULL, NULL, 0, &r, err);
    int version = res && !PQgetisnull(res, 0, 0) ? (int)col_i64(res, 0, 0)
                                                   : 0;
    bool empty = res && PQgetisnull(res, 0, 0);
    PQclear(res);
    if (r == 0 && version > SCHEMA_VERSION)
        r = geo_err_set(err, -EINVAL, "store: the database's schema version "
                        "%d is newer than this facetd knows (%d)", version,
                        SCHEMA_VERSION);
    for (int v = version; r == 0 && v < SCHEMA_VERSION; v++) {
        char bump[96];
        snprintf(bump, sizeof bump, empty && v == version
                 ? "INSERT INTO facetd_schema VALUES(%d)"
                 : "UPDATE facetd_schema SET version=%d", v + 1);
        PGresult *m;
        r = run(pg, "begin", "BEGIN", 0, NULL, err);
        if (r == 0) {
            /* several statements: the simple query protocol */
            m = PQexec(pg, migrations[v]);
            if (PQresultStatus(m) != PGRES_COMMAND_OK &&
                PQresultStatus(m) != PGRES_TUPLES_OK)
                r = pg_fail(pg, m, "migrate", err);
            PQclear(m);
            if (r == 0)
                r = run(pg, "migrate", bump, 0, NULL, err);
            r = end_tx(pg, r, err);
        }
        if (r == 0)
            log_msg(LOG_NOTICE, NULL, "store: database schema at version %d",
                    v + 1);
    }
    run(pg, "unlock schema", "SELECT pg_advisory_unlock(" MIGRATE_LOCK ")", 0,
        NULL, NULL);
    return r;
}

store *store_pg_open(const store_pg_config *c, geo_err *err)
{
    if (!c->url || !c->url[0] || !c->node || !c->node[0] || !c->lease_ms) {
        geo_err_set(err, -EINVAL, "store: URL, node name and lease needed");
        return NULL;
    }
    for (const char *p = c->node; *p; p++)
        if (!strchr("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                    "0123456789._:-", *p)) {
            geo_err_set(err, -EINVAL, "[Cluster] NodeName: '%s': letters, "
                        "digits and . _ : - only", c->node);
            return NULL;
        }
    char *perr = NULL;
    PQconninfoOption *opts = PQconninfoParse(c->url, &perr);
    if (!opts) {
        char buf[256];
        geo_err_set(err, -EINVAL, "[Store] URL: %s",
                    trimmed(perr ? perr : "out of memory", buf, sizeof buf));
        PQfreemem(perr);
        return NULL;
    }
    bool has_password = false;
    for (PQconninfoOption *o = opts; o->keyword; o++)
        if (strcmp(o->keyword, "password") == 0 && o->val && o->val[0])
            has_password = true;
    PQconninfoFree(opts);
    if (has_password) {
        geo_err_set(err, -EINVAL, "[Store] URL: carries a password; give it "
                    "through [Store] PasswordFile=, PGPASSFILE or a service "
                    "file instead");
        return NULL;
    }
    pg_store *s = calloc(1, sizeof *s);
    if (!s) {
        geo_err_set(err, -ENOMEM, "store: out of memory");
        return NULL;
    }
    s->base.ops = &pg_ops;
    s->wake[0] = s->wake[1] = -1;
    if (strlen(c->url) >= sizeof s->url || strlen(c->node) >= sizeof s->node ||
        (c->password_file && strlen(c->password_file) >= sizeof s->passfile)) {
        geo_err_set(err, -EINVAL, "store: URL, node name or password file "
                    "too long");
        free(s);
        return NULL;
    }
    snprintf(s->url, sizeof s->url, "%s", c->url);
    snprintf(s->passfile, sizeof s->passfile, "%s",
             c->password_file ? c->password_file : "");
    snprintf(s->node, sizeof s->node, "%s", c->node);
    snprintf(s->appname, sizeof s->appname, "facetd %s", c->node);
    s->lease_ms = c->lease_ms;
    if (pthread_key_create(&s->key, NULL) != 0) {
        geo_err_set(err, -ENOMEM, "store: no thread key");
        free(s);
        return NULL;
    }
    pthread_mutex_init(&s->conns_lock, NULL);
    pthread_mutex_init(&s->claims_lock, NULL);
    pthread_mutex_init(&s->ev_lock, NULL);
    atomic_init(&s->down_until, 0);
    atomic_init(&s->stopping, false);
    PGconn *pg = conn(s, err);
    if (!pg || migrate(pg, err) < 0) {
        pg_close(&s->base);
        return NULL;
    }
    if (pipe2(s->wake, O_CLOEXEC) < 0) {
        geo_err_set(err, -errno, "store: pipe: %s", strerror(errno));
        pg_close(&s->base);
        return NULL;
    }
    if (pthread_create(&s->thread, NULL, events_main, s) != 0) {
        geo_err_set(err, -EAGAIN, "store: cannot start the lease thread");
        pg_close(&s->base);
        return NULL;
    }
    s->thread_started = true;
    return &s->base;
}
