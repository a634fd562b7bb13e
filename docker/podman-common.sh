# shellcheck shell=bash
# What docker/podman-ci.sh and docker/compose-smoke.sh share (sourced, not run): podman's
# settings for these machines and the base image made from Debian's packages.
#
# Facts of these machines it works around: podman needs `--runtime runc` (crun fails on
# setrlimit) and rlimits it may set (the defaults are refused); builds and pip need the host's
# network, CA bundle and pip configuration, mounted read-only.

podman=(podman --runtime runc)
# shellcheck disable=SC2034  # used by the scripts that source this file
limits=(--ulimit nofile=4096:4096 --ulimit nproc=4096:4096)
volumes=()  # the host's CA bundle, pip configuration and the package folders it names, for builds and containers alike
for file in /etc/ssl/certs/ca-certificates.crt /etc/pip.conf /etc/xdg/pip "${PIP_FIND_LINKS:-}" /opt/pypi /opt/pypi-more; do
    if [ -n "$file" ] && [ -e "$file" ]; then volumes+=(-v "$file:$file:ro"); fi
done
environment=()  # pip's settings from the environment, for the tests container's pip
for name in PIP_INDEX_URL PIP_EXTRA_INDEX_URL PIP_CERT PIP_FIND_LINKS PIP_DEFAULT_TIMEOUT; do
    if [ -n "${!name:-}" ]; then environment+=(-e "$name"); fi
done

stage() { echo "== $(date -u +%H:%M:%S) $*"; }

# ensure_base_image SCRATCH_DIR: localhost/bookworm-py, from Debian's packages (mmdebstrap,
# python3 and venv); kept between runs, made again when CAUSALPLAN_REBUILD_BASE=1.
ensure_base_image() {
    if [ "${CAUSALPLAN_REBUILD_BASE:-0}" = 1 ] || ! podman image exists localhost/bookworm-py; then
        stage "base image from Debian's packages (mmdebstrap)"
        mmdebstrap --quiet --variant=minbase --include=python3,python3-venv,ca-certificates bookworm "$1/rootfs.tar"
        podman import --quiet "$1/rootfs.tar" localhost/bookworm-py >/dev/null
        rm -f "$1/rootfs.tar"
    fi
}

# build_image TAG PODMAN_BUILD_ARGUMENTS...: an image on the local base.
build_image() {
    local tag=$1
    shift
    stage "build $tag"
    # --format docker keeps the HEALTHCHECK (the OCI format has none), which compose waits on.
    "${podman[@]}" build --quiet --format docker --network=host "${volumes[@]}" \
        --build-arg BASE=localhost/bookworm-py -t "$tag" "$@" >/dev/null
}
