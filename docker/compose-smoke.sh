#!/usr/bin/env bash
# The compose stack (docker/compose.yaml) brought up for real, checked end to end through nginx,
# and torn down (its database volume too):
#
#   docker/compose-smoke.sh                          podman and podman-compose (as on CI's machines)
#   CAUSALPLAN_ENGINE=docker docker/compose-smoke.sh Docker and Docker Compose
#
# What it checks is docker/compose_smoke.py's: health through nginx and of every container that
# has a check, the database migrated once, a participant's steps reaching both replicas,
# X-Forwarded-For believed only from nginx, a batch job judged on the Dask workers, and the
# service still answering through nginx with a replica killed. Each check prints what it saw;
# on a failure the containers' last log lines follow.
#
# With podman it builds the images on a Debian base made locally (from the build cache, after
# docker/podman-ci.sh), PostgreSQL's from docker/postgres (Debian's package: the official image
# cannot be pulled here), and runs podman as docker/podman/containers.conf says (runc, the
# rlimits it may set). podman before 4.6 cannot wait for a health check, so the database is
# started, and found healthy, before the rest.
#
# Settings: CAUSALPLAN_ENGINE (podman), PODMAN_COMPOSE (.venv/bin/podman-compose),
# SMOKE_PYTHON (.venv/bin/python), CAUSALPLAN_POSTGRES_IMAGE (podman: localhost/causalplan-postgres).
# nginx is published on 127.0.0.1:8000, as compose.yaml says: that port must be free.
set -euo pipefail
if [ $# -gt 0 ]; then
    case "$1" in
        -h | --help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//' && exit 0 ;;
        *) echo "compose-smoke: no arguments are taken (settings are variables; see --help), got '$1'" >&2 && exit 2 ;;
    esac
fi
cd "$(dirname "$0")/.."
engine=${CAUSALPLAN_ENGINE:-podman}
python=${SMOKE_PYTHON:-.venv/bin/python}
if [ ! -x "$python" ]; then
    echo "compose-smoke: no Python at $python (SMOKE_PYTHON): make the venv as the README says" >&2
    exit 2
fi

case "$engine" in
    podman)
        scratch=$(mktemp -d /tmp/causalplan-compose.XXXXXX)
        # shellcheck source=docker/podman-common.sh
        source docker/podman-common.sh
        export CONTAINERS_CONF=${CONTAINERS_CONF:-$PWD/docker/podman/containers.conf}
        export CAUSALPLAN_POSTGRES_IMAGE=${CAUSALPLAN_POSTGRES_IMAGE:-localhost/causalplan-postgres}
        compose=("${PODMAN_COMPOSE:-.venv/bin/podman-compose}" -f docker/compose.yaml)
        if ! command -v "${compose[0]}" >/dev/null; then
            echo "compose-smoke: no podman-compose at ${compose[0]} (PODMAN_COMPOSE): .venv/bin/pip install podman-compose" >&2
            exit 2
        fi
        # The images' anonymous volumes (VOLUME) go with their containers.
        down=("${PODMAN_COMPOSE:-.venv/bin/podman-compose}" --podman-rm-args=-v -f docker/compose.yaml down -v)
        ensure_base_image "$scratch"
        # Built every time, so the stack runs the working tree: unchanged layers come from the cache.
        build_image localhost/causalplan-service -f docker/Dockerfile \
            --ignorefile docker/Dockerfile.dockerignore --target service .
        build_image localhost/causalplan-nginx docker/nginx
        if [ "$CAUSALPLAN_POSTGRES_IMAGE" = localhost/causalplan-postgres ]; then
            build_image localhost/causalplan-postgres docker/postgres
        fi
        rmdir "$scratch"
        ;;
    docker)
        stage() { echo "== $(date -u +%H:%M:%S) $*"; }
        compose=(docker compose -f docker/compose.yaml)
        down=("${compose[@]}" down -v)
        ;;
    *)
        echo "compose-smoke: CAUSALPLAN_ENGINE must be podman or docker, not '$engine'" >&2
        exit 2
        ;;
esac

up_log=$(mktemp /tmp/causalplan-compose-up.XXXXXX)
teardown() {
    local status=$?
    if [ "$status" -ne 0 ]; then
        echo "--- what compose said while starting the stack (its last lines)"
        tail -n 30 "$up_log"
        for container in $("$engine" ps -a --filter label=com.docker.compose.project=causalplan --format '{{.Names}}'); do
            echo "--- $container (last lines of its log)"
            "$engine" logs --tail 30 "$container" 2>&1 || true
        done
    fi
    stage "tear down (containers, network, database volume)"
    "${down[@]}" >/dev/null 2>&1 || true
    rm -f "$up_log"
    exit "$status"
}
trap teardown EXIT

if [ "$engine" = podman ]; then
    stage "up: postgres, then the rest once it is healthy"
    "${compose[@]}" up -d postgres >>"$up_log" 2>&1
    healthy=false
    for _ in $(seq 60); do
        if podman healthcheck run causalplan_postgres_1 >/dev/null 2>&1; then healthy=true && break; fi
        sleep 1
    done
    if [ "$healthy" != true ]; then echo "compose-smoke: postgres was not healthy within 60 s" >&2 && exit 1; fi
    "${compose[@]}" up -d >>"$up_log" 2>&1
else
    stage "up (building the images)"
    "${compose[@]}" up -d --build --wait
fi

stage "checks through nginx"
"$python" docker/compose_smoke.py --engine "$engine"
stage "compose smoke passed"
