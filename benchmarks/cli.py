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
    parser.add_argument("--runs", type=int, default=7)
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
    compiled = "off: causalplan is compiled on every run" if sys.dont_write_bytecode else "on"
    print(f"bytecode cache: {compiled}")
    print(f"ratio ours/UP: {ratio:.3f} (target <= {TARGET}: {'met' if ratio <= TARGET else 'NOT met'})")


if __name__ == "__main__":
    main()
