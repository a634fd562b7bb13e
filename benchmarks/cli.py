"""Whole-process speed of the CLI against the same solve through unified-planning.

    python benchmarks/cli.py [--runs 7]

Runs ``causalplan plan examples/paper/desk_lamp.yaml`` and ``python benchmarks/up_desk_lamp.py``
(import unified-planning, build the desk-lamp problem, solve it with its Fast Downward engine)
as separate processes, interleaved, and prints their medians and the ratio. Target: <= 0.15.
The causalplan run uses the ``causalplan`` next to this Python (no shell shims in between).
With PYTHONDONTWRITEBYTECODE set (as on the CI machines), an editable install compiles
causalplan's modules on every run, which ``pip install .`` does once; the script says which.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TARGET = 0.15


def wall_time(command: list[str]) -> float:
    """Return the wall time of one run of ``command`` (which must succeed)."""
    started = time.perf_counter()
    subprocess.run(command, cwd=ROOT, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=7, help="timed runs of each (after one warm-up each)")
    parser.add_argument("--output", type=Path, default=ROOT / "benchmarks" / "results" / "cli.json")
    args = parser.parse_args()
    ours_command = [str(Path(sys.executable).with_name("causalplan")), "plan", "examples/paper/desk_lamp.yaml"]
    up_command = [sys.executable, str(ROOT / "benchmarks" / "up_desk_lamp.py")]
    wall_time(ours_command)  # warm the file cache and causalplan's catalog cache
    wall_time(up_command)
    ours, up = [], []
    for _ in range(args.runs):
        ours.append(wall_time(ours_command))
        up.append(wall_time(up_command))
    ratio = statistics.median(ours) / statistics.median(up)
    print(
        f"causalplan plan (whole process): median {statistics.median(ours) * 1000:.0f} ms "
        f"(min {min(ours) * 1000:.0f}, max {max(ours) * 1000:.0f}) over {args.runs} runs"
    )
    print(
        f"unified-planning script:         median {statistics.median(up) * 1000:.0f} ms "
        f"(min {min(up) * 1000:.0f}, max {max(up) * 1000:.0f})"
    )
    if sys.dont_write_bytecode:
        print("PYTHONDONTWRITEBYTECODE is set: modules without a compiled copy are compiled on every run")
    print(f"ratio ours/UP: {ratio:.3f} (target <= {TARGET}: {'met' if ratio <= TARGET else 'NOT met'})")
    report = {
        "runs": args.runs,
        "ours_s": ours,
        "up_s": up,
        "ours_median_s": statistics.median(ours),
        "up_median_s": statistics.median(up),
        "ratio": ratio,
        "target": TARGET,
        "met": ratio <= TARGET,
        "bytecode_cache": not sys.dont_write_bytecode,
    }
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
