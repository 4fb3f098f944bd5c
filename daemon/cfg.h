/* cfg.h — facetd's configuration: built-in defaults, then the INI file
 * (/etc/facetd/facetd.conf or -c PATH), then its drop-ins (PATH.d/NAME.conf in
 * lexical order), then command-line flags; a later source overrides an
 * earlier one key by key.
 *
 * File syntax (like journald.conf): "[Section]" lines, "Key=Value" lines,
 * blank lines and lines starting with '#' or ';' ignored, whitespace
 * around keys and values trimmed. An empty value resets the key to its
 * default. A repeatable key (Scanner=) adds one entry per line; its first
 * line replaces the default list and an empty value restores it. Boolean
 * flags also take the form --no-FLAG. An unknown section or key, or a
 * malformed value, is an error
 * naming the file and line ("facetd.conf:12: Workers: expected a whole
 * number"). Every key is also a flag (--workers=4 or --workers 4); the
 * table in cfg.c is the one list of keys, and --help is printed from it.
 *
 * Value forms: sizes in bytes with an optional K, M, G or T suffix (powers
 * of 1024); durations in seconds with an optional ms, s, min, h or d
 * suffix; booleans yes/no, true/false, on/off, 1/0.
 *
 * Nothing here is thread-safe: the main thread loads a cfg and hands
 * workers copies of the values they need. */
#ifndef FACETD_CFG_H
#define FACETD_CFG_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include <jansson.h>

#include "ctx.h"

#define CFG_DEFAULT_PATH "/etc/facetd/facetd.conf"

enum {
    CFG_SCANNERS_MAX = 32,     /* Scanner= lines (SCAN_MATCH_MAX) */
    CFG_SCANNER_LEN = 1024,    /* bytes of one, NUL included */
    CFG_PIPELINE_LEN = 1024,   /* bytes of Pipeline=, NUL included */
};

typedef struct cfg {
    /* [Server] */
    char listen[128];             /* HOST:PORT, [V6]:PORT or :PORT; port 0
                                     picks a free port (logged) */
    char api_token[256];          /* bearer token; empty means none */
    char api_token_file[512];     /* file holding the token (trimmed) */
    bool allow_unauthenticated;   /* a non-loopback listener needs a token
                                     unless this is set */
    unsigned http_threads;        /* 0 = number of CPUs; max 64 */
    unsigned max_connections;     /* concurrent connections, ≥ 4 */
    uint64_t max_body;            /* request body bytes, ≥ 1 KiB */
    uint64_t connection_timeout_ms; /* idle connection timeout, ≥ 1 s */
    uint64_t connection_memory;   /* per-connection header memory, ≥ 8 KiB */
    uint64_t header_timeout_ms;   /* connect (or previous answer) to complete
                                     request headers */
    unsigned per_client_connections; /* from one address; 0 = no limit */
    unsigned max_query_args;      /* query arguments per request */
    unsigned max_waiters;         /* suspended ?wait= and SSE clients */
    uint64_t max_wait_ms;         /* cap on ?wait= */
    uint64_t keepalive_ms;        /* SSE keep-alive comment interval */
    unsigned inspect_max_facets;  /* POST /v1/inspect model size cap */
    /* [Jobs] */
    unsigned workers;             /* 0 = number of CPUs; max 256 */
    unsigned queue_size;          /* queued jobs before 503, ≥ 1 */
    uint64_t job_timeout_ms;      /* wall time limit of one job */
    uint64_t shutdown_timeout_ms; /* SIGTERM: how long running jobs may
                                     finish before they are requeued */
    bool paused;                  /* accept and keep jobs, start none */
    uint64_t job_lease_ms;        /* shared store: a claim's lease */
    /* [Store] */
    char state_dir[512];          /* directory of the job store */
    char store_url[1024];         /* PostgreSQL URI shared by a cluster;
                                     empty: SQLite in state_dir */
    char store_password_file[512]; /* libpq passfile for store_url */
    uint64_t retention_age_ms;    /* finished jobs older than this go */
    uint64_t retention_bytes;     /* finished jobs' total size cap */
    /* [Cluster] */
    char node_name[64];           /* empty: host name and port */
    /* [Log] */
    int log_level;                /* syslog level, LOG_INFO by default */
    /* [Scanners] */
    bool scanners;                /* Enabled=: run the USB scanner intake */
    char scanner[CFG_SCANNERS_MAX][CFG_SCANNER_LEN]; /* Scanner= lines,
                                     "VID:PID:bulk|hid [PIPELINE]", checked */
    unsigned nscanner;
    bool scanner_set;             /* a Scanner= line replaced the default
                                     list (later lines add to it) */
    char scanner_pipeline[CFG_PIPELINE_LEN]; /* Pipeline=, checked */
    bool scanner_pipeline_set;    /* Pipeline= given, not the default */
} cfg;

