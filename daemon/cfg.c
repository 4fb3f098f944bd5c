/* cfg.c — the key table, the INI reader with drop-ins, the flag parser and
 * the value parsers behind cfg.h. Invariant: every key exists once, in
 * keys[], with its default as text, so defaults, files, flags and --help
 * all go through the same parser. */
#include "cfg.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "config.h"
#include "log.h"
#include "pipeline.h"

/* K_LIST: a repeatable key (Scanner=): each line adds an entry, an empty
 * value resets the default list. K_PIPELINE: a string checked with
 * cfg_pipeline_json. */
enum ktype { K_STR, K_BOOL, K_UINT, K_SIZE, K_DURATION, K_LEVEL, K_LIST,
             K_PIPELINE };

typedef struct key {
    const char *section, *name, *flag;
    enum ktype type;
    size_t off, size;     /* field in cfg; size for strings */
    uint64_t min, max;    /* numeric range */
    bool reloadable;      /* SIGHUP can change it */
    const char *def;      /* default, as text */
    const char *help;     /* one line: --help */
    const char *doc;      /* more: facetd.conf(5), facetd.conf.example */
} key;

#define F(field) offsetof(cfg, field), sizeof(((cfg *)0)->field)
#define KiB 1024ull
#define MiB (1024ull * KiB)
#define GiB (1024ull * MiB)
#define SEC 1000ull

