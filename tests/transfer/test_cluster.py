"""Batches on a Dask LocalCluster: the same verdicts as the local batch, and a killed worker loses nothing."""

from __future__ import annotations

import json
import logging
import os
import signal
from pathlib import Path

import pytest
from distributed import Client, LocalCluster

from causalplan.objects.catalog import Catalog, load_catalog
from causalplan.transfer.batch import TrialResult, WrittenResult, read_trials, run_batch
from causalplan.transfer.cluster import (
    ClusterError,
    JudgeOptions,
    NumberedLines,
    chunks,
    connect,
    file_chunks,
    run_batch_on_cluster,
    trials_in,
    write_batch_on_cluster,
)
from tests.conftest import EXAMPLES

TRIALS = EXAMPLES / "batch" / "trials.jsonl"
OPTIONS = JudgeOptions(simulate=False)


@pytest.fixture(scope="module")
def catalog() -> Catalog:
    return load_catalog()


def _verdicts(results: list[TrialResult]) -> list[tuple[str, dict[str, object]]]:
    """Return each trial's verdict without what differs between runs (times, whether a cache answered)."""
    verdicts = []
    for result in results:
        data = result.verdict.as_dict()
        if isinstance(data.get("planning"), dict):
            data["planning"] = {k: v for k, v in data["planning"].items() if k not in ("timing", "cached")}
        verdicts.append((result.trial_id, data))
    return verdicts


def test_chunks_keep_every_trial_once_in_order() -> None:
    trials = list(read_trials(TRIALS))
    parts = chunks(trials, 7)
    assert [trial for part in parts for trial in part] == trials
    assert all(len(part) == 7 for part in parts[:-1])


def _written(results: list[WrittenResult]) -> list[tuple[dict[str, object], dict[str, object]]]:
    """Return each trial's CSV row and JSON verdict without what differs between runs."""
    written = []
    for result in results:
        data = json.loads(result.json_line)
        if isinstance(data.get("planning"), dict):
            data["planning"] = {k: v for k, v in data["planning"].items() if k not in ("timing", "cached")}
        written.append(({k: v for k, v in result.row.items() if k != "seconds"}, data))
    return written


def test_a_json_lines_file_is_cut_into_raw_lines_that_read_as_the_file_reads(tmp_path: Path) -> None:
    lines = tmp_path / "trials.jsonl"
    text = TRIALS.read_text(encoding="utf-8").splitlines()
    lines.write_bytes(b"\n".join([text[0].encode(), b"", b'{"id": "\xff"}', b"  \r", *(t.encode() for t in text[1:])]))
    parts = file_chunks(lines, 5)
    assert all(isinstance(part, NumberedLines) for part in parts)
    trials = [trial for part in parts if isinstance(part, NumberedLines) for trial in part.trials()]
    assert trials == list(read_trials(lines))
    assert trials_in(parts) == len(trials) == len(text) + 1  # the blank lines are no trials
    assert trials[1].problem == "Line 3 could not be read: it is not UTF-8 text (byte 8)."


def test_another_batch_file_is_read_by_the_client_and_cut_into_trials(tmp_path: Path) -> None:
    listing = tmp_path / "trials.json"
    listing.write_text(json.dumps([json.loads(line) for line in TRIALS.read_text().splitlines()[:3]]))
    parts = file_chunks(listing, 2)
    assert parts == chunks(list(read_trials(listing)), 2) and trials_in(parts) == 3
    with pytest.raises(ClusterError, match="at least 1; got 0"):
        file_chunks(listing, 0)


@pytest.mark.slow
def test_the_batch_commands_way_gives_the_rows_and_json_of_the_local_batch(catalog: Catalog) -> None:
    local = [result.written() for result in run_batch(list(read_trials(TRIALS)), catalog, simulate=False)]
    seen: list[int] = []
    on_cluster = write_batch_on_cluster(
        file_chunks(TRIALS, 8), catalog, OPTIONS, workers=2, on_chunk=lambda results: seen.append(len(results))
    )
    assert _written(on_cluster) == _written(local)
    assert sorted(seen) == sorted([8] * 5 + [2])


@pytest.mark.slow
def test_a_local_cluster_gives_the_verdicts_of_the_local_batch(catalog: Catalog) -> None:
    trials = list(read_trials(TRIALS))
    local = run_batch(trials, catalog, simulate=False)
    seen: list[int] = []
    on_cluster = run_batch_on_cluster(
        trials, catalog, OPTIONS, workers=2, chunk_size=9, on_chunk=lambda results: seen.append(len(results))
    )
    assert _verdicts(on_cluster) == _verdicts(local)
    assert sum(seen) == len(trials)


