# pg.sh — a throwaway PostgreSQL for the cluster tests and benchmarks
# (sourced, bash): initdb into a temporary directory as an unprivileged
# user (PostgreSQL refuses root), scram passwords, a free port on
# 127.0.0.1, a libpq password file for the nodes. Usage:
#   . tests/support/pg.sh
#   pg_available || skip ...     # the Debian PostgreSQL 15 binaries
#   pg_init DIR && pg_start      # sets PGD, PGPORT, PG_URL, PG_PASSFILE
#   pg_stop                      # immediate shutdown (also in traps)
PGBIN=${PGBIN:-/usr/lib/postgresql/15/bin}

pg_available() { [ -x "$PGBIN/initdb" ] && [ -x "$PGBIN/pg_ctl" ]; }

as_pg() {
    if [ "$(id -u)" = 0 ]; then runuser -u postgres -- "$@"; else "$@"; fi
}

# below the kernel's ephemeral range, where clients' own ports are taken
pg_free_port() {
    local p
    for p in $(shuf -i 20000-32000 -n 50); do
        (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null || { echo "$p"; return; }
    done
}

# pg_init PASSFILE_DIR [FSYNC]: a new cluster in its own temporary
# directory; the password file goes into PASSFILE_DIR (readable by the
# nodes). FSYNC off makes the tests cheaper; benchmarks keep it on.
pg_init() {
    PGD=$(mktemp -d -t facetd-pg.XXXXXX)
    PG_FSYNC=${2:-on}
    [ "$(id -u)" = 0 ] && chown postgres: "$PGD"
    PGPORT=$(pg_free_port)
    echo secret-pw >"$PGD/pw"
    [ "$(id -u)" = 0 ] && chown postgres: "$PGD/pw"
    as_pg "$PGBIN/initdb" -D "$PGD/data" -U facetd --pwfile="$PGD/pw" \
        -A scram-sha-256 -E UTF8 --no-instructions >"$PGD/initdb.log" 2>&1 ||
        return 1
    PG_PASSFILE=$1/pgpass
    pg_port "$PGPORT"
}

# pg_port PORT: the port the database listens on, in the URL and the
# password file.
pg_port() {
    PGPORT=$1
    printf '127.0.0.1:%s:*:facetd:secret-pw\n' "$PGPORT" >"$PG_PASSFILE"
    chmod 600 "$PG_PASSFILE"
    PG_URL="postgresql://facetd@127.0.0.1:$PGPORT/postgres"
}

# pg_start: starts it on PGPORT; the first start moves to another port
# if that one was taken meanwhile (tests run side by side). Later starts
# keep the port: the nodes know it.
pg_start() {
    local try
    for try in 1 2 3 4 5; do
        [ -f "$PGD/log" ] && : >"$PGD/log" # keeps its owner
        if as_pg "$PGBIN/pg_ctl" -D "$PGD/data" -l "$PGD/log" -w -t 30 -o \
            "-c listen_addresses=127.0.0.1 -c port=$PGPORT -c unix_socket_directories=$PGD -c fsync=$PG_FSYNC -c max_connections=200" \
            start >/dev/null 2>&1; then
            PG_STARTED=1
            return 0
        fi
        grep -q 'Address already in use' "$PGD/log" || return 1
        [ -z "${PG_STARTED:-}" ] && pg_port "$(pg_free_port)"
        sleep 0.5
    done
    return 1
}

pg_stop() {
    [ -n "${PGD:-}" ] && as_pg "$PGBIN/pg_ctl" -D "$PGD/data" -m immediate stop >/dev/null 2>&1
    return 0
}

# pg_cleanup: stops it and removes its directory (KEEP=1 keeps it).
pg_cleanup() {
    pg_stop
    [ -n "${PGD:-}" ] && [ -z "${KEEP:-}" ] && rm -rf "$PGD"
    return 0
}
