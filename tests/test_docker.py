"""The container files agree with each other and with the service's settings.

(The images themselves are built and run by ``.ci/run``: ``docker/podman-ci.sh``.)
"""

from __future__ import annotations

import ipaddress
import re
from pathlib import Path
from typing import Any

import yaml

from causalplan.settings import Settings

DOCKER = Path(__file__).resolve().parent.parent / "docker"


def compose() -> dict[str, Any]:
    data: dict[str, Any] = yaml.safe_load((DOCKER / "compose.yaml").read_text(encoding="utf-8"))
    return data


def test_the_replicas_trust_exactly_the_load_balancers_address() -> None:
    services = compose()["services"]
    nginx_address = services["nginx"]["networks"]["causalplan"]["ipv4_address"]
    trusted = yaml.safe_load(services["service"]["environment"]["CAUSALPLAN_TRUSTED_PROXIES"])
    assert trusted == [nginx_address]
    assert Settings(database_url="sqlite://", trusted_proxies=trusted).is_trusted_proxy(nginx_address)


def test_several_replicas_share_one_postgresql_and_one_dask_scheduler() -> None:
    services = compose()["services"]
    replica = services["service"]
    assert replica["deploy"]["replicas"] >= 2
    assert "ports" not in replica  # only the load balancer is published
    assert replica["environment"]["CAUSALPLAN_DATABASE_URL"].startswith("postgresql://")
    scheduler = replica["environment"]["CAUSALPLAN_DASK_SCHEDULER"]
    command = services["dask-scheduler"]["command"]
    assert scheduler == f"tcp://dask-scheduler:{command[command.index('--port') + 1]}"
    assert scheduler in services["dask-worker"]["command"]


def test_nginx_sends_to_the_replicas_and_lets_uploads_through() -> None:
    conf = (DOCKER / "nginx" / "nginx.conf").read_text(encoding="utf-8")
    assert re.search(r"upstream causalplan \{\s*server service:8000;", conf)
    assert "proxy_pass http://causalplan;" in conf and "X-Forwarded-For $proxy_add_x_forwarded_for" in conf
    limit = re.search(r"client_max_body_size (\d+)m;", conf)
    assert limit is not None and int(limit.group(1)) * 1024 * 1024 >= Settings().max_upload_bytes
    listen = re.search(r"listen (\d+);", conf)
    assert listen is not None and compose()["services"]["nginx"]["ports"] == [f"127.0.0.1:8000:{listen.group(1)}"]


def test_the_images_keep_the_official_base_for_users_and_take_another_as_an_argument() -> None:
    for dockerfile in (DOCKER / "Dockerfile", DOCKER / "nginx" / "Dockerfile"):
        text = dockerfile.read_text(encoding="utf-8")
        assert re.search(r"^ARG BASE=\S+bookworm\S*$", text, re.MULTILINE), dockerfile
        assert re.search(r"^FROM \$\{BASE\}", text, re.MULTILINE), dockerfile
    assert "ARG BASE=python:3.11-slim-bookworm" in (DOCKER / "Dockerfile").read_text(encoding="utf-8")


def test_the_tests_image_runs_readme_command_2_which_installs_what_the_tests_need() -> None:
    text = (DOCKER / "Dockerfile").read_text(encoding="utf-8")
    tests_stage = text.split("AS tests", 1)[1].split("FROM ", 1)[0]
    assert "docker/readme-command.sh 2" in tests_stage  # the command installs Chromium (tests/test_fresh_machine.py)
    tests_service = compose()["services"]["tests"]
    assert tests_service["init"] is True  # orphans must not become the test process's children


def test_postgresql_is_the_official_image_unless_a_variable_names_the_debian_one() -> None:
    postgres = compose()["services"]["postgres"]
    assert postgres["image"] == "${CAUSALPLAN_POSTGRES_IMAGE:-postgres:15-bookworm}"
    dockerfile = (DOCKER / "postgres" / "Dockerfile").read_text(encoding="utf-8")
    entrypoint = (DOCKER / "postgres" / "entrypoint.sh").read_text(encoding="utf-8")
    # The Debian image reads every setting compose gives the official one, and keeps its data where
    # the official one does (the volume compose mounts).
    assert set(postgres["environment"]) <= set(re.findall(r"\$\{?(POSTGRES_[A-Z]+)", entrypoint))
    pgdata = re.search(r"^ENV PGDATA=(\S+)$", dockerfile, re.MULTILINE)
    assert pgdata is not None and postgres["volumes"] == [f"postgres-data:{pgdata.group(1)}"]
    assert re.search(r"^ARG BASE=\S+bookworm\S*$", dockerfile, re.MULTILINE)
    assert re.search(r"^FROM \$\{BASE\}", dockerfile, re.MULTILINE)


def test_nginx_address_is_outside_the_range_handed_to_other_containers() -> None:
    data = compose()
    (ipam,) = data["networks"]["causalplan"]["ipam"]["config"]
    nginx_address = ipaddress.ip_address(data["services"]["nginx"]["networks"]["causalplan"]["ipv4_address"])
    assert nginx_address in ipaddress.ip_network(ipam["subnet"])
    assert nginx_address not in ipaddress.ip_network(ipam["ip_range"])


def test_the_dask_containers_share_the_service_image_but_not_its_health_check() -> None:
    services = compose()["services"]
    image = services["service"]["image"]
    assert "build" in services["service"]
    for name in ("dask-scheduler", "dask-worker"):
        assert services[name]["image"] == image and "build" not in services[name]  # built once, by `service`
        # The image's HEALTHCHECK asks the service's /health, which the scheduler and workers do not serve.
        check = services[name]["healthcheck"]
        assert check.get("disable") is True or "8787/health" in " ".join(check["test"])


def test_every_replicated_service_says_so_for_podman_compose() -> None:
    # podman-compose reads deploy.replicas only when deploy.mode is said (Docker takes it as the default).
    for name, service in compose()["services"].items():
        if "replicas" in service.get("deploy", {}):
            assert service["deploy"]["mode"] == "replicated", name
