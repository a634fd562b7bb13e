"""The primitives as motions: every primitive has one, and approaches start clear of the assembly."""

from __future__ import annotations

import pytest

from causalplan.objects.model import PRIMITIVE_TEXTS
from causalplan.sim.geometry import Frame
from causalplan.sim.motions import (
    APPROACH_MARGIN,
    MIN_APPROACH,
    MOTIONS,
    approach_path,
    approach_start,
    clearance,
)
from causalplan.sim.poses import Pose, distance

UP = (0.0, 0.0, 1.0)


def test_every_primitive_has_a_motion() -> None:
    assert set(MOTIONS) == set(PRIMITIVE_TEXTS)
    assert MOTIONS["screw"].turns > 0
    assert not MOTIONS["place"].fastens
    assert MOTIONS["ignite"].touches_only


def test_clearance_is_how_far_a_box_travels_to_leave_another() -> None:
    bulb = ((-0.03, -0.03, 0.28), (0.03, 0.03, 0.37))
    shade = ((-0.11, -0.11, 0.25), (0.11, 0.11, 0.39))
    assert clearance(bulb, shade, UP) == pytest.approx(0.11)
    assert clearance(bulb, ((1.0, 1.0, 1.0), (2.0, 2.0, 2.0)), UP) == 0.0
    assert approach_start(bulb, shade, UP) == pytest.approx(0.11 + APPROACH_MARGIN)
    assert approach_start(bulb, ((1.0, 1.0, 1.0), (2.0, 2.0, 2.0)), UP) == MIN_APPROACH


def test_an_approach_path_ends_at_the_seat_and_starts_along_the_axis() -> None:
    moving, fixed = Frame((0.0, 0.0, 0.0), (0.0, 0.0, -1.0)), Frame((0.0, 0.0, 0.2), UP)
    path = approach_path(Pose(), moving, fixed, MOTIONS["screw"])
    assert path(0.0).position == pytest.approx((0.0, 0.0, 0.2))
    assert path(0.1).position == pytest.approx((0.0, 0.0, 0.3))
    # A screw turns on the way in; an insert does not.
    assert distance(path(0.005).apply((0.01, 0.0, 0.0)), (0.01, 0.0, 0.205)) > 0.001
    straight = approach_path(Pose(), moving, fixed, MOTIONS["insert"])
    assert straight(0.005).apply((0.01, 0.0, 0.0)) == pytest.approx((0.01, 0.0, 0.205))