static const key keys[] = {
    {"Server", "Listen", "listen", K_STR, F(listen), 0, 0, false,
     "127.0.0.1:8080", "HOST:PORT, [IPV6]:PORT or :PORT to listen on",
     "Port 0 picks a free port (logged). Ignored when systemd passes "
     "the socket (facetd.socket)."},
    {"Server", "ApiToken", "api-token", K_STR, F(api_token), 0, 0, true, "",
     "bearer token every request must carry (Authorization: Bearer)",
     "Any address other than loopback needs a token, sent by clients "
     "as \"Authorization: Bearer TOKEN\" and compared in constant time, "
     "or AllowUnauthenticated=yes: facetd refuses to start otherwise. "
     "Visible ASCII characters only."},
    {"Server", "ApiTokenFile", "api-token-file", K_STR, F(api_token_file), 0,
     0, true, "", "file holding the API token",
     "The token is read from this file (whitespace around it trimmed) "
     "at start and on every reload, and replaces ApiToken=; it keeps "
     "the token out of the configuration. For example "
     "/etc/facetd/api-token."},
    {"Server", "AllowUnauthenticated", "allow-unauthenticated", K_BOOL,
     F(allow_unauthenticated), 0, 1, true, "no",
     "allow a non-loopback listener without an API token",
     "Without it facetd refuses to start on such an address."},
    {"Server", "HttpThreads", "http-threads", K_UINT, F(http_threads), 0, 64,
     false, "0", "HTTP threads (0: one per CPU)",
     "Each thread has its own epoll set on the listening socket; "
     "long-polls and event streams suspend their connection instead of "
     "holding a thread."},
    {"Server", "MaxConnections", "max-connections", K_UINT,
     F(max_connections), 4, 1000000, false, "1024",
     "concurrent HTTP connections", ""},
    {"Server", "MaxBody", "max-body", K_SIZE, F(max_body), KiB, 64 * GiB,
     true, "64M", "largest request body (413 above)",
     "An oversized Content-Length is refused before a byte is read."},
    {"Server", "ConnectionTimeout", "connection-timeout", K_DURATION,
     F(connection_timeout_ms), SEC, 3600 * SEC, false, "60s",
     "idle connection timeout", ""},
    {"Server", "ConnectionMemory", "connection-memory", K_SIZE,
     F(connection_memory), 8 * KiB, 16 * MiB, false, "64K",
     "memory per connection for headers", ""},
    {"Server", "HeaderTimeout", "header-timeout", K_DURATION,
     F(header_timeout_ms), 100, 3600 * SEC, false, "10s",
     "time a client has to send a request's headers (closed after)",
     "Counted from the connection, or from the previous answer on it."},
    {"Server", "PerClientConnections", "per-client-connections", K_UINT,
     F(per_client_connections), 0, 1000000, false, "64",
     "concurrent connections from one address (0: no limit)", ""},
    {"Server", "MaxQueryArgs", "max-query-args", K_UINT, F(max_query_args),
     1, 100000, true, "100", "query arguments per request (400 above)",
     ""},
    {"Server", "MaxWaiters", "max-waiters", K_UINT, F(max_waiters), 1,
     1000000, true, "4096", "clients waiting on ?wait= or events (429 above)",
     "A waiting client holds no thread: its connection is suspended "
     "until its job changes."},
    {"Server", "MaxWait", "max-wait", K_DURATION, F(max_wait_ms), 0,
     3600 * SEC, true, "60s", "longest ?wait=",
     "A longer ?wait= is cut to this."},
    {"Server", "KeepAlive", "keep-alive", K_DURATION, F(keepalive_ms),
     100, 3600 * SEC, true, "15s", "event stream keep-alive interval",
     "A comment line goes out at this interval while the stream has "
     "nothing else to send."},
    {"Server", "InspectMaxFacets", "inspect-max-facets", K_UINT,
     F(inspect_max_facets), 4, 100000000, true, "20000",
     "largest model POST /v1/inspect takes",
     "POST /v1/inspect answers synchronously; bigger models must be "
     "submitted as jobs. The facets are counted while the body is "
     "tokenised, so a larger model is refused (413) before it is built."},
    {"Server", "InspectTimeout", "inspect-timeout", K_DURATION,
     F(inspect_timeout_ms), 100, 3600 * SEC, true, "10s",
     "time limit of one POST /v1/inspect (503 after)",
     "Inspections run on two threads of their own, not on the HTTP "
     "threads; one that runs longer is stopped and answered 503."},
    {"Jobs", "Workers", "workers", K_UINT, F(workers), 0, 256, false, "0",
     "job workers (0: one per CPU)",
     "Each runs one job at a time; the kernels of a job share the "
     "thread pool."},
    {"Jobs", "QueueSize", "queue-size", K_UINT, F(queue_size), 1, 10000000,
     true, "1000", "queued jobs before submissions get 503",
     "The 503 carries Retry-After. Scanner jobs are not bounded by it."},
    {"Jobs", "JobTimeout", "job-timeout", K_DURATION, F(job_timeout_ms), SEC,
     7 * 24 * 3600 * SEC, true, "10min", "wall time limit of one job",
     "A job running longer is cancelled and fails."},
    {"Jobs", "ShutdownTimeout", "shutdown-timeout", K_DURATION,
     F(shutdown_timeout_ms), 0, 3600 * SEC, true, "30s",
     "time running jobs get to finish on SIGTERM",
     "The jobs still running then are queued again and run after the "
     "next start."},
    {"Jobs", "Paused", "paused", K_BOOL, F(paused), 0, 1, true, "no",
     "accept and keep jobs but start none (maintenance)",
     "Jobs (and scans) are still accepted and stored durably; no "
     "worker starts one until Paused=no is reloaded."},
    {"Jobs", "Lease", "job-lease", K_DURATION, F(job_lease_ms), SEC,
     3600 * SEC, false, "30s", "with a shared store: how long a node's "
     "claim on a job lasts unless renewed (a dead node's jobs run again "
     "after it)",
     "A node renews the claims of the jobs it runs; a worker whose lease "
     "was lost stops its run. Without Store URL= it has no effect."},
    {"Store", "URL", "store-url", K_STR, F(store_url), 0, 0, false, "",
     "job store shared by a cluster: postgresql://HOST[:PORT]/DB (no "
     "password in it); empty: SQLite in StateDirectory",
     "Every node of a cluster names the same database; cluster events "
     "wake the workers, waiting clients and scanner RESULTs of every "
     "node. An unreachable store answers 503 with Retry-After."},
    {"Store", "PasswordFile", "store-password-file", K_STR,
     F(store_password_file), 0, 0, false, "", "libpq password file for "
     "URL (default: PGPASSFILE or ~/.pgpass)",
     "A URL= that carries a password is refused: it goes here, in "
     "PGPASSFILE or in a service file."},
    {"Store", "StateDirectory", "state-dir", K_STR, F(state_dir), 0, 0, false,
     "/var/lib/facetd", "directory of the job store",
     "The SQLite job store lives here (facetd.db, WAL mode); a lock "
     "file keeps a second facetd off the same directory."},
    {"Store", "RetentionAge", "retention-age", K_DURATION,
     F(retention_age_ms), SEC, 100ull * 365 * 24 * 3600 * SEC, true, "7d",
     "finished jobs older than this are deleted",
     "Checked at start, every minute and on reload; queued and running "
     "jobs are never deleted."},
    {"Store", "RetentionBytes", "retention-bytes", K_SIZE,
     F(retention_bytes), MiB, 1ull << 50, true, "1G",
     "finished jobs beyond this total size are deleted, oldest first",
     "Counts the inputs and results of all jobs."},
    {"Cluster", "NodeName", "node-name", K_STR, F(node_name), 0, 0, false,
     "", "this node's name in the cluster (default: HOST:PORT)",
     "Recorded with each claim in the shared store; the default is the "
     "host name and the listening port."},
    {"Log", "LogLevel", "log-level", K_LEVEL, F(log_level), 0, 0, true,
     "info", "log level: err, warning, notice, info or debug",
     "Logs go to standard error, one line per event with its level and "
     "job id (journald priorities under systemd)."},
    {"Scanners", "Enabled", "scanners", K_BOOL, F(scanners), 0, 1, false,
     "yes", "take scans from USB scanners (--no-scanners: serve HTTP only)",
     "Each finished scan (FSP/1 over USB) becomes a high-priority job "
     "with source usb:SERIAL, and the scanner gets a RESULT frame when "
     "the job ends."},
    {"Scanners", "Scanner", "scanner", K_LIST, F(scanner), 0, 0, false,
     SCAN_DEFAULT_DEVICES, "VID:PID:bulk|hid [PIPELINE]: a scanner model "
     "(repeatable; the first replaces the default list)",
     "A line may add the pipeline for that model (as Pipeline=), for "
     "example \"0483:5740:hid /etc/facetd/pipelines/small-stones.json\". "
     "The default list is the specification's two test devices; an "
     "empty Scanner= restores it. Add a udev rule for every model "
     "listed (70-facetd-scanners.rules)."},
    {"Scanners", "Pipeline", "scanner-pipeline", K_PIPELINE,
     F(scanner_pipeline), 0, 0, true, "inspect,correct,inspect,report",
     "pipeline of scanner jobs: correct, op names (inspect,triangulate), "
     "inline JSON or a /path/to/pipeline.json",
     "correct is the post-scan correction; the default adds the stone's "
     "proportions (report) to every scan; a JSON file is read again "
     "on SIGHUP, as `facet run` takes it. facetd does not start when a "
     "configured pipeline names an unknown operation."},
};
enum { NKEYS = sizeof keys / sizeof keys[0] };

