"""The API as a typed client sees it: stable operation ids, shared components, every answer declared.

The slow test generates a client from ``/openapi.json`` with ``openapi-python-client`` (a tool
nobody here wrote) and uses it for a plan, a transfer, a simulation and a filmed job: a field
the service returns but the document does not declare would land in the client's
``additional_properties``, and an undeclared answer would not be parsed at all.
"""

from __future__ import annotations

import importlib
import json
import re
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest
import yaml
from fastapi.testclient import TestClient

from causalplan.service.api.schemas.jobs import JOB_EXAMPLES
from causalplan.service.main import create_app
from tests.service.fixtures import (
    DESK_LAMP,
    FAILED_DESK_LAMP,
    FAILED_FLASHLIGHT_MAPPING,
    FLASHLIGHT_MAPPING,
    running_client,
    settings_for,
    sqlite_url,
)

ROOT = Path(__file__).resolve().parents[3]
CLIENT_CONFIG = ROOT / "docs" / "openapi-python-client.yaml"
DOCUMENT = create_app(settings_for("sqlite://")).openapi()
OPERATIONS = [
    (method, path, operation) for path, methods in DOCUMENT["paths"].items() for method, operation in methods.items()
]
SNAKE_CASE = re.compile(r"^[a-z][a-z0-9]*(_[a-z0-9]+)*$")
ERROR_REF = {"$ref": "#/components/schemas/ErrorOut"}


def test_every_operation_has_a_unique_snake_case_id_that_is_its_routes_name() -> None:
    ids = [operation["operationId"] for _, _, operation in OPERATIONS]
    assert len(ids) == len(set(ids)), sorted(ids)
    assert all(SNAKE_CASE.match(operation_id) for operation_id in ids), ids
    # No path or method in an id: renaming a path must not rename a client's method.
    assert not [operation_id for operation_id in ids if re.search(r"_v1_|_(get|post|put|delete)$", operation_id)]
    assert {"create_plan", "create_transfer", "create_simulation", "create_job", "read_job", "read_job_video"} <= set(
        ids
    )


def test_the_documents_are_shared_components_not_copies_inlined_per_body() -> None:
    components = DOCUMENT["components"]["schemas"]
    assert {"ModelDocument", "MappingDocument"} <= set(components)
    inlined = [name for name in components if re.search(r".+(Model|Mapping)Document", name) or name.startswith("Body_")]
    assert not inlined
    model_ref = {"$ref": "#/components/schemas/ModelDocument"}
    plan_in = components["PlanIn"]["properties"]
    assert model_ref in plan_in["model"]["anyOf"]
    assert components["TransferIn"]["properties"]["mapping"] == {
        "$ref": "#/components/schemas/MappingDocument",
        "description": "The step-3 mapping of the new object's parts.",
    }
    create_model = DOCUMENT["paths"]["/v1/models"]["post"]["requestBody"]["content"]["application/json"]["schema"]
    assert create_model["$ref"] == model_ref["$ref"]


def test_every_answer_is_declared_with_a_schema_and_every_error_with_the_error_model() -> None:
    for method, path, operation in OPERATIONS:
        for status, answer in operation["responses"].items():
            content = answer.get("content")
            assert content, f"{method} {path} {status} declares no body"
            for media_type, declared in content.items():
                schema = declared.get("schema")
                assert schema, f"{method} {path} {status} {media_type} has no schema"
                if media_type == "application/json" and status.startswith(("4", "5")):
                    assert schema == ERROR_REF, f"{method} {path} {status}"
                if media_type == "application/json" and "$ref" not in str(schema):
                    # An open object would be an answer a client cannot type.
                    assert schema.get("type") not in (None, "object"), f"{method} {path} {status}: {schema}"


def test_films_are_declared_as_bytes_and_both_answers_of_a_simulation_are_typed() -> None:
    film = DOCUMENT["paths"]["/v1/jobs/{job_id}/video"]["get"]["responses"]["200"]["content"]
    assert film == {media: {"schema": {"type": "string", "format": "binary"}} for media in ("video/mp4", "image/gif")}
    simulation = DOCUMENT["paths"]["/v1/simulations"]["post"]["responses"]
    assert simulation["200"]["content"]["application/json"]["schema"] == {"$ref": "#/components/schemas/SimulationOut"}
    assert simulation["202"]["content"]["application/json"]["schema"] == {"$ref": "#/components/schemas/JobOut"}


