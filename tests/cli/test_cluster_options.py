"""Population, consensus, crowd curve and fit estimates on a Dask LocalCluster: the numbers of the local run."""

from __future__ import annotations

import json
import logging
from collections.abc import Iterator
from pathlib import Path

import pytest
from click.testing import CliRunner
from distributed import LocalCluster

from causalplan.cli import app
from causalplan.cli.cluster_options import ClusterChoice, chunk_mapper
from causalplan.sim.fit_estimates import estimate_fits
from causalplan.transfer.cluster import ClusterError, map_on_cluster
from tests.conftest import builtin_catalog

pytestmark = pytest.mark.slow  # each command starts a Dask cluster

runner = CliRunner(env={"FORCE_COLOR": None, "NO_COLOR": "1", "COLUMNS": "200"})
NO_ERRORS_BUT_A_MINORITY = [
    "--rate-non-causal",
    "0",
    "--rate-uncaused-intermediate",
    "0",
    "--rate-object-specific",
    "0.3",
    "--rate-missed-part",
    "0",
    "--rate-effect-as-cause",
    "0.3",
]


@pytest.fixture(scope="module")
def scheduler() -> Iterator[str]:
    """Return the address of a LocalCluster of two one-thread workers, shared by this module's tests."""
    with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None, silence_logs=logging.ERROR) as cluster:
        yield cluster.scheduler_address


def _population(path: Path, count: int, *tests: str) -> Path:
    made = runner.invoke(
        app,
        ["population", "desk_lamp", "--n", str(count), "--seed", "3", "--out", str(path), *NO_ERRORS_BUT_A_MINORITY]
        + [option for test in tests for option in ("--test", test)],
    )
    assert made.exit_code == 0, made.output
    return path


def test_map_on_cluster_keeps_the_items_order_and_reports_each_result(scheduler: str) -> None:
    seen: list[int] = []
    assert map_on_cluster(abs, [-3, 1, -2, 5], address=scheduler, on_result=seen.append) == [3, 1, 2, 5]
    assert sorted(seen) == [1, 2, 3, 5]


def test_a_task_that_fails_on_the_cluster_is_named(scheduler: str) -> None:
    with pytest.raises(ClusterError, match=r"Task 2 of 3 failed on the cluster: ValueError"):
        map_on_cluster(int, ["1", "one", "3"], address=scheduler)


def test_a_population_is_judged_by_batch_on_a_local_cluster_as_it_is_here(tmp_path: Path) -> None:
    crowd = _population(tmp_path / "crowd.jsonl", 6, "flashlight", "candle")
    common = ["batch", str(crowd), "--no-simulate", "--no-val"]
    here = runner.invoke(app, [*common, "--out", str(tmp_path / "here")])
    there = runner.invoke(app, [*common, "--workers", "1", "--chunk-size", "5", "--out", str(tmp_path / "there")])
    assert here.exit_code == 0 and there.exit_code == 0, there.output

    def verdicts(folder: str) -> list[tuple[str, str, str]]:
        rows = json.loads((tmp_path / folder / "verdicts.json").read_text())
        return [(row["id"], row["test_object"], row["verdict"]) for row in rows]

    assert len(verdicts("there")) == 12
    assert verdicts("there") == verdicts("here")
    assert {verdict for _, _, verdict in verdicts("here")} == {"transfers", "fails"}


def test_consensus_on_the_cluster_writes_the_report_it_writes_here(tmp_path: Path, scheduler: str) -> None:
    crowd = _population(tmp_path / "crowd.jsonl", 8, "flashlight", "candle")
    here = runner.invoke(app, ["consensus", str(crowd), "--no-simulate", "--out", str(tmp_path / "here")])
    there = runner.invoke(
        app,
        ["consensus", str(crowd), "--no-simulate", "--cluster", scheduler, "--chunk-size", "3", "--out", str(tmp_path)],
    )
    assert here.exit_code == there.exit_code == 0, there.output
    report = json.loads((tmp_path / "report.json").read_text())
    assert report == json.loads((tmp_path / "here" / "report.json").read_text())
    assert len(report["individual_verdicts"]) == 16
    assert 0.0 < report["individual_transfer_rate"] < 1.0  # a mixed crowd: the verdicts tell runs apart