/* What each section of keys[] is for: the headings of facetd.conf(5) and
 * of the example file. */
static const struct { const char *name, *doc; } sections[] = {
    {"Server", "The HTTP server: where it listens, who may use it, and its "
               "limits."},
    {"Jobs", "The queue and the workers that run the pipelines."},
    {"Store", "The durable job store, and how long finished jobs are kept."},
    {"Cluster", "Several facetd nodes sharing one job store ([Store] "
                "URL=)."},
    {"Log", "What facetd logs."},
    {"Scanners", "USB scanners speaking FSP/1: which devices, and the "
                 "pipeline of their jobs."},
};

static char *trim(char *s)
{
    while (isspace((unsigned char)*s))
        s++;
    size_t n = strlen(s);
    while (n && isspace((unsigned char)s[n - 1]))
        s[--n] = '\0';
    return s;
}

static int parse_u64(const char *s, uint64_t *ret, const char **ret_end)
{
    if (!isdigit((unsigned char)*s))
        return -EINVAL;
    errno = 0;
    char *end;
    unsigned long long v = strtoull(s, &end, 10);
    if (errno == ERANGE)
        return -ERANGE;
    *ret = v;
    *ret_end = end;
    return 0;
}

static int mul_ok(uint64_t v, uint64_t m, uint64_t *ret)
{
    if (m && v > UINT64_MAX / m)
        return -ERANGE;
    *ret = v * m;
    return 0;
}

static int parse_size(const char *s, uint64_t *ret)
{
    uint64_t v;
    const char *end;
    if (parse_u64(s, &v, &end) < 0)
        return -EINVAL;
    uint64_t m = 1;
    if (*end) {
        switch (toupper((unsigned char)*end)) {
        case 'K': m = KiB; break;
        case 'M': m = MiB; break;
        case 'G': m = GiB; break;
        case 'T': m = 1024 * GiB; break;
        default: return -EINVAL;
        }
        end++;
        if (toupper((unsigned char)*end) == 'I')
            end++;
        if (toupper((unsigned char)*end) == 'B')
            end++;
        if (*end)
            return -EINVAL;
    }
    return mul_ok(v, m, ret);
}

