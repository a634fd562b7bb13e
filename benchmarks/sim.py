"""Time one simulator check per paper object: build the scene, run the whole assembly, settle.

    python benchmarks/sim.py [--repeat K]

A check is ``simulate_plan(obj, steps, render=RenderMode.NONE)``: a fresh world with the
object's parts, every step moved, checked and welded, the final settle, and the true
mechanism judged; no picture. The reference, measured in the same run, is the smallest
PyBullet job of the same kind: start a headless server, add a table and one box, step 240
times (one simulated second), stop. Each case runs once to warm up, then ``--repeat``
times; the table shows medians, and ``(!)`` marks an object whose check did not pass. The
exit code is 0 when every object's median is under the target.
"""

from __future__ import annotations

import argparse
import functools
import platform
import statistics
import sys
import time
from collections.abc import Callable
from importlib import metadata

from rich.console import Console
from rich.table import Table

from causalplan.objects.catalog import load_catalog
from causalplan.objects.model import AssemblyObject
from causalplan.sim import RenderMode, SimulationReport, StepRequest, simulate_plan
from causalplan.sim.scene import load_pybullet

TARGET_SECONDS = 0.050
PLANS: dict[str, tuple[StepRequest, ...]] = {
    "desk_lamp": (
        StepRequest("screw", "light_bulb", "base_with_cables", "bulb_into_socket"),
        StepRequest("clip", "shade", "base_with_cables", "shade_onto_ring"),
    ),
    "flashlight": (
        StepRequest("insert", "batteries", "case", "batteries_into_bay"),
        StepRequest("screw", "head", "case", "head_onto_case"),
    ),
    "candle": (
        StepRequest("insert", "wick", "wax", "wick_into_wax"),
        StepRequest("ignite", "match", "wick", "match_lights_wick"),
    ),
    "kerosene_lamp": (
        StepRequest("screw", "burner", "fuel_tank", "burner_onto_tank"),
        StepRequest("insert", "wick", "burner", "wick_into_burner"),
        StepRequest("ignite", "lighter", "wick", "lighter_lights_wick"),
        StepRequest("place", "glass_chimney", "burner", "chimney_onto_burner"),
    ),
}
"""The whole assembly of each paper object, in an order that works."""


def empty_world() -> None:
    """The reference: a fresh headless server with a table and a box, one simulated second."""
    pb = load_pybullet()
    client = pb.connect(pb.DIRECT)
    pb.setGravity(0, 0, -9.81, physicsClientId=client)
    pb.createMultiBody(0, pb.createCollisionShape(pb.GEOM_PLANE, physicsClientId=client), physicsClientId=client)
    box = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[0.02, 0.02, 0.02], physicsClientId=client)
    pb.createMultiBody(0.1, box, basePosition=[0, 0, 0.02], physicsClientId=client)
    for _ in range(240):
        pb.stepSimulation(physicsClientId=client)
    pb.disconnect(physicsClientId=client)


def median_seconds(job: Callable[[], object], repeat: int) -> tuple[float, list[float]]:
    """Return the median wall time of ``repeat`` calls of ``job`` after one warm-up call, and all times."""
    job()
    times = []
    for _ in range(repeat):
        started = time.perf_counter()
        job()
        times.append(time.perf_counter() - started)
    return statistics.median(times), times


def _check(obj: AssemblyObject, steps: tuple[StepRequest, ...], reports: list[SimulationReport]) -> None:
    reports.append(simulate_plan(obj, steps, render=RenderMode.NONE))


def milliseconds(seconds: float) -> str:
    return f"{seconds * 1000:.1f} ms"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=15, help="timed runs per case (default 15)")
    arguments = parser.parse_args()
    repeat = max(1, arguments.repeat)
    console = Console(highlight=False, width=110)
    catalog = load_catalog()
    baseline, _ = median_seconds(empty_world, repeat)
    table = Table(
        "object",
        "steps",
        "check (median)",
        "scene",
        "steps run",
        "settle",
        "check / reference",
        title=f"Simulator check, median of {repeat} runs after a warm-up (no rendering)",
        title_justify="left",
    )
    medians = {}
    for object_id, steps in PLANS.items():
        reports: list[SimulationReport] = []
        check = functools.partial(_check, catalog.get(object_id), steps, reports)
        medians[object_id], _ = median_seconds(check, repeat)
        stages = {
            stage: statistics.median(report.timing.get(stage, 0.0) for report in reports[1:])
            for stage in ("scene", "steps", "settle")
        }
        mark = "" if all(report.passed for report in reports) else " (!)"
        table.add_row(
            object_id + mark,
            str(len(steps)),
            milliseconds(medians[object_id]),
            milliseconds(stages["scene"]),
            milliseconds(stages["steps"]),
            milliseconds(stages["settle"]),
            f"{medians[object_id] / baseline:.2f}x",
        )
    console.print(table)
    console.print(
        f"reference: headless PyBullet start + table + one box + 240 steps + stop, median {milliseconds(baseline)}"
    )
    slowest = max(medians, key=lambda object_id: medians[object_id])
    met = medians[slowest] < TARGET_SECONDS
    console.print(
        f"target: every object's median check under {milliseconds(TARGET_SECONDS)}: "
        f"{'met' if met else 'NOT met'} (slowest: {slowest}, {milliseconds(medians[slowest])})"
    )
    console.print(f"[dim]pybullet {metadata.version('pybullet')}, Python {platform.python_version()}[/]")
    return 0 if met else 1


if __name__ == "__main__":
    sys.exit(main())
