"""GET /v1/objects/{id}: the faults beside the parts, fits and mechanism."""

from __future__ import annotations

from fastapi.testclient import TestClient


def test_an_object_shows_its_faults(client: TestClient) -> None:
    data = client.get("/v1/objects/desk_lamp").json()
    assert data["fault_priors"] == "illustrative"
    assert data["faults"][0] == {
        "part": "light_bulb",
        "probability": 0.7,
        "looks": "a burnt-out filament",
        "visible": True,
    }
