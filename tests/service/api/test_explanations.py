"""POST /v1/explanations, and the repairs a transfer's answer carries when asked."""

from __future__ import annotations

from fastapi.testclient import TestClient

from tests.service.fixtures import DESK_LAMP, FAILED_DESK_LAMP, FAILED_FLASHLIGHT_MAPPING, FLASHLIGHT_MAPPING, error_of


def test_why_not_the_shade_before_the_bulb(client: TestClient) -> None:
    response = client.post(
        "/v1/explanations",
        json={"model": FAILED_DESK_LAMP, "why_not": "shade before light_bulb", "why": "2", "validate": True},
    )
    assert response.status_code == 200, response.text
    body = response.json()
    assert body["why_not"]["code"] == "blocked"
    assert body["why_not"]["decided_by"]["fit"] == "shade_onto_ring"
    assert [why["part"] for why in body["why"]] == ["shade"]
    assert body["plan"]["validated_by"] == {"replay": "valid", "val": "valid"}
    assert body["model_id"]


def test_the_alternative_plan_is_validated(client: TestClient) -> None:
    body = client.post(
        "/v1/explanations", json={"model": DESK_LAMP, "why_not": "attach shade", "validate": True}
    ).json()
    assert body["why_not"]["code"] == "not_needed"
    assert body["why_not"]["alternative"]["validated_by"] == {"replay": "valid", "val": "valid"}


def test_a_part_the_object_does_not_have_is_a_422(client: TestClient) -> None:
    response = client.post("/v1/explanations", json={"model": FAILED_DESK_LAMP, "why_not": "attach batteries"})
    error = error_of(response, 422)
    assert error["code"] == "unknown_part"
    assert "no part 'batteries'" in error["message"]


def test_a_failed_transfer_carries_its_repairs_when_asked(client: TestClient) -> None:
    asked = {"model": FAILED_DESK_LAMP, "mapping": FAILED_FLASHLIGHT_MAPPING, "repair": True}
    body = client.post("/v1/transfers", json=asked).json()
    assert body["verdict"] == "fails"
    repairs = body["repairs"]
    assert repairs["found"] >= 1 and repairs["repairs"][0]["verdict"] == "transfers"
    assert repairs["complete"] is True  # well within its budget (CAUSALPLAN_SEARCH_SECONDS)
    plain = client.post("/v1/transfers", json={**asked, "repair": False}).json()
    assert plain["repairs"] is None


def test_a_transfer_that_works_has_no_repairs(client: TestClient) -> None:
    body = client.post("/v1/transfers", json={"model": DESK_LAMP, "mapping": FLASHLIGHT_MAPPING, "repair": True}).json()
    assert (body["verdict"], body["repairs"]) == ("transfers", None)