def test_the_plan_and_transfer_fields_the_service_returns_are_declared() -> None:
    components = DOCUMENT["components"]["schemas"]
    plan = components["PlanOut"]
    assert {"success_probability", "expected_actions", "fallback_reason", "validated_by_up"} <= set(plan["required"])
    assert {"policy", "objective", "optimality", "success_probability_bounds", "fewest_attempts"} <= set(
        plan["properties"]
    )
    transfer = components["TransferOut"]["properties"]
    assert transfer["simulation"]["anyOf"][0] == {"$ref": "#/components/schemas/SimulationSummaryOut"}
    assert transfer["planning"]["anyOf"][0] == {"$ref": "#/components/schemas/PlanResultOut"}


# -- a generated client, used end to end --------------------------------------------------------------


def generate_client(folder: Path, document: dict[str, Any]) -> ModuleType:
    """Run openapi-python-client on ``document`` with the shipped configuration; import the package it made."""
    spec = folder / "openapi.json"
    spec.write_text(json.dumps(document))
    config: dict[str, Any] = yaml.safe_load(CLIENT_CONFIG.read_text())
    config_file = folder / "config.yaml"
    config_file.write_text(yaml.safe_dump({**config, "post_hooks": []}))  # no formatter needed to import it
    package = folder / "causalplan_api_client"
    command = [sys.executable, "-m", "openapi_python_client", "generate", "--path", str(spec)]
    command += ["--output-path", str(package), "--meta", "none", "--config", str(config_file)]
    run = subprocess.run(command, capture_output=True, text=True, timeout=120, check=False)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "Warning" not in run.stdout + run.stderr, run.stdout + run.stderr  # nothing of the API left out
    sys.path.insert(0, str(folder))
    try:
        return importlib.import_module("causalplan_api_client")
    finally:
        sys.path.remove(str(folder))


def undeclared_fields(value: Any, where: str = "answer") -> list[str]:
    """Return where a parsed answer holds fields its schema does not declare (in ``additional_properties``).

    A model made only of ``additional_properties`` is a declared map (e.g. ``timing``), not a miss.
    """
    found: list[str] = []
    if isinstance(value, list):
        for index, item in enumerate(value):
            found += undeclared_fields(item, f"{where}[{index}]")
    fields = getattr(type(value), "__attrs_attrs__", None)
    if fields is None:
        return found
    names = [field.name for field in fields if field.name != "additional_properties"]
    if names and value.additional_properties:
        found.append(f"{where}: {sorted(value.additional_properties)}")
    for name in names:
        found += undeclared_fields(getattr(value, name), f"{where}.{name}")
    return found


@pytest.fixture(scope="module")
def generated(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[ModuleType, TestClient]]:
    """The generated package and a running app (small films) whose TestClient the generated client sends through."""
    folder = tmp_path_factory.mktemp("client")
    settings = settings_for(
        sqlite_url(tmp_path_factory.mktemp("db")), job_poll_seconds=0.05, robot_video_width=96, robot_video_height=72
    )
    with running_client(settings) as running:
        yield generate_client(folder, running.get("/openapi.json").json()), running


def client_of(package: ModuleType, running: TestClient) -> Any:
    """Return the generated ``Client`` sending its requests to the running app."""
    return package.Client(base_url=str(running.base_url)).set_httpx_client(running)


def call(package: ModuleType, operation: str, running: TestClient, **arguments: Any) -> tuple[Any, int]:
    """Call a generated operation (``"<tag>.<operation id>"``); return its parsed answer and its status."""
    module = importlib.import_module(f"{package.__name__}.api.{operation}")
    response = module.sync_detailed(client=client_of(package, running), **arguments)
    return response.parsed, int(response.status_code)


def model(package: ModuleType, name: str) -> Any:
    return getattr(importlib.import_module(f"{package.__name__}.models"), name)


