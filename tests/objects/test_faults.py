"""The catalog's faults: which part can be broken, its prior, and whether inspection shows it."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from causalplan.errors import CatalogError
from causalplan.objects.catalog import Catalog, parse_object

DATA = Path(__file__).resolve().parents[2] / "causalplan" / "objects" / "data"


def test_every_catalog_object_lists_illustrative_faults_that_sum_to_one(catalog: Catalog) -> None:
    assert len(catalog.objects) == 9
    for obj in catalog.objects.values():
        assert obj.fault_priors == "illustrative", obj.id
        assert obj.faults, obj.id
        assert sum(fault.probability for fault in obj.faults) == pytest.approx(1.0), obj.id
        assert all(obj.is_needed(fault.part) for fault in obj.faults), obj.id
        assert "ILLUSTRATIVE" in (DATA / f"{obj.id}.yaml").read_text(encoding="utf-8")


def test_a_part_is_needed_only_when_every_way_of_some_requirement_uses_it(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    assert [lamp.is_needed(part) for part in ("base_with_cables", "light_bulb", "shade")] == [True, True, False]
    lantern = catalog.get("solar_lantern")  # the panel or the crank charges the battery: neither alone is needed
    assert not lantern.is_needed("solar_panel") and not lantern.is_needed("crank_handle")
    assert lantern.is_needed("body") and lantern.is_needed("led_lamp")


def _desk_lamp_with(faults: object) -> str:
    data = yaml.safe_load((DATA / "desk_lamp.yaml").read_text(encoding="utf-8"))
    data["faults"] = faults
    return yaml.safe_dump(data)


@pytest.mark.parametrize(
    ("parts", "message"),
    [
        ([{"part": "shade", "probability": 1.0, "looks": "torn", "visible": True}], "does not need shade"),
        ([{"part": "lid", "probability": 1.0, "looks": "gone", "visible": True}], "lid is not a part"),
        (
            [
                {"part": "light_bulb", "probability": 0.5, "looks": "burnt", "visible": True},
                {"part": "base_with_cables", "probability": 0.4, "looks": "broken", "visible": False},
            ],
            "sum to 0.9, not 1",
        ),
        (
            [
                {"part": "light_bulb", "probability": 0.5, "looks": "burnt", "visible": True},
                {"part": "light_bulb", "probability": 0.5, "looks": "loose", "visible": True},
            ],
            "light_bulb listed twice",
        ),
    ],
)
def test_faults_that_cannot_be_are_refused_with_the_reason(parts: list[dict[str, object]], message: str) -> None:
    with pytest.raises(CatalogError, match=message):
        parse_object(_desk_lamp_with({"priors": "illustrative", "parts": parts}), "lamp.yaml")


def test_the_priors_must_say_where_they_come_from() -> None:
    fault = {"part": "light_bulb", "probability": 1.0, "looks": "burnt", "visible": True}
    with pytest.raises(CatalogError, match="priors"):
        parse_object(_desk_lamp_with({"priors": "guessed", "parts": [fault]}), "lamp.yaml")
    obj = parse_object(_desk_lamp_with({"priors": "measured", "parts": [fault]}), "lamp.yaml")
    assert obj.fault_priors == "measured" and obj.faults[0].visible
