"""GET /v1/objects, GET /v1/objects/{id}, GET /health, and errors for unknown routes and methods."""

from __future__ import annotations

from fastapi.testclient import TestClient

from causalplan.planners import pipeline
from tests.service.fixtures import error_of


def test_the_catalog_is_listed(client: TestClient) -> None:
    objects = client.get("/v1/objects").json()
    by_id = {obj["id"]: obj for obj in objects}
    assert {"desk_lamp", "flashlight", "candle", "kerosene_lamp", "toy_car"} <= set(by_id)
    assert by_id["desk_lamp"]["category"] == "electric"
    assert [part["id"] for part in by_id["flashlight"]["parts"]] == ["case", "head", "batteries"]


def test_one_object_in_full(client: TestClient) -> None:
    lamp = client.get("/v1/objects/desk_lamp").json()
    assert lamp["base"] == "base_with_cables"
    fits = {fit["id"]: fit for fit in lamp["fits"]}
    assert fits["bulb_into_socket"]["moving"] == "light_bulb.thread"
    assert fits["bulb_into_socket"]["text"] == "Screw the light bulb into the base with cables."
    assert fits["shade_onto_ring"]["blocks"] == ["base_with_cables.socket"]
    assert lamp["mechanism"]["requires"][0]["any_of"] == ["bulb_into_socket"]
    socket = next(c for p in lamp["parts"] if p["id"] == "base_with_cables" for c in p["connectors"])
    assert socket == {"id": "socket", "kind": "threaded socket", "spec": "E27"}


def test_an_unknown_object_is_404_with_a_suggestion(client: TestClient) -> None:
    error = error_of(client.get("/v1/objects/flashlite"), 404)
    assert error["code"] == "unknown_object"
    assert "Did you mean 'flashlight'?" in error["message"]


def test_health_reports_planners_database_pool_and_limits(client: TestClient) -> None:
    health = client.get("/health").json()
    assert health["status"] == "ok"
    assert [planner["name"] for planner in health["planners"]] == list(pipeline.PLANNERS)
    fd = next(planner for planner in health["planners"] if planner["name"] == "fd")
    assert fd == {"name": "fd", "available": True, "problem": None}
    assert health["fast_downward"]["available"] is True and health["fast_downward"]["problem"] is None
    assert "/" not in str(health["fast_downward"])  # no paths: /health says what runs, not where it lies
    assert health["fast_downward"]["versions"]["up-fast-downward"]
    assert isinstance(health["optional_backends_failed"], dict)
    assert health["database"] == {
        "reachable": True,
        "backend": "sqlite",
        "revision": "0011",
        "expected_revision": "0011",
        "problem": None,
    }
    assert health["pool"]["workers"] == 2 and health["pool"]["max_in_flight"] == 18
    assert health["limits"]["max_rules"] == 200 and health["limits"]["max_time_limit"] == 60.0
    assert set(health["cache"]) == {"size", "entries", "hits", "misses"}
    assert health["storage"]["free_mb"] > 0 and health["storage"]["problem"] is None


def test_unknown_routes_and_methods_have_the_error_shape(client: TestClient) -> None:
    error = error_of(client.get("/v1/nothing"), 404)
    assert error["code"] == "not_found" and "/docs" in error["message"]
    error = error_of(client.delete("/v1/objects"), 405)
    assert error["code"] == "method_not_allowed"


def test_the_openapi_document_describes_every_route_and_error(client: TestClient) -> None:
    spec = client.get("/openapi.json").json()
    assert set(spec["paths"]) == {
        "/v1/models",
        "/v1/models/{model_id}",
        "/v1/models/{model_id}/graph",
        "/v1/plans",
        "/v1/simulations",
        "/v1/transfers",
        "/v1/troubleshooting",
        "/v1/explanations",
        "/v1/jobs",
        "/v1/jobs/{job_id}",
        "/v1/jobs/{job_id}/video",
        "/v1/jobs/{job_id}/playback",
        "/v1/objects",
        "/v1/objects/{object_id}",
        "/v1/trials",
        "/v1/export",
        "/v1/experiments",
        "/v1/experiments/{experiment_id}",
        "/v1/experiments/{experiment_id}/participants",
        "/v1/experiments/{experiment_id}/results",
        "/v1/experiments/{experiment_id}/export",
        "/v1/experiments/{experiment_id}/export/shareable",
        "/v1/experiments/{experiment_id}/recruitment",
        "/health",
        "/health/ready",
    }
    plans = spec["paths"]["/v1/plans"]["post"]["responses"]
    assert {"200", "404", "413", "422", "429", "503", "504"} <= set(plans)
    assert plans["422"]["content"]["application/json"]["schema"] == {"$ref": "#/components/schemas/ErrorOut"}
    assert "HTTPValidationError" not in spec["components"]["schemas"]
    jobs = spec["paths"]["/v1/jobs"]["post"]["responses"]
    assert {"202", "413", "422", "429"} <= set(jobs) and "200" not in jobs
    assert {"200", "404", "409"} <= set(spec["paths"]["/v1/jobs/{job_id}"]["delete"]["responses"])
    assert client.get("/docs").status_code == 200
