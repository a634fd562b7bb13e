#!/usr/bin/env bash
# The Docker image's install steps, kept in this one script: docker/Dockerfile runs it, and so
# does .ci/run (no Docker engine runs there), so every CI run proves the image's install works.
#
#   docker/install.sh SOURCE_DIR VENV_DIR
#
# Installs causalplan from SOURCE_DIR, with its planners (Fast Downward's search binary and
# translator come as wheels), into a new virtual environment at VENV_DIR; then checks that a
# plan is found and that the database migrations ship inside the installed package.
set -euo pipefail

usage="usage: docker/install.sh SOURCE_DIR VENV_DIR"
source_dir=$(cd "${1:?$usage}" && pwd)
venv=${2:?$usage}

python3 -m venv "$venv"
"$venv/bin/pip" install --quiet "$source_dir"

scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
cd "$scratch"  # away from the source tree, so only the installed package is used

"$venv/bin/causalplan" plan "$source_dir/examples/paper/desk_lamp.yaml"
"$venv/bin/python" - "$scratch/check.sqlite3" <<'PYTHON'
import sys

from causalplan.service.storage.migrate import upgrade
from causalplan.service.storage.session import create_database_engine

engine = create_database_engine(f"sqlite:///{sys.argv[1]}")
print(f"database schema {upgrade(engine)} installs from the package")
PYTHON
