#!/usr/bin/env bash
# A throwaway PostgreSQL server for the distributed-sweep tests (Debian's packages).
#
#   source .ci/postgres.sh          # exports VFGYM_TEST_POSTGRES_URL into this shell
#   bash .ci/postgres.sh [ENVFILE]  # starts it and writes `export ...` lines to ENVFILE
#   bash .ci/postgres.sh --stop [ENVFILE]
#
# PostgreSQL refuses to run as root, so as root the server gets its own system user
# (vfgympg) and data directory; as any other user it runs as that user. It listens on
# 127.0.0.1 only, on a free port, with a generated password; fsync is off (test data).
# An already running server recorded in ENVFILE is reused.

_vfgym_pg_main() {
  local env_file="${1:-${VFGYM_PG_ENV_FILE:-/tmp/vfgym-postgres.env}}"
  local base="${VFGYM_PG_BASE:-/tmp/vfgym-postgres}"
  local os_user db_user="vfgym" db_name="vfgym_test" bindir port password run_as=()

  _vfgym_pg_bindir() {
    local d
    d=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n 1)
    [ -n "$d" ] && [ -x "$d/initdb" ] && echo "$d"
  }

  # Reuse a live server from an earlier call.
  if [ -f "$env_file" ]; then
    # shellcheck disable=SC1090
    . "$env_file"
    if [ -n "${VFGYM_TEST_POSTGRES_PGBIN:-}" ] && [ -n "${VFGYM_TEST_POSTGRES_PORT:-}" ] &&
      "$VFGYM_TEST_POSTGRES_PGBIN/pg_isready" -q -h 127.0.0.1 -p "$VFGYM_TEST_POSTGRES_PORT"; then
      echo "postgres.sh: reusing the server on port $VFGYM_TEST_POSTGRES_PORT ($env_file)" >&2
      return 0
    fi
  fi

  bindir=$(_vfgym_pg_bindir || true)
  if [ -z "$bindir" ]; then
    if [ "$(id -u)" != 0 ]; then
      echo "postgres.sh: PostgreSQL is not installed and installing needs root" >&2
      return 1
    fi
    echo "postgres.sh: installing Debian's postgresql" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -q >&2
    apt-get install -y -q postgresql >&2
    bindir=$(_vfgym_pg_bindir)
  fi

  if [ "$(id -u)" = 0 ]; then
    os_user=vfgympg
    if ! id "$os_user" >/dev/null 2>&1; then
      useradd --system --home-dir "$base" --no-create-home --shell /usr/sbin/nologin "$os_user"
    fi
    run_as=(runuser -u "$os_user" --)
  else
    os_user=$(id -un)
  fi

  # A fresh data directory owned by the server's user.
  if [ -f "$base/data/postmaster.pid" ]; then
    "${run_as[@]}" "$bindir/pg_ctl" -D "$base/data" -m immediate stop >/dev/null 2>&1 || true
  fi
  rm -rf "$base"
  mkdir -p "$base/data" "$base/socket"
  chmod 700 "$base/data"
  password=$(od -An -N16 -tx1 /dev/urandom | tr -d ' \n')
  printf '%s\n' "$password" >"$base/pwfile"
  chown -R "$os_user" "$base"
  chmod 600 "$base/pwfile"

  "${run_as[@]}" "$bindir/initdb" -D "$base/data" -U "$db_user" --pwfile="$base/pwfile" \
    --auth=scram-sha-256 -E UTF8 --no-locale >"$base/initdb.log" 2>&1 || {
    cat "$base/initdb.log" >&2
    return 1
  }
  rm -f "$base/pwfile"

  port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  "${run_as[@]}" "$bindir/pg_ctl" -D "$base/data" -l "$base/server.log" -w -t 60 \
    -o "-c listen_addresses=127.0.0.1 -p $port -k $base/socket -c fsync=off \
-c synchronous_commit=off -c full_page_writes=off -c max_connections=200" start >&2 || {
    cat "$base/server.log" >&2
    return 1
  }
  PGPASSWORD="$password" "$bindir/createdb" -h 127.0.0.1 -p "$port" -U "$db_user" "$db_name"

  cat >"$env_file" <<EOF
export VFGYM_TEST_POSTGRES_URL=postgresql://$db_user:$password@127.0.0.1:$port/$db_name
export VFGYM_TEST_POSTGRES_PORT=$port
export VFGYM_TEST_POSTGRES_PGBIN=$bindir
export VFGYM_TEST_POSTGRES_DATA=$base/data
EOF
  chmod 600 "$env_file"
  # shellcheck disable=SC1090
  . "$env_file"
  echo "postgres.sh: PostgreSQL $("$bindir/postgres" --version | awk '{print $3}') on" \
    "127.0.0.1:$port as OS user $os_user, data in $base/data; env in $env_file" >&2
}

_vfgym_pg_stop() {
  local env_file="${1:-${VFGYM_PG_ENV_FILE:-/tmp/vfgym-postgres.env}}" run_as=()
  [ -f "$env_file" ] || return 0
  # shellcheck disable=SC1090
  . "$env_file"
  [ "$(id -u)" = 0 ] && run_as=(runuser -u vfgympg --)
  "${run_as[@]}" "$VFGYM_TEST_POSTGRES_PGBIN/pg_ctl" -D "$VFGYM_TEST_POSTGRES_DATA" \
    -m fast stop >&2 || true
  rm -f "$env_file"
}

if [ "${BASH_SOURCE[0]}" != "$0" ]; then
  # Sourced (by .ci/run): export the URL into the caller's shell; leave nothing else.
  _vfgym_pg_main "$@"
  unset -f _vfgym_pg_main _vfgym_pg_stop _vfgym_pg_bindir
else
  set -euo pipefail
  if [ "${1:-}" = "--stop" ]; then
    shift
    _vfgym_pg_stop "$@"
  else
    _vfgym_pg_main "$@"
    echo "VFGYM_TEST_POSTGRES_URL=$VFGYM_TEST_POSTGRES_URL"
  fi
fi
