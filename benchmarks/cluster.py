"""Batches on Dask: 1 and 2 local workers against the plain local batch, measured in one run.

    python benchmarks/cluster.py                 # 100,000 trials (the issue's size)
    python benchmarks/cluster.py --trials 5000   # a quick look

The trials are the paper's scenarios of ``examples/batch/trials.jsonl`` repeated with new ids,
judged without the simulator (the planner's verdicts). Three timings, each from a cold start of
the caches: the plain ``run_batch`` in this process, ``run_batch_on_cluster`` on a local cluster
of one worker process, and on one of two. Targets: two workers at least 1.7x faster than one;
one worker at most 10% slower than the plain batch (Dask's overhead). The verdicts of the three
runs must be the same. Exit 0 when both targets are met.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

from causalplan.objects.catalog import load_catalog
from causalplan.transfer.batch import Trial, TrialResult, read_trials, run_batch
from causalplan.transfer.cluster import JudgeOptions, run_batch_on_cluster
from causalplan.transfer.verdict import clear_caches

SCENARIOS = Path(__file__).resolve().parent.parent / "examples" / "batch" / "trials.jsonl"
SPEED_UP_GOAL = 1.7
OVERHEAD_GOAL = 0.10


def trials_of(count: int) -> list[Trial]:
    """Return ``count`` trials: the scenarios over and over, each with an id of its own."""
    scenarios = list(read_trials(SCENARIOS))
    return [replace(scenarios[i % len(scenarios)], id=f"t{i:06d}") for i in range(count)]


def verdicts(results: list[TrialResult]) -> list[tuple[str, str, str]]:
    return [(r.trial_id, r.verdict.verdict.value, r.verdict.decided_by) for r in results]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--trials", type=int, default=100_000)
    parser.add_argument("--chunk-size", type=int, default=2_000)
    args = parser.parse_args()
    catalog = load_catalog()
    trials = trials_of(args.trials)
    options = JudgeOptions(simulate=False)

    clear_caches()
    started = time.perf_counter()
    local = run_batch(trials, catalog, simulate=False)
    plain = time.perf_counter() - started
    timings = {}
    for workers in (1, 2):
        started = time.perf_counter()
        results = run_batch_on_cluster(trials, catalog, options, workers=workers, chunk_size=args.chunk_size)
        timings[workers] = time.perf_counter() - started
        if verdicts(results) != verdicts(local):
            print(f"verdicts on {workers} worker(s) differ from the local batch", file=sys.stderr)
            return 1
    speed_up = timings[1] / timings[2]
    overhead = timings[1] / plain - 1
    print(f"{args.trials} trials, chunks of {args.chunk_size}, same verdicts in all three runs")
    print("| run | seconds | trials/s |\n|---|---|---|")
    for name, seconds in (("plain run_batch", plain), ("Dask, 1 worker", timings[1]), ("Dask, 2 workers", timings[2])):
        print(f"| {name} | {seconds:.1f} | {args.trials / seconds:.0f} |")
    met_speed, met_overhead = speed_up >= SPEED_UP_GOAL, overhead <= OVERHEAD_GOAL
    print(f"speed-up 2 vs 1 worker: {speed_up:.2f}x (goal >= {SPEED_UP_GOAL}x): {'met' if met_speed else 'NOT met'}")
    met = "met" if met_overhead else "NOT met"
    print(f"overhead 1 worker vs plain: {overhead:+.1%} (goal <= {OVERHEAD_GOAL:.0%}): {met}")
    return 0 if met_speed and met_overhead else 1


if __name__ == "__main__":
    sys.exit(main())
