#!/usr/bin/env bash
# The containers, built and run with podman where Docker Hub cannot be reached (what .ci/run does):
#
#   docker/podman-ci.sh [SCRATCH_DIR]
#
# 1. a base image from Debian's packages (mmdebstrap bookworm, python3 and venv), imported as
#    localhost/bookworm-py (kept between runs; CAUSALPLAN_REBUILD_BASE=1 makes it again);
# 2. the service and tests images of docker/Dockerfile on that base (BASE build argument), and
#    the load balancer's (docker/nginx), whose configuration nginx checks;
# 3. the tests container: the README's test command inside it (PostgreSQL and Chromium are
#    Debian's, installed in the image);
# 4. the service container's smoke test (docker/smoke.py: health, one plan, one transfer).
#
# Facts of these machines it works around: podman needs `--runtime runc` (crun fails on
# setrlimit) and rlimits it may set (the defaults are refused); builds and pip need the host's
# network, CA bundle and pip configuration, mounted read-only.
set -euo pipefail
cd "$(dirname "$0")/.."
scratch=${1:-$(mktemp -d /tmp/causalplan-podman.XXXXXX)}
mkdir -p "$scratch"

podman=(podman --runtime runc)
limits=(--ulimit nofile=4096:4096 --ulimit nproc=4096:4096)
volumes=()  # the host's CA bundle and pip configuration, for builds and containers alike
for file in /etc/ssl/certs/ca-certificates.crt /etc/pip.conf /etc/xdg/pip "${PIP_FIND_LINKS:-}"; do
    if [ -n "$file" ] && [ -e "$file" ]; then volumes+=(-v "$file:$file:ro"); fi
done
environment=()  # pip's settings from the environment, for the tests container's pip
for name in PIP_INDEX_URL PIP_EXTRA_INDEX_URL PIP_CERT PIP_FIND_LINKS PIP_DEFAULT_TIMEOUT; do
    if [ -n "${!name:-}" ]; then environment+=(-e "$name"); fi
done

stage() { echo "== $(date -u +%H:%M:%S) $*"; }

if [ "${CAUSALPLAN_REBUILD_BASE:-0}" = 1 ] || ! podman image exists localhost/bookworm-py; then
    stage "base image from Debian's packages (mmdebstrap)"
    mmdebstrap --quiet --variant=minbase --include=python3,python3-venv,ca-certificates bookworm "$scratch/rootfs.tar"
    podman import --quiet "$scratch/rootfs.tar" localhost/bookworm-py >/dev/null
    rm -f "$scratch/rootfs.tar"
fi

for target in service tests; do
    stage "build localhost/causalplan-$target"
    # --format docker keeps the HEALTHCHECK (the OCI format has none), which compose waits on.
    "${podman[@]}" build --quiet --format docker --network=host "${volumes[@]}" \
        -f docker/Dockerfile --ignorefile docker/Dockerfile.dockerignore \
        --build-arg BASE=localhost/bookworm-py --target "$target" -t "localhost/causalplan-$target" . >/dev/null
done

stage "build localhost/causalplan-nginx (the load balancer) and check its configuration"
"${podman[@]}" build --quiet --format docker --network=host "${volumes[@]}" \
    --build-arg BASE=localhost/bookworm-py -t localhost/causalplan-nginx docker/nginx >/dev/null
# nginx resolves its upstream when it reads the file: name compose's `service` for the check.
"${podman[@]}" run --rm "${limits[@]}" --add-host service:127.0.0.1 localhost/causalplan-nginx nginx -t -q

stage "tests container: the README's test command"
# --init: an init process as PID 1 adopts and reaps orphans (PostgreSQL's server, killed
# planners); without it the test process is PID 1, and the tests that check that a search left
# no child behind find those orphans. Chromium wants more shared memory than the default 64 MB.
"${podman[@]}" run --rm --init --shm-size=1g --network=host "${limits[@]}" "${volumes[@]}" "${environment[@]}" \
    -e CI=true localhost/causalplan-tests

stage "service container: smoke test"
port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
name="causalplan-smoke-$$"
"${podman[@]}" run -d --rm --name "$name" --network=host "${limits[@]}" localhost/causalplan-service \
    causalplan serve --host 127.0.0.1 --port "$port" >/dev/null
trap '"${podman[@]}" stop -t 5 "$name" >/dev/null 2>&1 || true' EXIT
"${SMOKE_PYTHON:-.venv/bin/python}" docker/smoke.py "http://127.0.0.1:$port"
stage "containers done"
