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


def test_the_oil_lamps_wick_lit_before_its_oil_does_not_burn(catalog: Catalog) -> None:
    lamp = catalog.get("oil_lamp")
    parts = solids(lamp)
    wick = mating_pose(parts["wick"].frames["stem"], parts["lamp_bowl"].frames["spout"])
    bottle = mating_pose(parts["oil_bottle"].frames["neck"], parts["lamp_bowl"].frames["filling_hole"])
    in_spout = Joint(1, "wick_into_spout", "wick", "stem", "lamp_bowl", "spout")
    with Scene(parts, drawn=False) as scene:
        scene.add_part("lamp_bowl", Pose(), dynamic=False)
        scene.add_part("wick", wick, dynamic=False)
        scene.add_part("oil_bottle", bottle, dynamic=False)
        scene.add_part("match", Pose((0.0, 0.3, 0.0)), dynamic=False)

        def judged(lit_at: int, oil_at: int) -> list[tuple[bool, str]]:
            lit = Joint(lit_at, "match_lights_wick", "match", "flame", "wick", "tip", touch_only=True)
            oil = Joint(oil_at, "bottle_into_filling_hole", "oil_bottle", "neck", "lamp_bowl", "filling_hole")
            return [(check.met, check.detail) for check in evaluate(lamp, scene, [in_spout, lit, oil])]

        lit_first, lit_last = judged(lit_at=2, oil_at=3), judged(lit_at=3, oil_at=2)
    assert [met for met, _ in lit_last] == [True, True, True]
    assert [met for met, _ in lit_first] == [True, True, False]
    assert lit_first[2][1].endswith(
        "but that was before 'stand the bottle of lamp oil neck down in the lamp bowl' (step 3), which must come first"
    )
