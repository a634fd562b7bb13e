"""Batches on Dask: ``causalplan batch`` on 1 and 2 local workers against the plain local batch.

    python benchmarks/cluster.py                   # 100,000 trials (the issue's size)
    python benchmarks/cluster.py --trials 5000     # a quick look
    python benchmarks/cluster.py --trials-file F   # any batch file instead (e.g. benchmarks/batch.py --keep F)

What is timed is the user's job: one ``causalplan batch TRIALS.jsonl --no-simulate --no-val``
process from start to exit (trials read, judged, verdicts.csv and verdicts.json written): plain,
with ``--workers 1`` and with ``--workers 2``, in that order, in rounds (``--rounds``, default 3);
each figure is the median of its rounds. Rounds, not one run each, because on these shared
machines the speed of a core drifts within minutes: three runs in a row measure the drift as
much as the code. The cluster runs include what a user of ``--workers`` waits for: the local
cluster's start and close. The trials are the paper's scenarios of
``examples/batch/trials.jsonl`` repeated with new ids, written to a file as a user would have
them. Every run must give the plain batch's verdicts (verdicts.json, less the planner's timings
and whether its cache answered).

Targets: two workers at least 1.7x faster than one; one worker at most 10% slower than the
plain batch. Exit 0 when both are met.

Then, for diagnosis, where the time goes on a cluster already running: the start of a local
cluster of 1 and of 2 workers (what a user with a running cluster does not pay), and a run of
``write_batch_on_cluster`` on it with the CPU seconds of this process (the client and, in a
local cluster, the scheduler, which runs in the client's process) and of each worker.
"""

from __future__ import annotations

import argparse
import json
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
SCENARIOS = ROOT / "examples" / "batch" / "trials.jsonl"
SPEED_UP_GOAL = 1.7
OVERHEAD_GOAL = 0.10
RUNS = {"plain batch": (), "--workers 1": ("--workers", "1"), "--workers 2": ("--workers", "2")}


def write_trials(path: Path, count: int) -> None:
    """Write ``count`` trials: the scenarios over and over, each readable one with an id of its own.

    Lines that cannot be read stay as they are (their trials are named by their line).
    """
    scenarios = SCENARIOS.read_text(encoding="utf-8").splitlines()
    with path.open("w", encoding="utf-8") as handle:
        for number in range(count):
            line = scenarios[number % len(scenarios)]
            try:
                entry = json.loads(line)
            except json.JSONDecodeError:
                entry = None
            if isinstance(entry, dict):
                entry["id"] = f"t{number:06d}"
                line = json.dumps(entry)
            handle.write(line + "\n")


