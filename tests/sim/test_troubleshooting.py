"""A troubleshooting episode's last test in physics: the object rebuilt as the episode left it."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from causalplan.cli import app
from causalplan.objects.catalog import Catalog
from causalplan.sim.troubleshooting import repair_in_physics
from causalplan.troubleshoot.task import troubleshooting_task
from tests.sim.fixtures import SHADE_BEFORE_BULB, SPARE_SHADE_ONLY

LAMP = Path(__file__).resolve().parents[2] / "examples" / "paper" / "desk_lamp.yaml"


def test_the_desk_lamp_rebuilt_after_a_new_bulb_gives_light_in_physics(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    episode = troubleshooting_task(lamp).episode("oracle", "light_bulb")
    rebuilt = repair_in_physics(lamp, episode)
    assert rebuilt.order == ("base_with_cables", "light_bulb", "shade")
    assert rebuilt.fits == ("bulb_into_socket", "shade_onto_ring")
    assert rebuilt.report.passed and rebuilt.broken_part_replaced and rebuilt.produces_goal


def test_physics_refuses_a_rebuild_in_an_order_the_geometry_blocks(catalog: Catalog) -> None:
    # Shade back on before the bulb: physics finds the socket covered, whatever the catalog says.
    lamp = catalog.get("desk_lamp")
    rebuilt = repair_in_physics(lamp, SHADE_BEFORE_BULB)
    assert not rebuilt.produces_goal
    failed = rebuilt.report.failed_step
    assert failed is not None and failed.failure is not None and failed.failure.value == "blocked_path"


def test_a_lamp_to_light_is_lit_before_anything_covers_its_wick(catalog: Catalog) -> None:
    lamp = catalog.get("kerosene_lamp")
    episode = troubleshooting_task(lamp).episode("oracle", "wick")
    rebuilt = repair_in_physics(lamp, episode)
    assert rebuilt.fits.index("lighter_lights_wick") < rebuilt.fits.index("chimney_onto_burner")
    assert rebuilt.produces_goal


def test_a_broken_part_never_replaced_gives_no_goal_though_physics_builds_it(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    rebuilt = repair_in_physics(lamp, SPARE_SHADE_ONLY)
    assert rebuilt.report.passed and not rebuilt.broken_part_replaced and not rebuilt.produces_goal


@pytest.mark.slow
def test_every_episode_of_every_strategy_ends_with_the_goal_produced_in_physics(catalog: Catalog) -> None:
    for obj in catalog.objects.values():
        task = troubleshooting_task(obj)
        for strategy in task.strategies:
            for fault in obj.faults:
                rebuilt = repair_in_physics(obj, task.episode(strategy, fault.part))
                assert rebuilt.produces_goal, (obj.id, strategy, fault.part, rebuilt.as_dict())


def test_the_cli_checks_the_episode_in_physics() -> None:
    result = CliRunner().invoke(app, ["troubleshoot", str(LAMP), "--fault", "base_with_cables", "--physics", "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.output)
    assert data["status"] == "repaired" and data["physics"]["produces_goal"]
    assert data["physics"]["simulation"]["passed"]
    alone = CliRunner().invoke(app, ["troubleshoot", str(LAMP), "--all-faults", "--physics"])
    assert alone.exit_code == 2 and "missing_option" in alone.output
