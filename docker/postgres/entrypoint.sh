#!/usr/bin/env bash
# Starts PostgreSQL on PGDATA, creating the cluster on first start as the official image does:
# POSTGRES_USER (default postgres) is its superuser with POSTGRES_PASSWORD (required), and
# POSTGRES_DB (default: the user's name) is created. Clients from other hosts sign in with
# that password (scram-sha-256); the local socket trusts its own user, as the official image's.
set -euo pipefail

bin=$(find /usr/lib/postgresql -path '*/bin/postgres' -printf '%h\n' | sort -V | tail -n 1)
data=${PGDATA:?PGDATA must name the data folder}
user=${POSTGRES_USER:-postgres}
database=${POSTGRES_DB:-$user}

if [ ! -s "$data/PG_VERSION" ]; then
    if [ -z "${POSTGRES_PASSWORD:-}" ]; then
        echo "causalplan-postgres: POSTGRES_PASSWORD is not set; the first start needs it (the superuser's password)" >&2
        exit 2
    fi
    password_file=$(mktemp)
    trap 'rm -f "$password_file"' EXIT
    printf '%s\n' "$POSTGRES_PASSWORD" >"$password_file"
    "$bin/initdb" --pgdata="$data" --username="$user" --pwfile="$password_file" \
        --encoding=UTF8 --locale=C.UTF-8 --auth-local=trust --auth-host=scram-sha-256 >/dev/null
    rm -f "$password_file"
    echo "host all all all scram-sha-256" >>"$data/pg_hba.conf"
    if [ "$database" != postgres ]; then
        # Single-user mode: no server listens while the database is made.
        echo "CREATE DATABASE \"${database//\"/\"\"}\";" | "$bin/postgres" --single -D "$data" -j postgres >/dev/null
    fi
    echo "causalplan-postgres: cluster created in $data (superuser $user, database $database)"
fi
exec "$bin/postgres" -D "$data" -c listen_addresses='*' "$@"