@pytest.mark.slow  # generates and imports a client, and films the robot
def test_a_generated_client_plans_transfers_simulates_and_follows_a_filmed_job(
    generated: tuple[ModuleType, TestClient],
) -> None:
    package, running = generated
    document = model(package, "ModelDocument").from_dict(DESK_LAMP)
    stored, status = call(package, "models.create_model", running, body=document)
    assert status == 201 and isinstance(stored, model(package, "ModelOut")) and stored.valid, stored
    graph, status = call(package, "models.read_model_graph", running, model_id=stored.id)
    assert status == 200 and isinstance(graph, str) and "<svg" in graph  # the default answer, not parsed as JSON

    plan_in = model(package, "PlanIn")

    plan, status = call(package, "plans.create_plan", running, body=plan_in.from_dict({"model": DESK_LAMP}))
    assert status == 200 and isinstance(plan, model(package, "PlanOut")), plan
    assert plan.status.value == "solved" and plan.plan_length == 1 and plan.plan[0].fit == "bulb_into_socket"
    assert plan.success_probability == 1.0 and plan.expected_actions == 1.0
    assert plan.fallback_reason is None and plan.validated_by_up is None
    assert plan.validated_by.additional_properties == {"replay": "valid", "val": "valid"}
    assert undeclared_fields(plan) == []

    mdp, _ = call(package, "plans.create_plan", running, body=plan_in.from_dict({"model": DESK_LAMP, "planner": "mdp"}))
    assert mdp.objective.value == "probability" and mdp.policy[0].attempt == "bulb_into_socket"
    assert undeclared_fields(mdp) == []

    transfer_in = model(package, "TransferIn")
    body = transfer_in.from_dict({"model": DESK_LAMP, "mapping": FLASHLIGHT_MAPPING})
    transfer, status = call(package, "transfers.create_transfer", running, body=body)
    assert status == 200 and isinstance(transfer, model(package, "TransferOut")), transfer
    assert transfer.verdict.value == "transfers" and transfer.planning.success_probability == 1.0
    assert isinstance(transfer.simulation, model(package, "SimulationSummaryOut")) and transfer.simulation.passed
    assert undeclared_fields(transfer) == []

    failing = {"model": FAILED_DESK_LAMP, "mapping": FAILED_FLASHLIGHT_MAPPING, "repair": True}
    failed, _ = call(package, "transfers.create_transfer", running, body=transfer_in.from_dict(failing))
    assert failed.verdict.value == "fails" and failed.planning is None and failed.repairs.found >= 1
    assert undeclared_fields(failed) == []

    simulation_in = model(package, "SimulationIn")
    simulation, status = call(
        package,
        "simulations.create_simulation",
        running,
        body=simulation_in.from_dict({"model": DESK_LAMP, "picture": True}),
    )
    assert status == 200 and isinstance(simulation, model(package, "SimulationOut")), simulation
    assert simulation.simulation.passed and simulation.simulation.steps[0].checks[0].passed
    assert simulation.image.startswith("data:image/png;base64,") and simulation.planning.plan_length == 1
    assert undeclared_fields(simulation) == []

    filmed = simulation_in.from_dict({"model": DESK_LAMP, "robot": True, "video": "mp4"})
    job, status = call(package, "simulations.create_simulation", running, body=filmed)
    assert status == 202 and isinstance(job, model(package, "JobOut")) and job.kind.value == "video", job
    job = finished(package, running, job)
    assert job.progress.done == job.progress.total > 0 and undeclared_fields(job) == []
    assert isinstance(job.result, model(package, "SimulationResultOut")) and job.result.robot.carried_out
    assert job.result.video.content_type == "video/mp4"

    film, status = call(package, "jobs.read_job_video", running, job_id=job.id)
    assert status == 200 and isinstance(film, importlib.import_module(f"{package.__name__}.types").File), film
    data = film.payload.read()
    assert isinstance(data, bytes) and data[4:8] == b"ftyp" and len(data) == job.result.video.bytes_


@pytest.mark.slow  # runs a job of each other kind
def test_a_generated_client_reads_each_kinds_result_typed(generated: tuple[ModuleType, TestClient]) -> None:
    package, running = generated
    results = {
        "batch": "BatchResultOut",
        "simulation": "SimulationResultOut",
        "consensus": "ConsensusResultOut",
        "fit_estimation": "FitEstimationResultOut",
    }
    for kind, result_model in results.items():
        request = {**JOB_EXAMPLES[kind]["value"], **({"trials": 3} if kind == "fit_estimation" else {})}
        body = model(package, f"{''.join(word.title() for word in kind.split('_'))}JobIn").from_dict(request)
        job, status = call(package, "jobs.create_job", running, body=body)
        assert status == 202 and job.kind.value == kind, job
        job = finished(package, running, job)
        assert isinstance(job.result, model(package, result_model)), (kind, job.result)
        assert undeclared_fields(job) == [], kind


def finished(package: ModuleType, running: TestClient, job: Any, seconds: float = 300.0) -> Any:
    """Poll a job through the generated client until it has finished; assert it succeeded; return it."""
    deadline = time.monotonic() + seconds
    while job.status.value in ("queued", "running") and time.monotonic() < deadline:
        time.sleep(0.2)
        job, status = call(package, "jobs.read_job", running, job_id=job.id)
        assert status == 200
    assert job.status.value == "succeeded", job
    return job
