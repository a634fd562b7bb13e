"""The catalog: the built-in objects, and a user's object files with clear errors."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from causalplan.errors import CatalogError, UnknownObjectError
from causalplan.objects.catalog import Catalog, load_catalog
from tests.conftest import EXAMPLES

DESIGN_PARTS = {
    "desk_lamp": {"shade", "light_bulb", "base_with_cables"},
    "flashlight": {"case", "head", "batteries"},
}


def test_the_paper_objects_and_a_tutorial_object_are_built_in(catalog: Catalog) -> None:
    assert {"desk_lamp", "flashlight", "candle", "kerosene_lamp"} <= set(catalog.objects)
    for object_id, parts in DESIGN_PARTS.items():
        assert set(catalog.get(object_id).part_ids) == parts
    assert {obj.category for obj in catalog.objects.values() if obj.goal == "light"} == {"electric", "combustion"}
    assert catalog.get("candle").category == catalog.get("kerosene_lamp").category == "combustion"
    tutorial = [obj for obj in catalog.objects.values() if obj.goal != "light"]
    assert [obj.id for obj in tutorial] == ["toy_car"]


def test_every_fit_joins_connectors_with_the_same_spec(catalog: Catalog) -> None:
    for obj in catalog.objects.values():
        specs = {(part.id, connector.id): connector.spec for part in obj.parts for connector in part.connectors}
        for fit in obj.fits:
            moving, fixed = fit.connectors()
            assert specs[moving] == specs[fixed], fit.id
            assert fit.probability == 1.0


def test_unknown_object_suggests_a_close_id(catalog: Catalog) -> None:
    with pytest.raises(UnknownObjectError, match="Did you mean 'desk_lamp'"):
        catalog.get("desk_lmp")


def _write_object(folder: Path, **changes: object) -> Path:
    base = yaml.safe_load((EXAMPLES / "catalog/bedside_lamp.yaml").read_text())
    base.update(changes)
    path = folder / "object.yaml"
    path.write_text(yaml.safe_dump(base))
    return path


def test_a_user_folder_adds_objects(tmp_path: Path) -> None:
    _write_object(tmp_path, id="my_lamp")
    assert "my_lamp" in load_catalog([tmp_path]).objects


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"id": "desk_lamp"}, "already defined"),
        ({"id": "Bad Id"}, "id"),
        ({"base": "nothing"}, "base 'nothing' is not one of the parts"),
        ({"category": None}, "category"),
        (
            {"fits": [{"id": "f", "primitive": "weld", "moving": "warm_bulb.thread", "fixed": "lamp_body.socket"}]},
            "unknown primitive 'weld'",
        ),
        (
            {"fits": [{"id": "f", "primitive": "screw", "moving": "warm_bulb.nope", "fixed": "lamp_body.socket"}]},
            "is not a 'part.connector'",
        ),
        (
            {
                "fits": [
                    {
                        "id": "f",
                        "primitive": "screw",
                        "moving": "warm_bulb.thread",
                        "fixed": "lamp_body.socket",
                        "probability": 0,
                    }
                ]
            },
            "greater than 0",
        ),
        (
            {
                "fits": [
                    {"id": "lamp_body", "primitive": "screw", "moving": "warm_bulb.thread", "fixed": "lamp_body.socket"}
                ]
            },
            "clash",
        ),
        ({"mechanism": {"explanation": "x", "requires": [{"any": ["nope"], "says": "y"}]}}, "unknown fit"),
        ({"parts": [{"id": "and", "name": "x", "connectors": []}], "base": "and", "fits": []}, "PDDL keyword"),
        ({"colour": "red"}, "Extra inputs"),
    ],
)
def test_a_bad_user_object_gets_a_clear_error(tmp_path: Path, changes: dict[str, object], message: str) -> None:
    _write_object(tmp_path, **changes)
    with pytest.raises(CatalogError, match=message) as error:
        load_catalog([tmp_path])
    assert "object.yaml" in str(error.value)


def test_connectors_with_different_specs_do_not_fit(tmp_path: Path) -> None:
    base = yaml.safe_load((EXAMPLES / "catalog/bedside_lamp.yaml").read_text())
    base["parts"][1]["connectors"][0]["spec"] = "E27"
    (tmp_path / "lamp.yaml").write_text(yaml.safe_dump(base))
    with pytest.raises(CatalogError, match="does not fit"):
        load_catalog([tmp_path])


def test_malformed_object_file_and_missing_folder(tmp_path: Path) -> None:
    (tmp_path / "bad.yaml").write_text("id: [unclosed\n")
    with pytest.raises(CatalogError, match="line"):
        load_catalog([tmp_path])
    with pytest.raises(CatalogError, match="does not exist"):
        load_catalog([tmp_path / "missing"])
