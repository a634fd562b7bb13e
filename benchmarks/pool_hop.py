"""The hop to a planner worker alone: ``PlannerPool.run`` of a job that returns at once.

Run it once per side to compare two versions of the pool (``PYTHONPATH`` at each), from a
folder holding neither (a worker must import the side's own code):

    cd /tmp && PYTHONPATH=/path/to/side python /path/to/side/benchmarks/pool_hop.py [--calls 300]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

from causalplan.service.pool.pool import PlannerPool


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=300)
    args = parser.parse_args()
    pool = PlannerPool(2, 0, 4096, 5.0)
    pool.start()
    try:
        for _ in range(20):  # warm
            pool.run(os.getpid, (), 30)
        times = []
        for _ in range(args.calls):
            started = time.perf_counter()
            pool.run(os.getpid, (), 30)
            times.append(time.perf_counter() - started)
    finally:
        pool.close()
    p90 = statistics.quantiles(times, n=10)[-1]
    print(
        f"PlannerPool.run, a job that returns at once: median {statistics.median(times) * 1000:.3f} ms, "
        f"p90 {p90 * 1000:.3f} ms ({args.calls} calls, 2 workers)"
    )


if __name__ == "__main__":
    main()