/* Fills every field with its default. */
void cfg_defaults(cfg *c);

/* Builds a configuration from defaults, files and flags. argv are the
 * daemon's arguments after the program name (argc of them); -c PATH /
 * --config=PATH picks the file (default CFG_DEFAULT_PATH, which may be
 * absent; an explicit PATH must exist). --help and --version are not
 * handled here (the caller checks cfg_wants_help first). On success fills
 * *ret and returns 0; on error returns -EINVAL (or -ENOMEM, -EIO) with err
 * naming the file and line or the flag, and leaves *ret untouched. */
int cfg_load(cfg *ret, int argc, char **argv, geo_err *err);


/* Checks ranges and combinations (a token file that cannot be read, …)
 * and reads api_token_file into api_token. 0 or -EINVAL with err. */
int cfg_finish(cfg *c, geo_err *err);

/* True when argv asks for --help / -h. */
bool cfg_wants_help(int argc, char **argv);

/* Prints the usage with every flag, its section/key, default and meaning. */
void cfg_print_help(FILE *out, const char *prog);

/* One key of the configuration table as the documentation generated from
 * it shows it (cfg_doc.h): facetd.conf(5) and the example file. */
typedef struct cfg_key_doc {
    const char *section, *name, *flag;
    const char *form;        /* the value's form: "SIZE", "DURATION", ... */
    const char *def;         /* default as text, "" for none; a list's
                                entries separated by commas */
    const char *help;        /* one line, as --help prints it */
    const char *doc;         /* the rest, sentences */
    const char *section_doc; /* what the key's section is for */
    bool reloadable;         /* SIGHUP applies it */
    bool boolean;            /* also --no-FLAG */
    bool repeatable;         /* one entry per line */
} cfg_key_doc;

/* The number of keys, and key i (0 ≤ i < count) in table order, sections
 * grouped. */
int cfg_key_count(void);
void cfg_key_describe(int i, cfg_key_doc *d);

/* The pipeline a Pipeline= value (or the PIPELINE of a Scanner= line)
 * names, as the JSON value of the Job API's "pipeline" member: "auto";
 * op names separated by commas ("inspect" or "inspect,triangulate",
 * each with its defaults); a JSON array or string written inline
 * ("[{\"op\":\"merge_facets\",\"max_angle_deg\":2}]"); or the path
 * of a file holding that JSON (starting with '/' or "./", as `facet run`
 * takes it). Only the form is checked here, not whether the operations
 * are in this build. A new JSON value the caller owns, or NULL with err
 * set. Reads the file, if any, each time it is called. */
json_t *cfg_pipeline_json(const char *spec, geo_err *err);

/* Splits a checked Scanner= line into the device entry (written to
 * dev, NUL-terminated, at most dev_size bytes) and the pipeline after it
 * (a pointer into line, "" when the line names none). */
const char *cfg_scanner_split(const char *line, char *dev, size_t dev_size);

/* Writes the keys whose values differ between a and b and that a reload
 * cannot change (listen address, state directory, threads, ...) as a
 * comma-separated list of "Section.Key" into buf. Returns the number of
 * such keys. */
int cfg_restart_only_changes(const cfg *a, const cfg *b, char *buf,
                             size_t size);

#endif