def test_the_crowd_curve_on_the_cluster_is_the_curve_here(tmp_path: Path, scheduler: str) -> None:
    common = ["crowd-curve", "desk_lamp", "--sizes", "1,3", "--draws", "3", "--test", "candle"]
    common += NO_ERRORS_BUT_A_MINORITY
    here = runner.invoke(app, [*common, "--out", str(tmp_path / "here")])
    there = runner.invoke(app, [*common, "--cluster", scheduler, "--chunk-size", "4", "--out", str(tmp_path / "there")])
    assert here.exit_code == there.exit_code == 0, there.output
    points = json.loads((tmp_path / "there" / "curve.json").read_text())["points"]
    assert points == json.loads((tmp_path / "here" / "curve.json").read_text())["points"]
    assert [point["size"] for point in points] == [1, 3]


def test_fit_estimates_in_chunks_on_the_cluster_are_those_of_the_run_here(scheduler: str) -> None:
    lamp = builtin_catalog().get("desk_lamp")
    here = estimate_fits(lamp, trials=12, seed=3, fit_ids=("bulb_into_socket",))
    done: list[int] = []
    there = estimate_fits(
        lamp,
        trials=12,
        seed=3,
        fit_ids=("bulb_into_socket",),
        map_chunks=chunk_mapper(ClusterChoice(scheduler, None, 5)),
        chunk_size=5,
        progress=done.append,
    )
    assert there == here
    assert sorted(done) == [2, 5, 5]  # three chunks, each reported as it came
    assert 0 < here[0].successes < 12 and here[0].failures  # mixed outcomes: a shuffled noise would show


@pytest.mark.parametrize(
    "command",
    [
        ["consensus", "crowd.jsonl"],
        ["crowd-curve", "desk_lamp"],
        ["estimate-fits", "desk_lamp"],
    ],
)
def test_cluster_and_workers_together_are_refused_by_every_command(command: list[str]) -> None:
    result = runner.invoke(app, [*command, "--cluster", "tcp://127.0.0.1:9", "--workers", "2"])
    assert result.exit_code == 2
    assert "Give --cluster (an existing cluster) or --workers (a local one), not both." in result.output


@pytest.mark.parametrize("address", ["foo", "tcp://host", "tcp://host:port"])
def test_a_scheduler_address_without_a_port_is_refused_before_any_work(address: str) -> None:
    result = runner.invoke(app, ["crowd-curve", "--cluster", address])
    assert result.exit_code == 2
    assert "Invalid value for '--cluster'" in result.output and "looks like tcp://10.0.0.5:8786" in result.output


def test_a_chunk_size_without_a_cluster_is_refused() -> None:
    result = runner.invoke(app, ["estimate-fits", "desk_lamp", "--chunk-size", "10"])
    assert result.exit_code == 2
    assert "--chunk-size sizes the tasks of a cluster: give --cluster or --workers too." in result.output


def test_an_unreachable_scheduler_is_a_clear_error_of_the_command(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("causalplan.transfer.cluster.CONNECT_TIMEOUT", "1s")  # Dask retries until then
    crowd = _population(tmp_path / "crowd.jsonl", 2, "flashlight")
    result = runner.invoke(
        app, ["consensus", str(crowd), "--no-simulate", "--cluster", "tcp://127.0.0.1:9", "--out", str(tmp_path)]
    )
    assert result.exit_code == 2
    assert "cluster_error" in result.output and "Cannot reach the Dask scheduler at tcp://127.0.0.1:9" in result.output
