"""Time filming the robot ("Watch the robot"), next to the robot's run of the same plan without a film.

    python benchmarks/films.py [--repeat K] [--sizes 160x120,480x360]

For each paper object's full plan (every part in place): the median of K robot runs without
a film (``simulate_plan(..., robot=True)``, the reference, in the same run), then one film
per size (``simulate_plan(..., video=True)`` and the MP4 encoding), its frames and bytes and
its cost as a ratio of the run. Last, what filming every plan ``service.pages.ahead`` would
draw ahead (one per set of two or more parts, up to ``MAX_PART_SETS`` per object) would
cost one worker at the service's size: the sum over objects of their part sets times the
film's time.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import time
from importlib import metadata

from rich.console import Console
from rich.table import Table

from causalplan.objects.catalog import load_catalog
from causalplan.pddl.task import build_task
from causalplan.planners.pipeline import plan_task
from causalplan.service.pages.ahead import needing, part_sets
from causalplan.sim import RenderMode, simulate_plan
from causalplan.sim.video import encode

OBJECTS = ("desk_lamp", "flashlight", "candle", "kerosene_lamp")


def _size(text: str) -> tuple[int, int]:
    width, height = text.lower().split("x")
    return int(width), int(height)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3, help="Robot runs without a film per object (median).")
    parser.add_argument("--sizes", default="160x120,480x360", help="Film sizes, WIDTHxHEIGHT, comma-separated.")
    args = parser.parse_args()
    sizes = [_size(item) for item in args.sizes.split(",") if item]
    catalog = load_catalog(())
    console = Console(width=160)  # the table stays whole when written to a file
    console.print(
        f"python {platform.python_version()}, pybullet {metadata.version('pybullet')}, "
        f"imageio-ffmpeg {metadata.version('imageio-ffmpeg')}, {platform.machine()}, repeat {args.repeat}"
    )
    table = Table(title="Filming the robot against its run without a film (same plan, same run)")
    for column in (
        "object",
        "steps",
        "run ms",
        *(f"film {w}x{h} s" for w, h in sizes),
        "ratio (largest)",
        "frames",
        "MP4 KB",
    ):
        table.add_column(column)
    ahead_seconds = 0.0
    ahead_films = 0
    for object_id in OBJECTS:
        obj = catalog.get(object_id)
        steps = plan_task(build_task(needing(obj, obj.part_ids), obj, None), "fd", 30.0).steps
        runs = []
        for _ in range(args.repeat):
            started = time.perf_counter()
            simulate_plan(obj, steps, render=RenderMode.NONE, robot=True)
            runs.append(time.perf_counter() - started)
        run = statistics.median(runs)
        film_seconds = []
        frames = 0
        size_kb = 0.0
        for size in sizes:
            started = time.perf_counter()
            report = simulate_plan(obj, steps, render=RenderMode.NONE, robot=True, video=True, video_size=size)
            data = encode(report.video, ".mp4")
            film_seconds.append(time.perf_counter() - started)
            frames, size_kb = len(report.video), len(data) / 1024
        sets = sum(1 for _ in part_sets(obj))
        ahead_films += sets
        ahead_seconds += sets * film_seconds[-1]  # a smaller part set films a shorter plan: an upper bound
        table.add_row(
            object_id,
            str(len(steps)),
            f"{run * 1000:.0f}",
            *(f"{seconds:.1f}" for seconds in film_seconds),
            f"{film_seconds[-1] / run:.0f}x",
            str(frames),
            f"{size_kb:.0f}",
        )
    console.print(table)
    width, height = sizes[-1]
    console.print(
        f"Filming ahead every plan service.pages.ahead draws ({ahead_films} plans) at {width}x{height}: "
        f"at most {ahead_seconds / 60:.1f} min of one worker."
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
