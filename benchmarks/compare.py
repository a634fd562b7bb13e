"""``causalplan compare`` as a whole process against one ``causalplan plan`` process, in the same run.

    python benchmarks/compare.py [--rounds 5]

Runs ``causalplan plan examples/paper/desk_lamp.yaml`` and ``causalplan compare --planners
fd,fd-opt,mdp`` (the paper's six tasks: 18 runs, each in a process of its own) as separate
processes, interleaved after one warm-up each, and prints their medians and the ratio.
Target: the comparison takes at most 10x one plan. Every row of each comparison must be solved
and valid, or the script says so and exits 1. Uses the ``causalplan`` next to this Python.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TARGET = 10.0
PLANNERS = "fd,fd-opt,mdp"


def wall_time(command: list[str]) -> float:
    """Return the wall time of one run of ``command`` (which must succeed)."""
    started = time.perf_counter()
    subprocess.run(command, cwd=ROOT, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - started


def rows_of(out: Path) -> list[dict[str, object]]:
    """Return the rows a comparison wrote to ``out``/compare.json."""
    runs: list[dict[str, object]] = json.loads((out / "compare.json").read_text(encoding="utf-8"))["runs"]
    return runs


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=5, help="timed runs of each (after one warm-up each)")
    parser.add_argument("--output", type=Path, default=ROOT / "benchmarks" / "results" / "compare.json")
    args = parser.parse_args()
    causalplan = str(Path(sys.executable).with_name("causalplan"))
    plan_command = [causalplan, "plan", "examples/paper/desk_lamp.yaml"]
    plans, comparisons, bad_rows = [], [], []
    with tempfile.TemporaryDirectory(prefix="causalplan-bench-compare-") as folder:
        out = Path(folder)
        compare_command = [causalplan, "compare", "--planners", PLANNERS, "--out", str(out)]
        wall_time(plan_command)  # warm the file cache and causalplan's catalog cache
        wall_time(compare_command)
        for _ in range(args.rounds):
            plans.append(wall_time(plan_command))
            comparisons.append(wall_time(compare_command))
            rows = rows_of(out)
            bad_rows += [row for row in rows if row["status"] != "solved" or row["valid"] is not True]
        runs = len(rows)
    plan_median, compare_median = statistics.median(plans), statistics.median(comparisons)
    ratio = compare_median / plan_median
    met = ratio <= TARGET and not bad_rows
    print(
        f"causalplan plan (whole process):       median {plan_median * 1000:.0f} ms "
        f"(min {min(plans) * 1000:.0f}, max {max(plans) * 1000:.0f}) over {args.rounds} rounds"
    )
    print(
        f"causalplan compare --planners {PLANNERS} ({runs} runs): median {compare_median * 1000:.0f} ms "
        f"(min {min(comparisons) * 1000:.0f}, max {max(comparisons) * 1000:.0f})"
    )
    if bad_rows:
        print(f"{len(bad_rows)} rows were not solved and valid, e.g. {bad_rows[0]}")
    print(f"ratio compare/plan: {ratio:.1f} (target <= {TARGET:g}: {'met' if met else 'NOT met'})")
    report = {
        "rounds": args.rounds,
        "runs_per_comparison": runs,
        "plan_s": plans,
        "compare_s": comparisons,
        "plan_median_s": plan_median,
        "compare_median_s": compare_median,
        "ratio": ratio,
        "target": TARGET,
        "all_rows_solved_and_valid": not bad_rows,
        "met": met,
    }
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
    return 0 if met else 1


if __name__ == "__main__":
    sys.exit(main())
