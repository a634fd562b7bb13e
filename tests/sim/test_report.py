"""The simulation report: its JSON shape, its one-line explanation, and the short form for verdicts."""

from __future__ import annotations

import json

from causalplan.objects.catalog import Catalog
from causalplan.sim import RenderMode, simulate_plan
from causalplan.sim.checks import TOLERANCES
from tests.sim.fixtures import CORRECT_PLANS, steps


def test_a_passing_report_as_json(catalog: Catalog) -> None:
    report = simulate_plan(catalog.get("candle"), CORRECT_PLANS["candle"], render=RenderMode.NONE)
    data = json.loads(json.dumps(report.as_dict()))
    assert set(data) == {
        "object", "passed", "produces_goal", "stable", "explanation", "steps", "stability", "mechanism",
        "tolerances", "arm", "timing_ms",
    }  # fmt: skip
    assert data["passed"] and data["explanation"] == ""
    assert data["tolerances"] == TOLERANCES
    first = data["steps"][0]
    assert first["args"] == ["wick", "wax"] and first["status"] == "passed" and first["failure"] is None
    assert {check["name"] for check in first["checks"]} >= {"connectors", "path", "contact", "alignment"}
    assert all(check["passed"] for step in data["steps"] for check in step["checks"])
    assert set(data["timing_ms"]) == {"scene", "steps", "settle", "mechanism"}
    assert report.summary() == {
        "passed": True,
        "produces_goal": True,
        "stable": True,
        "failed_step": None,
        "failure": None,
        "unmet_requirements": [],
        "explanation": "",
    }


def test_a_failing_report_explains_itself(catalog: Catalog) -> None:
    report = simulate_plan(
        catalog.get("desk_lamp"),
        steps("clip shade base_with_cables shade_onto_ring", "screw light_bulb base_with_cables bulb_into_socket"),
        render=RenderMode.NONE,
    )
    summary = report.summary()
    assert (summary["failed_step"], summary["failure"], summary["passed"]) == (2, "blocked_path", False)
    assert summary["unmet_requirements"] == ["the light bulb is screwed into the socket of the base"]
    explanation = report.explanation()
    assert explanation.startswith("step 2 (Screw the light bulb into the base with cables.) failed: ")
    assert "no light, because not: the light bulb is screwed into the socket of the base" in explanation