static int parse_duration(const char *s, uint64_t *ret_ms)
{
    uint64_t v;
    const char *end;
    if (parse_u64(s, &v, &end) < 0)
        return -EINVAL;
    static const struct { const char *unit; uint64_t ms; } units[] = {
        {"", SEC},   {"ms", 1},  {"s", SEC}, {"sec", SEC},
        {"min", 60 * SEC}, {"m", 60 * SEC}, {"h", 3600 * SEC},
        {"d", 86400 * SEC},
    };
    for (size_t i = 0; i < sizeof units / sizeof units[0]; i++)
        if (strcmp(end, units[i].unit) == 0)
            return mul_ok(v, units[i].ms, ret_ms);
    return -EINVAL;
}

static int parse_bool(const char *s, bool *ret)
{
    static const char *const yes[] = {"yes", "true", "on", "1"};
    static const char *const no[] = {"no", "false", "off", "0"};
    for (int i = 0; i < 4; i++) {
        if (strcasecmp(s, yes[i]) == 0)
            return *ret = true, 0;
        if (strcasecmp(s, no[i]) == 0)
            return *ret = false, 0;
    }
    return -EINVAL;
}

/* Checks one Scanner= line; with the first n entries of c's list as the
 * scanners it is added to (no VID:PID twice). */
static int check_scanner(const cfg *c, unsigned n, const key *k,
                         const char *value, geo_err *err)
{
    char dev[64];
    const char *pipeline = cfg_scanner_split(value, dev, sizeof dev);
    scan_match m;
    int r = scan_match_parse(dev, &m, err);
    if (r < 0) {
        geo_err_prefix(err, k->name);
        return r;
    }
    for (unsigned i = 0; i < n; i++) {
        char other[64];
        cfg_scanner_split(c->scanner[i], other, sizeof other);
        scan_match o;
        if (scan_match_parse(other, &o, NULL) == 0 && o.vid == m.vid &&
            o.pid == m.pid)
            return geo_err_set(err, -EINVAL, "%s: %04x:%04x listed twice",
                               k->name, m.vid, m.pid);
    }
    if (*pipeline) {
        json_t *pj = cfg_pipeline_json(pipeline, err);
        if (!pj) {
            geo_err_prefix(err, k->name);
            return -EINVAL;
        }
        json_decref(pj);
    }
    if (n == CFG_SCANNERS_MAX)
        return geo_err_set(err, -EINVAL, "%s: more than %d scanners",
                           k->name, CFG_SCANNERS_MAX);
    if (strlen(value) >= CFG_SCANNER_LEN)
        return geo_err_set(err, -EINVAL, "%s: longer than %d bytes", k->name,
                           CFG_SCANNER_LEN - 1);
    return 0;
}

/* K_LIST: an empty value restores the default list; the first line after
 * that replaces it, later lines add. c is unchanged on error. */
static int set_list(cfg *c, const key *k, const char *value, geo_err *err)
{
    if (*value) {
        unsigned n = c->scanner_set ? c->nscanner : 0;
        int r = check_scanner(c, n, k, value, err);
        if (r < 0)
            return r;
        if (!c->scanner_set)
            memset(c->scanner, 0, sizeof c->scanner);
        memcpy(c->scanner[n], value, strlen(value) + 1);
        c->nscanner = n + 1;
        c->scanner_set = true;
        return 0;
    }
    memset(c->scanner, 0, sizeof c->scanner);
    c->nscanner = 0;
    char def[256];
    snprintf(def, sizeof def, "%s", k->def);
    for (char *save, *e = strtok_r(def, ",", &save); e;
         e = strtok_r(NULL, ",", &save)) {
        char *entry = trim(e);
        if (check_scanner(c, c->nscanner, k, entry, err) == 0)
            memcpy(c->scanner[c->nscanner++], entry, strlen(entry) + 1);
    }
    c->scanner_set = false;
    return 0;
}

