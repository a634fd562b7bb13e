"""`causalplan objects ID`: the faults beside the parts and the mechanism."""

from __future__ import annotations

import json

from click.testing import CliRunner

from causalplan.cli import app

runner = CliRunner(env={"FORCE_COLOR": None, "NO_COLOR": "1", "COLUMNS": "200"})


def test_objects_shows_the_faults_with_their_priors_and_visibility() -> None:
    result = runner.invoke(app, ["objects", "desk_lamp"])
    assert result.exit_code == 0, result.output
    assert "Faults (illustrative priors)" in result.output
    bulb = next(line for line in result.output.splitlines() if "a burnt-out filament" in line)
    assert "light_bulb" in bulb and "0.7" in bulb and "yes" in bulb


def test_objects_json_gives_the_faults() -> None:
    result = runner.invoke(app, ["objects", "flashlight", "--json"])
    data = json.loads(result.output)
    assert data["fault_priors"] == "illustrative"
    assert {fault["part"] for fault in data["faults"]} == {"batteries", "head", "case"}
