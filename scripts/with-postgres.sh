#!/usr/bin/env bash
# Runs a command beside a throwaway PostgreSQL server:
#
#   bash scripts/with-postgres.sh cargo test --workspace --locked
#
# Creates a cluster in a fresh temp dir with Debian's initdb (as the `postgres` system
# user when run as root: the server refuses to run as root), starts it with pg_ctl on a
# free 127.0.0.1 port (its Unix socket in the temp dir too, so it never meets a system
# cluster on 5432), creates the database `stanice_test`, exports
#   STANICE_TEST_POSTGRES_URL=postgres://postgres@127.0.0.1:PORT/stanice_test
# runs the command, and always stops the server and removes the temp dir afterwards,
# returning the command's exit status. No network beyond loopback, no docker.
#
# The cluster trusts local connections (it lives for one command) and runs with
# synchronous_commit=off, which is the durability SQLite's WAL + synchronous=NORMAL gives
# (a crash may lose the last commits, never consistency); fsync stays on.
#
# When STANICE_TEST_POSTGRES_URL is already set, the command runs against that server.
# When PostgreSQL is not installed, the command runs without the variable (the PostgreSQL
# tests then skip), unless STANICE_REQUIRE_PEERS=1, which makes that an error.
set -euo pipefail

log() { echo "[with-postgres] $*" >&2; }

if [ "$#" -eq 0 ]; then
    echo "usage: $0 COMMAND [ARGS...]" >&2
    exit 2
fi

if [ -n "${STANICE_TEST_POSTGRES_URL:-}" ]; then
    log "using the given STANICE_TEST_POSTGRES_URL"
    exec "$@"
fi

PG_BIN="$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n1 || true)"
if [ -z "$PG_BIN" ] || [ ! -x "$PG_BIN/initdb" ]; then
    if [ "${STANICE_REQUIRE_PEERS:-0}" = "1" ]; then
        log "ERROR: PostgreSQL is not installed (run scripts/install-test-deps.sh)"
        exit 1
    fi
    log "PostgreSQL is not installed: running without it (PostgreSQL tests will skip)"
    exec "$@"
fi

# Run PostgreSQL's programs as `postgres` when we are root, from a directory it may read.
as_pg() {
    if [ "$(id -u)" -eq 0 ]; then
        (cd / && runuser -u postgres -- "$@")
    else
        (cd / && "$@")
    fi
}
if [ "$(id -u)" -eq 0 ] && ! id postgres >/dev/null 2>&1; then
    log "ERROR: running as root but there is no 'postgres' system user"
    exit 1
fi

free_port() {
    python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1]); s.close()' 2>/dev/null \
        || echo $((20000 + RANDOM % 20000))
}

PGTMP="$(mktemp -d "${TMPDIR:-/tmp}/stanice-pg.XXXXXX")"
PGDATA="$PGTMP/data"
STARTED=0
cleanup() {
    local status=$?
    if [ "$STARTED" -eq 1 ]; then
        as_pg "$PG_BIN/pg_ctl" -D "$PGDATA" -m immediate -w stop >/dev/null 2>&1 || true
    fi
    rm -rf "$PGTMP"
    exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

if [ "$(id -u)" -eq 0 ]; then chown postgres: "$PGTMP"; fi
chmod 700 "$PGTMP"

as_pg "$PG_BIN/initdb" -D "$PGDATA" -U postgres --auth=trust --encoding=UTF8 \
    --locale=C.UTF-8 --no-sync >"$PGTMP/initdb.log" 2>&1 \
    || { cat "$PGTMP/initdb.log" >&2; log "ERROR: initdb failed"; exit 1; }

PORT=""
for _ in 1 2 3 4 5; do
    PORT="$(free_port)"
    if as_pg "$PG_BIN/pg_ctl" -D "$PGDATA" -l "$PGTMP/server.log" -w -t 60 start \
        -o "-c listen_addresses=127.0.0.1 -p $PORT -c unix_socket_directories=$PGTMP \
            -c synchronous_commit=off -c max_connections=200" >/dev/null 2>&1; then
        STARTED=1
        break
    fi
    log "could not start on port $PORT, trying another"
done
if [ "$STARTED" -ne 1 ]; then
    cat "$PGTMP/server.log" >&2 || true
    log "ERROR: the PostgreSQL server did not start"
    exit 1
fi

as_pg "$PG_BIN/createdb" -h 127.0.0.1 -p "$PORT" -U postgres stanice_test
export STANICE_TEST_POSTGRES_URL="postgres://postgres@127.0.0.1:$PORT/stanice_test"
log "PostgreSQL $("$PG_BIN/postgres" --version | awk '{print $3}') on 127.0.0.1:$PORT ($PGTMP)"

set +e
"$@"
status=$?
set -e
exit "$status"