static int set_value(cfg *c, const key *k, const char *value, geo_err *err)
{
    char *field = (char *)c + k->off;
    uint64_t v = 0;
    if (k->type == K_LIST)
        return set_list(c, k, value, err);
    bool given = *value != '\0';
    if (!*value)
        value = k->def;
    switch (k->type) {
    case K_LIST:
        break;
    case K_PIPELINE: {
        if (strlen(value) >= k->size)
            return geo_err_set(err, -EINVAL, "%s: longer than %zu bytes",
                               k->name, k->size - 1);
        json_t *pj = cfg_pipeline_json(value, err);
        if (!pj) {
            geo_err_prefix(err, k->name);
            return -EINVAL;
        }
        json_decref(pj);
        memcpy(field, value, strlen(value) + 1);
        c->scanner_pipeline_set = given;
        return 0;
    }
    case K_STR:
        if (strlen(value) >= k->size)
            return geo_err_set(err, -EINVAL, "%s: longer than %zu bytes",
                               k->name, k->size - 1);
        memcpy(field, value, strlen(value) + 1);
        return 0;
    case K_BOOL: {
        bool b;
        if (parse_bool(value, &b) < 0)
            return geo_err_set(err, -EINVAL,
                               "%s: expected yes or no, got '%s'", k->name,
                               value);
        memcpy(field, &b, sizeof b);
        return 0;
    }
    case K_LEVEL: {
        int lvl = log_level_from_name(value);
        if (lvl < 0)
            return geo_err_set(err, -EINVAL,
                               "%s: expected err, warning, notice, info or "
                               "debug, got '%s'", k->name, value);
        memcpy(field, &lvl, sizeof lvl);
        return 0;
    }
    case K_UINT: {
        const char *end;
        if (parse_u64(value, &v, &end) < 0 || *end)
            return geo_err_set(err, -EINVAL,
                               "%s: expected a whole number, got '%s'",
                               k->name, value);
        break;
    }
    case K_SIZE:
        if (parse_size(value, &v) < 0)
            return geo_err_set(err, -EINVAL,
                               "%s: expected a size such as 64M, got '%s'",
                               k->name, value);
        break;
    case K_DURATION:
        if (parse_duration(value, &v) < 0)
            return geo_err_set(err, -EINVAL,
                               "%s: expected a duration such as 30s or 10min, "
                               "got '%s'", k->name, value);
        break;
    }
    if (v < k->min || v > k->max)
        return geo_err_set(err, -EINVAL,
                           "%s: %s out of range [%llu, %llu]%s", k->name,
                           value, (unsigned long long)k->min,
                           (unsigned long long)k->max,
                           k->type == K_DURATION ? " ms" : "");
    if (k->type == K_UINT) {
        unsigned u = (unsigned)v;
        memcpy(field, &u, sizeof u);
    } else {
        memcpy(field, &v, sizeof v);
    }
    return 0;
}

void cfg_defaults(cfg *c)
{
    memset(c, 0, sizeof *c);
    for (int i = 0; i < NKEYS; i++) {
        int r = set_value(c, &keys[i], "", NULL);
        (void)r;
    }
}

static const key *find_key(const char *section, const char *name)
{
    for (int i = 0; i < NKEYS; i++)
        if (strcasecmp(keys[i].section, section) == 0 &&
            strcasecmp(keys[i].name, name) == 0)
            return &keys[i];
    return NULL;
}

static bool known_section(const char *section)
{
    for (int i = 0; i < NKEYS; i++)
        if (strcasecmp(keys[i].section, section) == 0)
            return true;
    return false;
}

/* Sets one key by its section and name (as in a file) from a string
 * value; an empty value resets the default. 0 or -EINVAL with err. */
static int cfg_set(cfg *c, const char *section, const char *name,
                   const char *value, geo_err *err)
{
    const key *k = find_key(section, name);
    if (!k)
        return geo_err_set(err, -EINVAL, "unknown key %s in [%s]", name,
                           section);
    return set_value(c, k, value, err);
}

