"""The true mechanism judged on the simulated assembly: joints that still hold, joined to the base."""

from __future__ import annotations

from causalplan.objects.catalog import Catalog
from causalplan.sim.geometry import mating_pose, solids
from causalplan.sim.mechanism import Joint, evaluate, joined_to_base
from causalplan.sim.poses import Pose
from causalplan.sim.scene import Scene

BULB = Joint(1, "bulb_into_socket", "light_bulb", "thread", "base_with_cables", "socket")


def test_parts_are_joined_to_the_base_through_holding_joints() -> None:
    joints = [
        Joint(1, None, "b", "x", "a", "y"),
        Joint(2, None, "c", "x", "b", "y"),
        Joint(3, None, "e", "x", "d", "y"),
    ]
    assert joined_to_base("a", joints) == {"a", "b", "c"}


def test_a_seated_bulb_meets_the_requirement_and_a_loose_one_does_not(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    parts = solids(lamp)
    seat = mating_pose(parts["light_bulb"].frames["thread"], parts["base_with_cables"].frames["socket"])
    with Scene(parts, drawn=False) as scene:
        scene.add_part("base_with_cables", Pose(), dynamic=False)
        scene.add_part("light_bulb", seat, dynamic=False)
        (seated,) = evaluate(lamp, scene, [BULB])
        scene.place("light_bulb", seat.translated((0.01, 0.0, 0.0)))
        (loose,) = evaluate(lamp, scene, [BULB])
        (never,) = evaluate(lamp, scene, [])
    assert seated.met and seated.fit == "bulb_into_socket"
    assert "seated on the base with cables" in seated.detail
    assert not loose.met and "10.0 mm" in loose.detail
    assert not never.met and never.detail.startswith("never done")


def test_a_lit_wick_counts_only_when_it_stands_in_the_wax(catalog: Catalog) -> None:
    candle = catalog.get("candle")
    lit = Joint(2, "match_lights_wick", "match", "flame", "wick", "tip", touch_only=True)
    with Scene(solids(candle), drawn=False) as scene:
        for part in ("wax", "wick", "match"):
            scene.add_part(part, Pose((0.0, 0.3 if part != "wax" else 0.0, 0.0)), dynamic=False)
        standing, burning = evaluate(candle, scene, [lit])
    assert not standing.met
    assert not burning.met and "not joined to the wax" in burning.detail
