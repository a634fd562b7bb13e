"""Fit estimates on Dask: 1 and 2 local workers against the run in this process, measured in one run.

    python benchmarks/fits_cluster.py                       # desk lamp, 4,000 insertions per fit
    python benchmarks/fits_cluster.py --trials 1000 --chunk-size 250

``estimate_fits`` of one object three times with the same seed: in this process (the
reference), then in chunks on a local cluster of one worker process and of two. Every chunk
repeats the robot's nominal run of its fit before its insertions, so the one-worker ratio shows
what that repetition and Dask cost, and the two-worker ratio what a second process gains. The
three runs must give the same estimates (exit 1 otherwise). Prints the ratios; it has no targets.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable, Sequence
from functools import partial

from causalplan.objects.catalog import load_catalog
from causalplan.sim.fit_estimates import ChunkOutcome, FitEstimate, InsertionChunk, estimate_fits
from causalplan.transfer.cluster import map_on_cluster


def on_local_cluster(
    workers: int,
    function: Callable[[InsertionChunk], ChunkOutcome],
    chunks: Sequence[InsertionChunk],
    on_result: Callable[[ChunkOutcome], None] | None,
) -> list[ChunkOutcome]:
    return map_on_cluster(function, chunks, workers=workers, on_result=on_result)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--object", default="desk_lamp")
    parser.add_argument("--trials", type=int, default=4_000, help="insertions per fit")
    parser.add_argument("--chunk-size", type=int, default=1_000)
    args = parser.parse_args()
    obj = load_catalog().get(args.object)
    estimate_fits(obj, trials=1)  # warm this process (imports, PyBullet) as the workers' first chunk warms them

    started = time.perf_counter()
    here = estimate_fits(obj, trials=args.trials)
    timings: dict[str, float] = {"here": time.perf_counter() - started}
    results: dict[str, list[FitEstimate]] = {}
    for workers in (1, 2):
        started = time.perf_counter()
        results[f"{workers}"] = estimate_fits(
            obj, trials=args.trials, map_chunks=partial(on_local_cluster, workers), chunk_size=args.chunk_size
        )
        timings[f"{workers}"] = time.perf_counter() - started
    fits = len(here)
    chunks = fits * -(-args.trials // args.chunk_size)
    print(f"{args.object}: {fits} fits x {args.trials} insertions, chunks of {args.chunk_size} ({chunks} chunks)")
    print(f"in this process         {timings['here']:8.2f} s  (reference)")
    for workers in (1, 2):
        seconds = timings[f"{workers}"]
        print(f"{workers} local worker(s)      {seconds:8.2f} s  {seconds / timings['here']:.2f}x the reference time")
    for name, estimates in (("here", here), ("1 worker", results["1"])):
        robot = sum(estimate.timing.get("robot", 0.0) for estimate in estimates)
        trials = sum(estimate.timing.get("trials", 0.0) for estimate in estimates)
        print(f"{name}: nominal robot runs {robot / (robot + trials):.0%} of the estimating time")
    print(f"speed-up of 2 workers over 1: {timings['1'] / timings['2']:.2f}x (cluster start-up included)")
    same = all(result == here for result in results.values())
    print("estimates identical to the reference: " + ("yes" if same else "NO"))
    for estimate in here:
        print(f"  {estimate.fit}: {estimate.successes}/{estimate.trials} {estimate.failures}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