/* Reads one INI file into c. A missing file is -ENOENT (err set). */
static int parse_file(cfg *c, const char *path, geo_err *err)
{
    FILE *f = fopen(path, "re");
    if (!f)
        return geo_err_set(err, -errno, "%s: %s", path, strerror(errno));
    char line[4096], section[64] = "";
    int lineno = 0, r = 0;
    while (fgets(line, sizeof line, f)) {
        lineno++;
        if (!strchr(line, '\n') && !feof(f)) {
            r = geo_err_set(err, -EINVAL, "%s:%d: line too long", path,
                            lineno);
            break;
        }
        char *s = trim(line);
        if (!*s || *s == '#' || *s == ';')
            continue;
        if (*s == '[') {
            char *close = strchr(s, ']');
            if (!close || close[1] || close - s - 1 >= (long)sizeof section) {
                r = geo_err_set(err, -EINVAL, "%s:%d: malformed section %s",
                                path, lineno, s);
                break;
            }
            *close = '\0';
            snprintf(section, sizeof section, "%s", trim(s + 1));
            if (!known_section(section)) {
                r = geo_err_set(err, -EINVAL, "%s:%d: unknown section [%s]",
                                path, lineno, section);
                break;
            }
            continue;
        }
        char *eq = strchr(s, '=');
        if (!eq) {
            r = geo_err_set(err, -EINVAL, "%s:%d: expected Key=Value",
                            path, lineno);
            break;
        }
        *eq = '\0';
        char *name = trim(s), *value = trim(eq + 1);
        if (!*section) {
            r = geo_err_set(err, -EINVAL, "%s:%d: %s outside a [Section]",
                            path, lineno, name);
            break;
        }
        r = cfg_set(c, section, name, value, err);
        if (r < 0) {
            char where[600];
            snprintf(where, sizeof where, "%s:%d", path, lineno);
            geo_err_prefix(err, where);
            break;
        }
    }
    if (!r && ferror(f))
        r = geo_err_set(err, -EIO, "%s: read error", path);
    fclose(f);
    return r;
}

static int by_name(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* Applies PATH.d/ *.conf in lexical order; a missing directory is fine. */
static int parse_dropins(cfg *c, const char *path, geo_err *err)
{
    char dir[PATH_MAX];
    if ((size_t)snprintf(dir, sizeof dir, "%s.d", path) >= sizeof dir)
        return geo_err_set(err, -EINVAL, "%s: path too long", path);
    DIR *d = opendir(dir);
    if (!d)
        return errno == ENOENT || errno == ENOTDIR
                   ? 0
                   : geo_err_set(err, -errno, "%s: %s", dir, strerror(errno));
    char **names = NULL;
    size_t n = 0, cap = 0;
    int r = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        size_t l = strlen(e->d_name);
        if (e->d_name[0] == '.' || l < 6 ||
            strcmp(e->d_name + l - 5, ".conf") != 0)
            continue;
        if (n == cap) {
            cap = cap ? 2 * cap : 16;
            char **nn = realloc(names, cap * sizeof *nn);
            if (!nn) {
                r = -ENOMEM;
                break;
            }
            names = nn;
        }
        if (!(names[n] = strdup(e->d_name))) {
            r = -ENOMEM;
            break;
        }
        n++;
    }
    closedir(d);
    if (r == 0 && n)
        qsort(names, n, sizeof *names, by_name);
    for (size_t i = 0; r == 0 && i < n; i++) {
        char p[PATH_MAX];
        if ((size_t)snprintf(p, sizeof p, "%s/%s", dir, names[i]) >= sizeof p)
            r = geo_err_set(err, -EINVAL, "%s/%s: path too long", dir,
                            names[i]);
        else
            r = parse_file(c, p, err);
    }
    for (size_t i = 0; i < n; i++)
        free(names[i]);
    free(names);
    if (r == -ENOMEM)
        geo_err_set(err, r, "out of memory reading %s", dir);
    return r;
}

static const key *find_flag(const char *flag, size_t len)
{
    for (int i = 0; i < NKEYS; i++)
        if (strlen(keys[i].flag) == len && strncmp(keys[i].flag, flag, len) == 0)
            return &keys[i];
    return NULL;
}

bool cfg_wants_help(int argc, char **argv)
{
    for (int i = 0; i < argc; i++)
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0)
            return true;
    return false;
}

/* Walks argv; for each option calls back with (flag key or NULL for the
 * config path, value). Returns 0 or -EINVAL with err. */
static int walk_args(int argc, char **argv, cfg *c, const char **ret_path,
                     geo_err *err)
{
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "-c") == 0 || strcmp(a, "--config") == 0) {
            if (i + 1 >= argc)
                return geo_err_set(err, -EINVAL, "%s needs a path", a);
            *ret_path = argv[++i];
            continue;
        }
        if (strncmp(a, "--config=", 9) == 0) {
            *ret_path = a + 9;
            continue;
        }
        if (strncmp(a, "--", 2) != 0)
            return geo_err_set(err, -EINVAL, "unexpected argument '%s'", a);
        const char *name = a + 2, *eq = strchr(name, '=');
        size_t len = eq ? (size_t)(eq - name) : strlen(name);
        const key *k = find_flag(name, len);
        /* --no-FLAG turns a boolean off */
        bool negated = false;
        if (!k && !eq && len > 3 && strncmp(name, "no-", 3) == 0) {
            k = find_flag(name + 3, len - 3);
            negated = k && k->type == K_BOOL;
            if (!negated)
                k = NULL;
        }
        if (!k)
            return geo_err_set(err, -EINVAL, "unknown option --%.*s",
                               (int)len, name);
        const char *value;
        if (negated)
            value = "no";
        else if (eq)
            value = eq + 1;
        else if (k->type == K_BOOL)
            value = "yes";
        else if (i + 1 < argc)
            value = argv[++i];
        else
            return geo_err_set(err, -EINVAL, "--%s needs a value", k->flag);
        if (!c)
            continue;
        int r = set_value(c, k, value, err);
        if (r < 0) {
            char where[80];
            snprintf(where, sizeof where, "--%s", k->flag);
            geo_err_prefix(err, where);
            return r;
        }
    }
    return 0;
}