@pytest.mark.slow
@pytest.mark.parametrize("way", ["run_batch_on_cluster", "write_batch_on_cluster"])
def test_a_worker_killed_mid_batch_loses_nothing_and_counts_nothing_twice(
    catalog: Catalog, way: str, tmp_path: Path
) -> None:
    four_times = tmp_path / "trials.jsonl"
    four_times.write_bytes(TRIALS.read_bytes() * 4)
    trials = list(read_trials(four_times))
    local = run_batch(trials, catalog, simulate=False)
    with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None, silence_logs=logging.ERROR) as cluster:
        with Client(cluster) as watcher:
            pids = list(watcher.run(os.getpid).values())
        killed: list[int] = []

        def kill_one_worker(results: object) -> None:
            if not killed:
                killed.append(pids[0])
                os.kill(pids[0], signal.SIGKILL)

        address = cluster.scheduler_address
        if way == "run_batch_on_cluster":
            on_cluster = run_batch_on_cluster(
                trials, catalog, OPTIONS, address=address, chunk_size=3, on_chunk=kill_one_worker
            )
            assert _verdicts(on_cluster) == _verdicts(local)
        else:
            written = write_batch_on_cluster(
                file_chunks(four_times, 3), catalog, OPTIONS, address=address, on_chunk=kill_one_worker
            )
            assert _written(written) == _written([result.written() for result in local])
    assert killed


def test_an_unreachable_scheduler_is_a_clear_error(catalog: Catalog, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("causalplan.transfer.cluster.CONNECT_TIMEOUT", "1s")  # Dask retries until then
    with pytest.raises(ClusterError, match=r"Cannot reach the Dask scheduler at tcp://127\.0\.0\.1:9"):
        run_batch_on_cluster([], catalog, address="tcp://127.0.0.1:9")


@pytest.mark.slow
def test_the_batch_command_on_two_local_workers_writes_what_a_local_run_writes(tmp_path: Path) -> None:
    from click.testing import CliRunner

    from causalplan.cli import app

    runner = CliRunner()
    local = runner.invoke(app, ["batch", str(TRIALS), "--no-simulate", "--no-val", "--out", str(tmp_path / "local")])
    on_cluster = runner.invoke(
        app,
        [
            "batch",
            str(TRIALS),
            "--no-simulate",
            "--no-val",
            "--workers",
            "2",
            "--chunk-size",
            "10",
            "--out",
            str(tmp_path / "cluster"),
        ],
    )
    assert local.exit_code == 0 and on_cluster.exit_code == 0, on_cluster.output
    local_rows = (tmp_path / "local" / "verdicts.csv").read_text().splitlines()
    cluster_rows = (tmp_path / "cluster" / "verdicts.csv").read_text().splitlines()
    assert [row.rsplit(",", 1)[0] for row in cluster_rows] == [row.rsplit(",", 1)[0] for row in local_rows]
    streamed = (tmp_path / "cluster" / "verdicts.jsonl").read_text().splitlines()
    assert sorted(json.loads(line)["id"] for line in streamed) == sorted(row.split(",")[0] for row in local_rows[1:])
    assert "verdicts.jsonl" in " ".join(on_cluster.output.split()) and "verdicts.jsonl" not in local.output


def test_cluster_and_workers_together_are_refused(tmp_path: Path) -> None:
    from click.testing import CliRunner

    from causalplan.cli import app

    result = CliRunner().invoke(app, ["batch", str(TRIALS), "--cluster", "tcp://127.0.0.1:9", "--workers", "2"])
    assert result.exit_code == 2
    assert "not both" in result.output


@pytest.mark.slow
def test_two_local_clusters_at_once_start_without_a_port_warning(recwarn: pytest.WarningsRecorder) -> None:
    first, first_cluster = connect(None, 1)
    second, second_cluster = connect(None, 1)
    try:
        assert first.scheduler_info()["address"] != second.scheduler_info()["address"]
    finally:
        for client, cluster in ((first, first_cluster), (second, second_cluster)):
            client.close()  # type: ignore[no-untyped-call]
            cluster.close()
    assert not [warning for warning in recwarn if "already in use" in str(warning.message)]
