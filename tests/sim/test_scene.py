"""The PyBullet world: parts as bodies (more than 16 shapes too), welds, glass, one server per thread."""

from __future__ import annotations

import subprocess
import sys

import pytest

from causalplan.objects.catalog import Catalog
from causalplan.sim.geometry import solids
from causalplan.sim.poses import Pose, difference
from causalplan.sim.scene import Scene, load_pybullet


def test_pybullet_is_imported_without_its_banner() -> None:
    completed = subprocess.run(
        [sys.executable, "-c", "from causalplan.sim.scene import load_pybullet; load_pybullet()"],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    assert completed.stderr == "" and completed.stdout == ""


def test_a_part_with_more_than_16_shapes_keeps_them_all(catalog: Catalog) -> None:
    parts = solids(catalog.get("desk_lamp"))
    assert len(parts["shade"].shapes) > 16
    with Scene(parts, drawn=False) as scene:
        scene.add_part("shade", Pose(), dynamic=False)
        lower, upper = scene.bounds(["shade"])
        assert scene.pb.getNumJoints(scene.bodies["shade"], physicsClientId=scene.client) == 2
    # The whole cone is there: 22 cm across at the bottom, 13.4 cm high with its top.
    assert upper[0] - lower[0] == pytest.approx(0.22, abs=0.002)
    assert upper[2] - lower[2] == pytest.approx(0.134, abs=0.002)


def test_see_through_shapes_are_grouped_for_drawing(catalog: Catalog) -> None:
    with Scene(solids(catalog.get("desk_lamp"))) as scene:
        scene.add_part("shade", Pose(), dynamic=False)
        scene.add_part("light_bulb", Pose((0.3, 0.0, 0.0)), dynamic=False)
        assert {body for body, _, _ in scene.glass} == {scene.bodies["shade"]}
        assert all(color[3] < 1.0 for _, _, color in scene.glass)


def test_each_scene_starts_empty_on_the_same_server(catalog: Catalog) -> None:
    parts = solids(catalog.get("candle"))
    with Scene(parts, drawn=False) as first:
        first.add_part("wax", Pose(), dynamic=True)
        client = first.client
    with Scene(parts, drawn=False) as second:
        assert second.client == client
        assert second.pb.getNumBodies(physicsClientId=second.client) == 1  # the table only


def test_a_weld_holds_two_parts_where_they_were(catalog: Catalog) -> None:
    parts = solids(catalog.get("flashlight"))
    with Scene(parts, drawn=False) as scene:
        scene.add_part("case", Pose(), dynamic=True)
        scene.add_part("head", Pose((0.0, 0.0, 0.124)), dynamic=True)
        scene.weld("case", "head")
        before = scene.pose("case").inverse() * scene.pose("head")
        scene.settle(0.5)
        moved, turned = difference(before, scene.pose("case").inverse() * scene.pose("head"))
    assert moved < 0.0005 and turned < 0.005


def test_a_part_without_mass_stays_and_with_mass_falls(catalog: Catalog) -> None:
    with Scene(solids(catalog.get("candle")), drawn=False) as scene:
        scene.add_part("wick", Pose((0.0, 0.0, 0.2)), dynamic=False)
        scene.settle(0.1)
        assert scene.pose("wick").position[2] == pytest.approx(0.2)
        scene.set_dynamic("wick", True)
        scene.settle(0.1)
        assert scene.pose("wick").position[2] < 0.16


def test_load_pybullet_is_cached() -> None:
    assert load_pybullet() is load_pybullet()