int cfg_load(cfg *ret, int argc, char **argv, geo_err *err)
{
    cfg c;
    cfg_defaults(&c);
    const char *path = NULL;
    int r = walk_args(argc, argv, NULL, &path, err);
    if (r < 0)
        return r;
    r = parse_file(&c, path ? path : CFG_DEFAULT_PATH, err);
    if (r == -ENOENT && !path)
        r = 0;
    if (r < 0)
        return r;
    r = parse_dropins(&c, path ? path : CFG_DEFAULT_PATH, err);
    if (r < 0)
        return r;
    r = walk_args(argc, argv, &c, &path, err);
    if (r < 0)
        return r;
    r = cfg_finish(&c, err);
    if (r < 0)
        return r;
    *ret = c;
    return 0;
}

int cfg_finish(cfg *c, geo_err *err)
{
    if (!c->state_dir[0])
        return geo_err_set(err, -EINVAL, "StateDirectory: must not be empty");
    if (c->api_token_file[0]) {
        FILE *f = fopen(c->api_token_file, "re");
        if (!f)
            return geo_err_set(err, -EINVAL, "ApiTokenFile: %s: %s",
                               c->api_token_file, strerror(errno));
        char buf[sizeof c->api_token + 2];
        size_t n = fread(buf, 1, sizeof buf - 1, f);
        fclose(f);
        if (n >= sizeof c->api_token)
            return geo_err_set(err, -EINVAL, "ApiTokenFile: %s: token longer "
                               "than %zu bytes", c->api_token_file,
                               sizeof c->api_token - 1);
        buf[n] = '\0';
        char *t = trim(buf);
        if (!*t)
            return geo_err_set(err, -EINVAL, "ApiTokenFile: %s: empty",
                               c->api_token_file);
        memcpy(c->api_token, t, strlen(t) + 1);
    }
    for (const char *p = c->api_token; *p; p++)
        if (!isgraph((unsigned char)*p))
            return geo_err_set(err, -EINVAL,
                               "ApiToken: only visible ASCII characters");
    return 0;
}

json_t *cfg_pipeline_json(const char *spec, geo_err *err)
{
    while (isspace((unsigned char)*spec))
        spec++;
    json_t *pj = NULL;
    json_error_t je;
    if (!*spec) {
        geo_err_set(err, -EINVAL, "empty pipeline");
        return NULL;
    }
    if (*spec == '[' || *spec == '"' || *spec == '{') {
        pj = json_loads(spec, JSON_DECODE_ANY | JSON_REJECT_DUPLICATES, &je);
        if (!pj) {
            geo_err_set(err, -EINVAL, "column %d: %s", je.column, je.text);
            return NULL;
        }
    } else if (*spec == '/' || strncmp(spec, "./", 2) == 0) {
        pj = json_load_file(spec, JSON_DECODE_ANY | JSON_REJECT_DUPLICATES,
                            &je);
        if (!pj) {
            geo_err_set(err, -EINVAL, "%s:%d:%d: %s", spec, je.line,
                        je.column, je.text);
            return NULL;
        }
    } else if (strcmp(spec, "correct") == 0 || strcmp(spec, "auto") == 0) {
        pj = json_string(spec);
    } else {
        pj = json_array();
        char buf[CFG_PIPELINE_LEN];
        snprintf(buf, sizeof buf, "%s", spec);
        for (char *save, *op = strtok_r(buf, ",", &save); pj && op;
             op = strtok_r(NULL, ",", &save))
            json_array_append_new(pj, json_string(trim(op)));
    }
    if (!pj) {
        geo_err_set(err, -ENOMEM, "out of memory");
        return NULL;
    }
    proto_pipeline pl;
    if (proto_pipeline_from_json(pj, "pipeline", &pl, err) < 0) {
        json_decref(pj);
        return NULL;
    }
    proto_pipeline_free(&pl);
    return pj;
}

