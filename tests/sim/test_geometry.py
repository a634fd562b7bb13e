"""Parts as solids: catalog geometry, the default cylinder, connector frames on faces, mating poses."""

from __future__ import annotations

import pytest

from causalplan.objects.catalog import Catalog
from causalplan.sim.geometry import DEFAULT_SIZE, Frame, bounds, centroid, mating_pose, solids
from causalplan.sim.poses import distance, scale


def test_a_part_without_geometry_is_a_cylinder_standing_on_its_origin(user_catalog: Catalog) -> None:
    body = solids(user_catalog.get("bedside_lamp"))["lamp_body"]
    assert not body.has_own_geometry
    assert [shape.kind for shape in body.shapes] == ["cylinder"]
    assert body.upper[2] - body.lower[2] == pytest.approx(DEFAULT_SIZE[2])
    assert body.lower[2] == pytest.approx(0.0)


def test_default_frames_put_attaching_connectors_below_and_the_others_on_top_then_sides(
    user_catalog: Catalog,
) -> None:
    parts = solids(user_catalog.get("worn_lamp"))
    base = parts["lamp_base"].frames
    assert base["worn_socket"].axis == (0.0, 0.0, 1.0)  # the first free face: the top
    assert base["spare_socket"].axis == (1.0, 0.0, 0.0)  # then the sides
    assert base["spare_socket"].position[0] == pytest.approx(DEFAULT_SIZE[0] / 2)
    adapter = parts["adapter"].frames
    assert adapter["plug"] == Frame((0.0, 0.0, 0.0), (0.0, 0.0, -1.0))  # attached by it: the bottom
    assert adapter["socket"].axis == (0.0, 0.0, 1.0)


def test_catalog_frames_are_kept(catalog: Catalog) -> None:
    lamp = solids(catalog.get("desk_lamp"))
    assert lamp["base_with_cables"].frames["socket"] == Frame((0.0, 0.0, 0.285), (0.0, 0.0, 1.0))
    assert lamp["shade"].has_own_geometry


def test_mating_puts_the_connectors_together_with_opposed_axes() -> None:
    moving = Frame((0.0, 0.0, 0.0), (0.0, 0.0, -1.0))
    fixed = Frame((0.02, 0.0, 0.1), (1.0, 0.0, 0.0))
    pose = mating_pose(moving, fixed, spin=0.7)
    assert distance(pose.apply(moving.position), fixed.position) == pytest.approx(0.0, abs=1e-12)
    assert pose.turn(moving.axis) == pytest.approx(scale(fixed.axis, -1.0))


def test_bounds_and_centre_of_a_part(catalog: Catalog) -> None:
    bulb = solids(catalog.get("desk_lamp"))["light_bulb"]
    lower, upper = bounds(bulb.shapes)
    assert lower[2] == pytest.approx(0.0) and upper[2] == pytest.approx(0.088)
    assert 0.0 < centroid(bulb.shapes)[2] < 0.088
    assert bulb.radius > 0.03
