"""POST /v1/simulations: the plan, the physics report and a picture of the result."""

from __future__ import annotations

import base64

import pytest
from fastapi.testclient import TestClient

from tests.service.fixtures import DESK_LAMP, FLASHLIGHT_MAPPING, error_of, with_unique_effect


@pytest.mark.slow
def test_a_model_is_planned_simulated_and_drawn(client: TestClient) -> None:
    response = client.post("/v1/simulations", json={"model": with_unique_effect(DESK_LAMP)})
    assert response.status_code == 200, response.text
    body = response.json()
    assert body["planning"]["status"] == "solved"
    assert body["simulation"]["produces_goal"] is True
    assert body["image"].startswith("data:image/png;base64,")
    assert base64.b64decode(body["image"].split(",", 1)[1])[:4] == b"\x89PNG"
    assert body["cached"] is False


def test_a_mapping_simulates_the_other_object_and_repeats_come_from_the_cache(client: TestClient) -> None:
    body = {"model": DESK_LAMP, "mapping": FLASHLIGHT_MAPPING, "picture": False}
    first = client.post("/v1/simulations", json=body).json()
    assert first["planning"]["object"] == "flashlight" and first["image"] is None
    assert first["simulation"]["produces_goal"] is True
    assert client.post("/v1/simulations", json=body).json()["cached"] is True


def test_an_invalid_model_is_a_422_with_the_cli_codes(client: TestClient) -> None:
    broken = {**DESK_LAMP, "rules": ["provide electricity light"]}
    response = client.post("/v1/simulations", json={"model": broken})
    assert "missing_causes_keyword" in str(error_of(response, 422))


def test_val_checks_the_simulated_plan_by_default_as_plans_do(client: TestClient) -> None:
    checked = client.post("/v1/simulations", json={"model": DESK_LAMP, "picture": False})
    plain = client.post("/v1/simulations", json={"model": DESK_LAMP, "picture": False, "validate": False})
    assert plain.status_code == checked.status_code == 200, checked.text
    assert checked.json()["planning"]["validated_by"] == {"replay": "valid", "val": "valid"}
    assert plain.json()["planning"]["validated_by"] == {"replay": "valid"}
    assert checked.json()["simulation"]["produces_goal"] is True
