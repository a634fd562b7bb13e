"""The robot as the last judge of a transfer, and the film the service shows."""

from __future__ import annotations

import dataclasses

import imageio.v3 as iio
import numpy as np
import pytest

from causalplan.caches import Caches
from causalplan.inputs import load_mapping, load_model
from causalplan.objects.catalog import load_catalog
from causalplan.planners.result import PlanStep
from causalplan.service.work.robot import robot_simulation
from causalplan.sim.outcomes import Failure
from causalplan.transfer.robot_verdict import (
    ROBOT_CANNOT_EXECUTE,
    robot_reason,
    robot_run,
    robot_transfer_verdict,
)
from causalplan.transfer.verdict import Verdict, transfer_verdict
from tests.conftest import EXAMPLES, builtin_catalog
from tests.sim.fixtures import PEG_BOARD, parsed_object, steps

pytestmark = pytest.mark.slow  # the Panda carries out and films plans

ROBOT = EXAMPLES / "robot"


def test_a_plan_the_robot_cannot_carry_out_fails_the_transfer_naming_the_step_and_code() -> None:
    catalog = load_catalog([ROBOT / "catalog"])
    model = load_model(ROBOT / "walled_plate.yaml", catalog)
    mapping = load_mapping(ROBOT / "long_bench_mapping.yaml", catalog)
    assert transfer_verdict(model, mapping, catalog).verdict is Verdict.TRANSFERS  # on paper and in physics
    verdict = robot_transfer_verdict(model, mapping, catalog)
    assert verdict.verdict is Verdict.FAILS and verdict.decided_by == "robot"
    reason = verdict.reasons[-1]
    assert reason.code == ROBOT_CANNOT_EXECUTE
    assert reason.labels == ("step 1", "unreachable")
    assert "cannot carry out step 1" in reason.message


def test_a_plan_the_robot_carries_out_still_transfers() -> None:
    catalog = builtin_catalog()
    model = load_model(EXAMPLES / "paper" / "desk_lamp.yaml", catalog)
    mapping = load_mapping(EXAMPLES / "paper" / "flashlight_mapping.yaml", catalog)
    verdict = robot_transfer_verdict(model, mapping, catalog)
    assert verdict.verdict is Verdict.TRANSFERS
    assert verdict.simulation is not None and verdict.simulation.robot and verdict.simulation.produces_goal


def test_a_planners_steps_and_the_requests_for_them_are_one_robot_run(process_caches: Caches) -> None:
    """The run is kept by the checked steps: a step's sentence, or its being a planner's, is not part of the key."""
    board = parsed_object(PEG_BOARD)
    planned = (PlanStep("insert", ("thin_peg", "board"), "thin_peg_into_hole", "Insert the thin peg into the board."),)
    first = robot_run(board, planned)
    assert robot_run(board, steps("insert thin_peg board thin_peg_into_hole")) is first
    assert robot_run(board, [planned[0]]) is first  # a list of the same steps too
    assert process_caches.stats()["robot_runs"] == {"size": 256, "entries": 1, "hits": 2, "misses": 1}


def test_the_film_of_the_robot_is_an_mp4_or_a_gif_of_every_frame() -> None:
    board = parsed_object(PEG_BOARD)
    plan = steps("insert thin_peg board thin_peg_into_hole")
    report, mp4 = robot_simulation(board, plan, "mp4", (160, 120))
    assert mp4 is not None and mp4[4:8] == b"ftyp" and report.produces_goal
    frames = iio.imread(mp4, index=None, extension=".mp4")
    assert frames.shape[1:] == (120, 160, 3) and len(frames) == len(report.video)
    _, gif = robot_simulation(board, plan, "gif", (160, 120))
    assert gif is not None and gif[:6] == b"GIF89a"


def test_the_last_frames_show_the_light_when_the_goal_is_produced() -> None:
    lamp = builtin_catalog().get("desk_lamp")
    report, _ = robot_simulation(lamp, steps("screw light_bulb base_with_cables bulb_into_socket"), "gif", (240, 180))

    def glowing(index: int) -> int:
        frame = report.video[index]
        pixels = np.frombuffer(frame.rgb, dtype=np.uint8).reshape(frame.height, frame.width, 3).astype(int)
        red, green, blue = pixels[..., 0], pixels[..., 1], pixels[..., 2]
        return int(((red > 240) & (green > 215) & (blue < 200) & (red - blue > 60)).sum())

    assert glowing(0) == 0
    assert glowing(-1) > 20


def test_a_run_the_motors_cannot_follow_is_a_reason_naming_their_step_and_code() -> None:
    desk_lamp = builtin_catalog().get("desk_lamp")
    screw = PlanStep("screw", ("light_bulb", "base_with_cables"), "bulb_into_socket", "Screw the bulb in.")
    driven = robot_run(desk_lamp, (screw,), motors=True)
    assert driven.motors is not None and robot_reason(driven) is None
    slipped = dataclasses.replace(
        driven, motors=dataclasses.replace(driven.motors, failure=Failure.GRASP_SLIPPED, step=1, message="it slid")
    )
    reason = robot_reason(slipped)
    assert reason is not None and reason.code == ROBOT_CANNOT_EXECUTE
    assert reason.labels == ("step 1", "grasp_slipped") and "motors" in reason.message
