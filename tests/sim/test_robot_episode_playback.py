"""The 3D player's document of a robot's troubleshooting episode."""

from __future__ import annotations

import pytest

from causalplan.objects.catalog import Catalog
from causalplan.service.api.schemas.playback import EpisodePlaybackOut
from causalplan.sim.robot_episode import robot_episode
from causalplan.sim.robot_episode_playback import episode_playback
from tests.sim.fixtures import SHADE_BEFORE_BULB


def test_a_run_that_stops_short_plays_up_to_the_action_the_robot_could_not_do(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    run = robot_episode(lamp, SHADE_BEFORE_BULB, tracks=True)
    document = EpisodePlaybackOut.model_validate(episode_playback(lamp, run, SHADE_BEFORE_BULB))
    played = [(action.action, action.part, action.passed) for action in document.actions]
    assert played == [
        ("detach", "shade", True),
        ("detach", "light_bulb", True),
        ("replace", "light_bulb", True),
        ("attach", "shade", True),
        ("attach", "light_bulb", False),  # the socket is covered: the run stops here
    ]
    assert document.actions[-1].message.startswith("the light bulb blocked by the shade")
    assert document.actions[-1].end == pytest.approx(document.seconds)  # the run's commands stop with it
