#!/usr/bin/env bash
# The containers, built and run with podman where Docker Hub cannot be reached (what .ci/run does):
#
#   docker/podman-ci.sh [SCRATCH_DIR]
#
# 1. a base image from Debian's packages (mmdebstrap bookworm, python3 and venv), imported as
#    localhost/bookworm-py (kept between runs; CAUSALPLAN_REBUILD_BASE=1 makes it again);
# 2. the service and tests images of docker/Dockerfile on that base (BASE build argument), and
#    the load balancer's (docker/nginx), whose configuration nginx checks;
# 3. the tests container: README command 2, read from the README (docker/readme-command.sh), run
#    as written in a copy of the repository on the bare base (python3 and venv only): the command
#    installs Chromium itself, and PostgreSQL comes from a wheel;
# 4. the service container's smoke test (docker/smoke.py: health, one plan, one transfer).
#
# podman's settings for these machines, and the base image: docker/podman-common.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
scratch=${1:-$(mktemp -d /tmp/causalplan-podman.XXXXXX)}
mkdir -p "$scratch"
# shellcheck source=docker/podman-common.sh
source docker/podman-common.sh

ensure_base_image "$scratch"

for target in service tests; do
    build_image "localhost/causalplan-$target" -f docker/Dockerfile --ignorefile docker/Dockerfile.dockerignore \
        --target "$target" .
done

build_image localhost/causalplan-nginx docker/nginx
stage "check the load balancer's configuration"
# nginx resolves its upstream when it reads the file: name compose's `service` for the check.
"${podman[@]}" run --rm "${limits[@]}" --add-host service:127.0.0.1 localhost/causalplan-nginx nginx -t -q

readme_command=$(bash docker/readme-command.sh 2)
stage "tests container: README command 2 on the bare base: $readme_command"
# --init: an init process as PID 1 adopts and reaps orphans (PostgreSQL's server, killed
# planners); without it the test process is PID 1, and the tests that check that a search left
# no child behind find those orphans. Chromium wants more shared memory than the default 64 MB.
"${podman[@]}" run --rm --init --shm-size=1g --network=host "${limits[@]}" "${volumes[@]}" "${environment[@]}" \
    -e CI=true -e DEBIAN_FRONTEND=noninteractive localhost/causalplan-tests bash -c "$readme_command"

stage "service container: smoke test"
port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
name="causalplan-smoke-$$"
"${podman[@]}" run -d --rm --name "$name" --network=host "${limits[@]}" localhost/causalplan-service \
    causalplan serve --host 127.0.0.1 --port "$port" >/dev/null
trap '"${podman[@]}" stop -t 5 "$name" >/dev/null 2>&1 || true' EXIT
"${SMOKE_PYTHON:-.venv/bin/python}" docker/smoke.py "http://127.0.0.1:$port"
stage "containers done"
