"""The registry of work: every entry a picklable function with typed arguments, its pool and its time limit."""

from __future__ import annotations

import dataclasses
import pickle
from pathlib import Path
from typing import Any, TypeVar

import pytest

from causalplan.causal.model import CausalModel, Labelling
from causalplan.objects.catalog import Catalog
from causalplan.service.work import registry
from causalplan.service.work.batches import ConsensusArguments, FitEstimateArguments, TrialsArguments
from causalplan.service.work.planning import (
    ExplanationArguments,
    PlanArguments,
    RepairArguments,
    SimulationArguments,
    TransferArguments,
)
from causalplan.service.work.registry import WORK, Pool
from causalplan.service.work.robot import PlanFilmArguments
from causalplan.settings import Settings
from tests.conftest import example_mapping, example_model

A = TypeVar("A")
SETTINGS = Settings(database_url="sqlite://", solve_grace_seconds=2.0, robot_seconds=50.0)
LIMIT = 10.0


@pytest.fixture(scope="module")
def model_and_mapping(catalog: Catalog) -> tuple[CausalModel, Labelling]:
    return example_model("paper/desk_lamp.yaml", catalog), example_mapping("paper/flashlight_mapping.yaml", catalog)


def test_every_entry_is_named_by_its_name_and_crosses_to_a_worker() -> None:
    assert len(WORK) == 17
    for name, work in WORK.items():
        assert work.name == name
        assert pickle.loads(pickle.dumps(work.function)) is work.function  # sent by reference
        assert dataclasses.is_dataclass(work.arguments) and work.arguments.__dataclass_params__.frozen  # type: ignore[attr-defined]


def test_each_pool_has_its_work() -> None:
    pools = {pool: sorted(name for name, work in WORK.items() if work.pool is pool) for pool in Pool}
    assert pools == {
        Pool.INTERACTIVE: [
            "assembly_picture",
            "explanation",
            "part_pictures",
            "plan",
            "repairs",
            "robot_playback",
            "simulation",
            "transfer",
            "troubleshooting",
        ],
        Pool.JOBS: [
            "consensus",
            "film_of_fits",
            "film_of_plan",
            "fit_estimate",
            "judged_trials",
            "queued_simulation",
            "queued_troubleshooting",
        ],
        Pool.ISOLATED: ["probe"],
    }
    kept = sorted(name for name, work in WORK.items() if work.is_final is not None)
    assert kept == ["plan", "simulation", "transfer", "troubleshooting"]


def test_time_limits_follow_the_request_and_the_settings(model_and_mapping: tuple[CausalModel, Labelling]) -> None:
    model, mapping = model_and_mapping
    solve = LIMIT + SETTINGS.solve_grace_seconds

    def seconds(work: registry.Work[A, Any], arguments: A) -> float:
        return work.seconds(arguments, SETTINGS)

    assert seconds(registry.PLAN, PlanArguments(model, None, "fd", LIMIT)) == solve
    assert seconds(registry.TRANSFER, TransferArguments(model, mapping, "fd", LIMIT)) == solve
    assert seconds(registry.TRANSFER, TransferArguments(model, mapping, "fd", LIMIT, robot=True)) == solve + 50.0
    simulation = SimulationArguments(model, None, "fd", LIMIT, picture=True)
    assert seconds(registry.SIMULATION, simulation) == solve + registry.SIMULATION_SECONDS
    assert seconds(registry.QUEUED_SIMULATION, simulation) == solve
    assert seconds(registry.QUEUED_SIMULATION, dataclasses.replace(simulation, robot=True)) == solve + 50.0
    assert seconds(registry.EXPLANATION, ExplanationArguments(model, None, "fd", LIMIT, "1", None)) == 2 * LIMIT + 2.0
    assert seconds(registry.REPAIRS, RepairArguments(model, mapping, "fd", LIMIT, seconds=7.0)) == 7.0 + 2.0
    film = PlanFilmArguments(model, None, "fd", LIMIT, False, "mp4", (160, 120), Path("progress.json"))
    assert seconds(registry.FILM_OF_PLAN, film) == solve + 50.0
    fit = FitEstimateArguments("desk_lamp", "bulb_into_socket", 200, 1, 1.0, 2.0)
    assert seconds(registry.FIT_ESTIMATE, fit) == pytest.approx(50.0 + 200 * registry.TRIAL_SECONDS)
    assert seconds(registry.JUDGED_TRIALS, TrialsArguments((), "fd", LIMIT, False)) == 0.0
    consensus = ConsensusArguments("{}\n{}\n", 2, 0.5, "fd", LIMIT, False)
    assert seconds(registry.CONSENSUS, consensus) == (2 + 8) * solve + registry.CONSENSUS_GRACE_SECONDS
