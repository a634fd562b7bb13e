"""Part geometry in catalog files: the schema's checks, colours, rotations, and tubes made of boxes."""

from __future__ import annotations

import math

import pytest
from pydantic import ValidationError

from causalplan.errors import CatalogError
from causalplan.objects.catalog import Catalog, parse_object
from causalplan.objects.schema import ConnectorSchema, ShapeSchema
from causalplan.objects.shapes import build_shapes, matrix_from_rpy, parse_color, rpy_from_matrix, tube_boxes
from tests.sim.fixtures import PEG_BOARD


def test_colours_with_and_without_alpha() -> None:
    assert parse_color("#ff0000") == (1.0, 0.0, 0.0, 1.0)
    assert parse_color("#00000080") == (0.0, 0.0, 0.0, pytest.approx(128 / 255))


@pytest.mark.parametrize("rpy", [(0.0, 0.0, 0.0), (0.3, -0.4, 1.2), (-1.0, 0.2, 3.0)])
def test_rotation_matrix_round_trips(rpy: tuple[float, float, float]) -> None:
    assert rpy_from_matrix(matrix_from_rpy(*rpy)) == pytest.approx(rpy)


def test_a_tube_is_a_closed_ring_of_staves() -> None:
    staves = tube_boxes(radius=0.05, top_radius=0.05, length=0.1, thickness=0.004, segments=12)
    assert len(staves) == 12
    for size, position, _ in staves:
        assert size[0] == pytest.approx(0.004) and size[2] == pytest.approx(0.1)
        assert math.hypot(position[0], position[1]) == pytest.approx(0.048)
    # Neighbouring staves meet: a stave is at least as wide as the chord between two of them.
    assert staves[0][0][1] >= 2 * 0.05 * math.sin(math.pi / 12)


def test_a_cone_leans_its_staves_inwards() -> None:
    (size, _, (_, pitch, _)), *_ = tube_boxes(radius=0.1, top_radius=0.06, length=0.1, thickness=0.004, segments=8)
    assert pitch < 0
    assert size[2] == pytest.approx(math.hypot(0.1, 0.04))


def test_a_turned_tube_turns_its_staves_with_it() -> None:
    shapes = build_shapes(ShapeSchema(shape="tube", radius=0.02, length=0.1, thickness=0.002, turn=(90.0, 0.0, 0.0)))
    assert len(shapes) == 12
    assert all(abs(shape.position[1]) < 0.021 for shape in shapes)  # the ring now lies across y...
    assert max(abs(shape.position[2]) for shape in shapes) == pytest.approx(0.019)  # ...and around x


@pytest.mark.parametrize(
    ("fields", "words"),
    [
        ({"shape": "box"}, "a box needs size"),
        ({"shape": "sphere", "radius": 0.1, "length": 0.2}, "a sphere does not use length"),
        ({"shape": "tube", "radius": 0.01, "length": 0.1, "thickness": 0.02}, "thickness must be less"),
        ({"shape": "cone", "radius": 0.1}, "'box', 'cylinder', 'sphere' or 'tube'"),
        ({"shape": "box", "size": [0.1, 0.1, 0.0]}, "greater than or equal to 0.0001"),
        ({"shape": "box", "size": [0.1, 0.1, 0.1], "color": "red"}, "String should match pattern"),
    ],
)
def test_shape_errors_say_what_is_wrong(fields: dict[str, object], words: str) -> None:
    with pytest.raises(ValidationError, match=words):
        ShapeSchema.model_validate(fields)


def test_a_connector_axis_cannot_be_zero_or_not_a_number() -> None:
    with pytest.raises(ValidationError, match="must not be"):
        ConnectorSchema(id="c", kind="k", spec="s", axis=(0.0, 0.0, 0.0))
    with pytest.raises(ValidationError, match="less than or equal"):
        ConnectorSchema(id="c", kind="k", spec="s", axis=(math.nan, 0.0, 1.0))


def test_angles_and_sizes_refuse_infinity() -> None:
    with pytest.raises(ValidationError):
        ShapeSchema(shape="sphere", radius=0.1, turn=(math.inf, 0.0, 0.0))
    with pytest.raises(ValidationError):
        ShapeSchema(shape="sphere", radius=math.nan)


def test_catalog_files_carry_geometry_and_unit_axes() -> None:
    board = parse_object(PEG_BOARD, "peg_board.yaml")
    assert board.part("board").geometry is not None
    assert len(board.part("board").geometry.shapes) == 5
    assert board.part("thin_peg").connectors[0].axis == (0.0, 0.0, -1.0)
    assert board.part("thin_peg").connectors[0].position == (0.0, 0.0, 0.0)


def test_an_object_file_with_a_bad_shape_names_the_file_and_field() -> None:
    text = PEG_BOARD.replace("{shape: box, size: [0.1, 0.1, 0.01], at: [0, 0, 0.005]}", "{shape: box, radius: 1}")
    with pytest.raises(CatalogError, match=r"peg_board.yaml: parts > 0 > geometry > shapes > 0"):
        parse_object(text, "peg_board.yaml")


def test_every_builtin_part_has_geometry_and_every_connector_a_frame(catalog: Catalog) -> None:
    for obj in catalog.objects.values():
        for part in obj.parts:
            assert part.geometry is not None, (obj.id, part.id)
            assert all(c.position is not None and c.axis is not None for c in part.connectors), (obj.id, part.id)


def test_the_light_of_each_light_producing_object_is_drawn_by_some_part(catalog: Catalog) -> None:
    for obj in catalog.objects.values():
        if obj.goal == "light":
            assert any(part.geometry and part.geometry.light for part in obj.parts), obj.id