def children_cpu() -> float:
    """Return the CPU seconds (user + system) of this process's finished children and theirs."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def batch_run(trials: Path, out: Path, chunk_size: int, options: tuple[str, ...]) -> tuple[float, float]:
    """Return the wall and CPU seconds (with every process it started) of one ``causalplan batch``."""
    command = [str(Path(sys.executable).with_name("causalplan")), "batch", str(trials), "--out", str(out)]
    command += ["--no-simulate", "--no-val", *options]
    if options:  # --chunk-size sizes a cluster's tasks: the plain batch refuses it
        command += ["--chunk-size", str(chunk_size)]
    cpu, started = children_cpu(), time.perf_counter()
    finished = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
    seconds = time.perf_counter() - started
    if finished.returncode != 0:
        raise SystemExit(f"{' '.join(command)} failed ({finished.returncode}):\n{finished.stderr[-2000:]}")
    return seconds, children_cpu() - cpu


def verdicts(out: Path) -> list[dict[str, Any]]:
    """Return a run's verdicts without what differs between runs (the planner's timings, its cache)."""
    entries: list[dict[str, Any]] = json.loads((out / "verdicts.json").read_text(encoding="utf-8"))
    for entry in entries:
        if isinstance(entry.get("planning"), dict):
            entry["planning"] = {k: v for k, v in entry["planning"].items() if k not in ("timing", "cached")}
    return entries


def breakdown(trials: Path, chunk_size: int, workers: int) -> str:
    """Return one line: a local cluster's start, then a batch on it with each process's CPU seconds."""
    from causalplan.objects.catalog import load_catalog
    from causalplan.transfer.cluster import JudgeOptions, connect, file_chunks, write_batch_on_cluster

    catalog = load_catalog()
    started = time.perf_counter()
    watcher, cluster = connect(None, workers)  # as --workers starts it
    start = time.perf_counter() - started
    try:
        worker_cpu_before: dict[str, float] = watcher.run(time.process_time)
        cpu, started = time.process_time(), time.perf_counter()
        write_batch_on_cluster(
            file_chunks(trials, chunk_size), catalog, JudgeOptions(simulate=False), address=cluster.scheduler_address
        )
        wall, client_cpu = time.perf_counter() - started, time.process_time() - cpu
        worker_cpu = [seconds - worker_cpu_before[name] for name, seconds in watcher.run(time.process_time).items()]
    finally:
        watcher.close()  # type: ignore[no-untyped-call]
        cluster.close()
    each = ", ".join(f"{seconds:.1f}" for seconds in worker_cpu)
    return (
        f"| {workers} | {start:.1f} | {wall:.1f} | {client_cpu:.1f} | {each} | "
        f"{(client_cpu + sum(worker_cpu)) / wall:.2f} |"
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--trials", type=int, default=100_000, help="how many trials to write (default 100,000)")
    parser.add_argument("--trials-file", type=Path, help="judge this batch file instead of writing one")
    parser.add_argument("--chunk-size", type=int, default=2_000, help="trials per cluster task (default 2,000)")
    parser.add_argument("--rounds", type=int, default=3, help="rounds of the three runs, medians reported (default 3)")
    parser.add_argument("--no-breakdown", action="store_true", help="skip the diagnosis on a running cluster")
    args = parser.parse_args()
    if args.trials < 1 or args.chunk_size < 1 or args.rounds < 1:
        parser.error("--trials, --chunk-size and --rounds must be at least 1")
    if args.trials_file is not None and not args.trials_file.is_file():
        parser.error(f"--trials-file: there is no file {args.trials_file}")
    folder = Path(tempfile.mkdtemp(prefix="cluster-benchmark-"))
    try:
        trials = args.trials_file.resolve() if args.trials_file else folder / "trials.jsonl"
        if args.trials_file is None:
            write_trials(trials, args.trials)
        reference: list[dict[str, Any]] | None = None
        timings: dict[str, list[tuple[float, float]]] = {name: [] for name in RUNS}
        for round_number in range(1, args.rounds + 1):
            for name, options in RUNS.items():
                out = folder / "out"
                timings[name].append(batch_run(trials, out, args.chunk_size, options))
                judged = verdicts(out)
                shutil.rmtree(out)
                if reference is None:
                    reference = judged
                elif judged != reference:
                    print(f"round {round_number}, {name}: the verdicts differ from the plain batch's", file=sys.stderr)
                    return 1
            print(
                f"round {round_number} of {args.rounds}: "
                + ", ".join(f"{name} {timings[name][-1][0]:.1f} s" for name in RUNS),
                flush=True,
            )
        assert reference is not None
        count, reference = len(reference), None  # a local cluster's workers are forked: they would inherit it
        seconds = {name: statistics.median(wall for wall, _ in runs) for name, runs in timings.items()}
        cpu = {name: statistics.median(used for _, used in runs) for name, runs in timings.items()}
        plain, one, two = (seconds[name] for name in RUNS)
        speed_up, overhead = one / two, one / plain - 1
        print(f"{count} trials, chunks of {args.chunk_size}, the same verdicts in every run")
        print("| causalplan batch | seconds (median) | each round's seconds | CPU seconds (all processes) | trials/s |")
        print("|---|---|---|---|---|")
        for name, runs in timings.items():
            each = ", ".join(f"{wall:.1f}" for wall, _ in runs)
            print(f"| {name} | {seconds[name]:.1f} | {each} | {cpu[name]:.1f} | {count / seconds[name]:.0f} |")
        met_speed, met_overhead = speed_up >= SPEED_UP_GOAL, overhead <= OVERHEAD_GOAL
        print(
            f"speed-up 2 vs 1 worker: {speed_up:.2f}x (goal >= {SPEED_UP_GOAL}x): {'met' if met_speed else 'NOT met'}"
        )
        met = "met" if met_overhead else "NOT met"
        print(f"overhead 1 worker vs plain: {overhead:+.1%} (goal <= {OVERHEAD_GOAL:.0%}): {met}")
        if not args.no_breakdown:
            print("\nOn a running local cluster (write_batch_on_cluster, this process as the client):")
            print(
                "| workers | cluster start s | batch s | client + scheduler CPU s | each worker's CPU s | cores busy |"
            )
            print("|---|---|---|---|---|---|")
            for workers in (1, 2):
                print(breakdown(trials, args.chunk_size, workers))
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return 0 if met_speed and met_overhead else 1


if __name__ == "__main__":
    sys.exit(main())
