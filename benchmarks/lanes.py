"""The fast test lane against the full suite, both run here, one after the other.

    python benchmarks/lanes.py [--workers auto] [--fast-first]

Runs ``pytest -q -n WORKERS`` (every test: the README's command) and ``pytest -q -n WORKERS
-m "not slow"`` (the lane a developer runs after every change) as separate processes, with
the same options, and prints the wall time of each, their test counts and the ratio.
Target: the fast lane takes at most 0.3x the full suite. Both must pass; a lane that fails
is reported with its summary line and the script exits 1. It is long (the full suite is
most of it): run it when the machine is otherwise quiet.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from datetime import UTC, datetime
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TARGET = 0.3


def run_lane(workers: str, *selection: str) -> dict[str, object]:
    """Run pytest over the suite with ``selection``; return its wall time, exit code and summary line."""
    command = [sys.executable, "-m", "pytest", "-q", "-p", "no:randomly", "-n", workers, *selection]
    print(f"$ {' '.join(command[1:])}", flush=True)
    started = time.perf_counter()
    completed = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, check=False)
    seconds = time.perf_counter() - started
    lines = completed.stdout.strip().splitlines()
    summary = lines[-1] if lines else completed.stderr.strip()[-500:]
    print(f"  {seconds:.0f} s, exit code {completed.returncode}: {summary}", flush=True)
    if completed.returncode != 0:
        failures = [line for line in lines if line.startswith(("FAILED", "ERROR"))]
        print("\n".join(f"  {line}" for line in failures[:30]), flush=True)
    return {"command": command[1:], "seconds": seconds, "exit_code": completed.returncode, "summary": summary}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--workers", default="auto", help="pytest-xdist's -n for both lanes (0: no workers)")
    parser.add_argument("--fast-first", action="store_true", help="run the fast lane first")
    parser.add_argument("--output", type=Path, default=ROOT / "benchmarks" / "results" / "lanes.json")
    args = parser.parse_args()
    lanes = [("full", ()), ("fast", ("-m", "not slow"))]
    if args.fast_first:
        lanes.reverse()
    started = datetime.now(UTC).isoformat(timespec="seconds")
    results = {name: run_lane(args.workers, *selection) for name, selection in lanes}
    full, fast = results["full"], results["fast"]
    ratio = float(str(fast["seconds"])) / float(str(full["seconds"]))
    passed = full["exit_code"] == 0 and fast["exit_code"] == 0
    met = passed and ratio <= TARGET
    print(f"full suite: {full['seconds']:.0f} s ({full['summary']})")
    print(f"fast lane:  {fast['seconds']:.0f} s ({fast['summary']})")
    print(f"ratio fast/full: {ratio:.3f} (target <= {TARGET}: {'met' if met else 'NOT met'})")
    report = {"started": started, "workers": args.workers, "lanes": results, "ratio": ratio, "target": TARGET}
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps({**report, "met": met}, indent=2) + "\n", encoding="utf-8")
    return 0 if met else 1


if __name__ == "__main__":
    sys.exit(main())
