#!/usr/bin/env bash
# with_postgres.sh CMD [ARGS...]: run CMD with a PostgreSQL server of its
# own, started here and stopped (and its files removed) when CMD ends.
#
# The server is a fresh cluster (initdb) in a temporary directory, trusting
# local connections, listening on a Unix socket in that directory and on a
# free loopback TCP port, with its default durability (fsync on,
# synchronous_commit on).  CMD gets GLINT_TEST_PG, a libpq connection
# string to the server's "postgres" database as user postgres, and
# GLINT_TEST_PG_PORT.  As root the server runs as the postgres user
# (PostgreSQL refuses root).  Exits 77 (skipped) when PostgreSQL's server
# programs are not installed (Debian: postgresql).
set -euo pipefail

bindir=""
for d in /usr/lib/postgresql/*/bin; do
  [ -x "$d/initdb" ] && bindir=$d
done
if [ -z "$bindir" ]; then
  echo "with_postgres.sh: PostgreSQL's server is not installed (apt install postgresql): skipped"
  exit 77
fi

run_as=()
if [ "$(id -u)" -eq 0 ]; then
  id postgres >/dev/null 2>&1 || { echo "with_postgres.sh: no postgres user" >&2; exit 1; }
  run_as=(runuser -u postgres --)
fi

dir=$(mktemp -d /tmp/glint-pg-XXXXXX)
chmod 755 "$dir"
[ ${#run_as[@]} -gt 0 ] && chown postgres: "$dir"
pid=""
cleanup() {
  if [ -f "$dir/data/postmaster.pid" ]; then
    "${run_as[@]}" "$bindir/pg_ctl" -D "$dir/data" -m immediate stop >/dev/null 2>&1 || true
  fi
  rm -rf "$dir"
}
trap cleanup EXIT

"${run_as[@]}" "$bindir/initdb" -D "$dir/data" -U postgres --auth=trust -E UTF8 \
  --no-instructions >"$dir/initdb.log" 2>&1 || { cat "$dir/initdb.log" >&2; exit 1; }

# a free loopback port (the kernel's choice)
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
"${run_as[@]}" "$bindir/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w -t 60 \
  -o "-c listen_addresses=127.0.0.1 -p $port -c unix_socket_directories=$dir -c max_connections=200" \
  start >/dev/null || { cat "$dir/server.log" >&2; exit 1; }

export GLINT_TEST_PG="host=$dir port=$port user=postgres dbname=postgres"
export GLINT_TEST_PG_PORT=$port
export GLINT_TEST_PG_BINDIR=$bindir
set +e
"$@"
rc=$?
set -e
exit $rc