const char *cfg_scanner_split(const char *line, char *dev, size_t dev_size)
{
    while (isspace((unsigned char)*line))
        line++;
    size_t n = strcspn(line, " \t");
    snprintf(dev, dev_size, "%.*s", (int)n, line);
    line += n;
    while (isspace((unsigned char)*line))
        line++;
    return line;
}

int cfg_key_count(void)
{
    return NKEYS;
}

void cfg_key_describe(int i, cfg_key_doc *d)
{
    static const char *const forms[] = {
        [K_STR] = "TEXT",         [K_BOOL] = "BOOLEAN",
        [K_UINT] = "NUMBER",      [K_SIZE] = "SIZE",
        [K_DURATION] = "DURATION", [K_LEVEL] = "LEVEL",
        [K_LIST] = "DEVICE [PIPELINE]", [K_PIPELINE] = "PIPELINE",
    };
    const key *k = &keys[i];
    *d = (cfg_key_doc){.section = k->section, .name = k->name,
                       .flag = k->flag, .form = forms[k->type],
                       .def = k->def, .help = k->help, .doc = k->doc,
                       .section_doc = "", .reloadable = k->reloadable,
                       .boolean = k->type == K_BOOL,
                       .repeatable = k->type == K_LIST};
    for (size_t j = 0; j < sizeof sections / sizeof sections[0]; j++)
        if (strcmp(sections[j].name, k->section) == 0)
            d->section_doc = sections[j].doc;
}

void cfg_print_help(FILE *out, const char *prog)
{
    fprintf(out,
            "usage: %s [-c PATH] [--KEY=VALUE ...]\n\n"
            "facetd serves the facet job API over HTTP (see facetd(8)).\n"
            "Configuration: built-in defaults, then %s (or -c PATH),\n"
            "then PATH.d/NAME.conf, then the flags below.\n\n"
            "  -c, --config PATH         configuration file\n"
            "  -h, --help                this help\n"
            "      --version             print the version\n",
            prog, CFG_DEFAULT_PATH);
    const char *section = "";
    for (int i = 0; i < NKEYS; i++) {
        const key *k = &keys[i];
        if (strcmp(section, k->section) != 0) {
            section = k->section;
            fprintf(out, "\n[%s]\n", section);
        }
        char flag[64];
        snprintf(flag, sizeof flag, "--%s%s", k->flag,
                 k->type == K_BOOL ? "" : "=V");
        if (k->type == K_BOOL && strcmp(k->def, "yes") == 0)
            snprintf(flag, sizeof flag, "--[no-]%s", k->flag);
        fprintf(out, "  %-26s %s=  %s (default: %s)%s\n", flag, k->name,
                k->help, *k->def ? k->def : "none",
                k->reloadable ? "" : " [restart]");
    }
    fprintf(out, "\nSizes take K, M, G, T suffixes; durations ms, s, min, h, "
                 "d.\nSIGHUP reloads the configuration (keys marked "
                 "[restart] need a restart).\n");
}

int cfg_restart_only_changes(const cfg *a, const cfg *b, char *buf,
                             size_t size)
{
    int n = 0;
    size_t used = 0;
    if (size)
        buf[0] = '\0';
    for (int i = 0; i < NKEYS; i++) {
        const key *k = &keys[i];
        if (k->reloadable)
            continue;
        bool same;
        if (k->type == K_LIST) {
            same = a->nscanner == b->nscanner;
            for (unsigned j = 0; same && j < a->nscanner; j++)
                same = strcmp(a->scanner[j], b->scanner[j]) == 0;
        } else {
            size_t len = k->type == K_STR ? strlen((const char *)a + k->off) + 1
                         : k->type == K_UINT ? sizeof(unsigned)
                         : k->type == K_BOOL ? sizeof(bool)
                         : k->type == K_LEVEL ? sizeof(int)
                                              : sizeof(uint64_t);
            same = memcmp((const char *)a + k->off, (const char *)b + k->off,
                          len) == 0;
        }
        if (same)
            continue;
        n++;
        if (used < size) {
            int w = snprintf(buf + used, size - used, "%s%s.%s",
                             used ? ", " : "", k->section, k->name);
            if (w > 0)
                used += (size_t)w;
        }
    }
    return n;
}
