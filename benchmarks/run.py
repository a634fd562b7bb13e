"""Time our direct Fast Downward route against unified-planning's, on the paper's models and synthetic objects.

    python benchmarks/run.py [--repeat K] [--sizes 10,40,80,160] [--quick] [--up-time-limit S]

Both routes start from the same ``PlanningTask``: ours is ``plan_task(task, "fd")`` (compile to
PDDL with derived predicates, translate in-process, search with a search process started
ahead of the task, replay); UP's is
``solve_with_up(task, "fast-downward")`` (build the axiom-free UP problem, then
``OneshotPlanner(name="fast-downward")``, which writes PDDL and runs FD's driver). Every case
is run once to warm up, then ``--repeat`` times; the tables show medians of wall time.
Results also go to ``benchmarks/results/latest.json``. See benchmarks/README.md.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import platform
import statistics
import sys
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

from causalplan import caches
from causalplan.comparison.synthetic import MAX_PARTS, MIN_PARTS, synthetic_task
from causalplan.inputs import load_model
from causalplan.objects.catalog import load_catalog
from causalplan.pddl.task import PlanningTask, build_task
from causalplan.planners.pipeline import plan_task
from causalplan.planners.replay import replay
from causalplan.planners.up_problem import solve_with_up

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results" / "latest.json"
PAPER_MODELS = (
    "examples/paper/desk_lamp.yaml",
    "examples/paper/failed_desk_lamp.yaml",
    "examples/near/candle.yaml",
    "examples/far/abstract_desk_lamp.yaml",
)
DEFAULT_SIZES = (10, 40, 80, 160)
TARGET_PARTS = 80
TARGET_SECONDS = 2.0
OUR_TIME_LIMIT = 60.0
WIDTH = 120


@dataclass
class RouteResult:
    """The repeated runs of one route on one case."""

    status: str = "not run"
    seconds: list[float] = field(default_factory=list)
    plan_length: int | None = None
    valid: bool | None = None  # replay: valid under the model and under the true mechanism
    stages: dict[str, list[float]] = field(default_factory=dict)
    message: str = ""

    @property
    def median(self) -> float | None:
        return statistics.median(self.seconds) if self.seconds and self.status == "solved" else None

    def stage_median(self, stage: str) -> float | None:
        values = self.stages.get(stage)
        return statistics.median(values) if values and self.status == "solved" else None

    def as_dict(self) -> dict[str, object]:
        return {
            "status": self.status,
            "median_s": self.median,
            "runs_s": [round(value, 6) for value in self.seconds],
            "stage_medians_s": {stage: self.stage_median(stage) for stage in self.stages},
            "plan_length": self.plan_length,
            "valid": self.valid,
            "message": self.message,
        }


Run = Callable[[], tuple[str, int | None, bool | None, dict[str, float], str]]


def ours(task: PlanningTask) -> Run:
    def run() -> tuple[str, int | None, bool | None, dict[str, float], str]:
        # A real solve, not a remembered answer, on an object parsed afresh (as the first model on it)
        caches.current().fd_answers.clear()
        result = plan_task(task, "fd", time_limit=OUR_TIME_LIMIT)
        valid = result.valid_under_model and result.valid_under_true_mechanism if result.has_plan else None
        return result.status.value, len(result.steps) if result.has_plan else None, valid, result.timing, result.message

    return run


def through_up(task: PlanningTask, time_limit: float) -> Run:
    def run() -> tuple[str, int | None, bool | None, dict[str, float], str]:
        outcome = solve_with_up(task, "fast-downward", time_limit)
        if outcome.status.value != "solved":
            return outcome.status.value, None, None, outcome.timing, outcome.message
        checked = replay(task, outcome.actions)
        valid = checked.executable and checked.valid_under_model and checked.valid_under_true_mechanism
        return "solved", len(outcome.actions), valid, outcome.timing, outcome.message

    return run


def measure(run: Run, repeat: int) -> RouteResult:
    """Warm up once, then time ``repeat`` runs; stop early when a run does not solve."""
    result = RouteResult()
    for attempt in range(repeat + 1):
        started = time.perf_counter()
        status, length, valid, timing, message = run()
        elapsed = time.perf_counter() - started
        result.status, result.plan_length, result.valid, result.message = status, length, valid, message
        if status != "solved":  # a timeout or failure: report it, do not repeat it
            result.seconds = [elapsed]
            return result
        if attempt == 0:
            continue  # the warm-up run
        result.seconds.append(elapsed)
        for stage, seconds in timing.items():
            result.stages.setdefault(stage, []).append(seconds)
    return result


def fmt_seconds(route: RouteResult) -> str:
    if route.median is None:
        return route.status.replace("_", " ")
    return f"{route.median * 1000:.1f} ms" if route.median < 1 else f"{route.median:.2f} s"


def fmt_stage(route: RouteResult, stage: str) -> str:
    value = route.stage_median(stage)
    return "" if value is None else f"{value * 1000:.1f}"


def ratio(mine: RouteResult, theirs: RouteResult) -> float | None:
    if mine.median is None or theirs.median is None:
        return None
    return theirs.median / mine.median


def fmt_ratio(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f}x"


def fmt_length(route: RouteResult) -> str:
    if route.plan_length is None:
        return "-"
    mark = "" if route.valid else " (!)"
    return f"{route.plan_length}{mark}"


def table(title: str, first_column: str, rows: list[tuple[str, RouteResult, RouteResult]]) -> Table:
    out = Table(title=title, title_justify="left")
    out.add_column(first_column)
    out.add_column("ours (fd)", justify="right")
    out.add_column("translate ms", justify="right", style="dim")
    out.add_column("search ms", justify="right", style="dim")
    out.add_column("UP fast-downward", justify="right")
    out.add_column("UP/ours", justify="right", style="bold")
    out.add_column("plan len ours/UP", justify="right")
    for name, mine, theirs in rows:
        out.add_row(
            name,
            fmt_seconds(mine),
            fmt_stage(mine, "translate"),
            fmt_stage(mine, "search"),
            fmt_seconds(theirs),
            fmt_ratio(ratio(mine, theirs)),
            f"{fmt_length(mine)} / {fmt_length(theirs)}",
        )
    return out


def paper_tasks() -> list[tuple[str, PlanningTask]]:
    catalog = load_catalog()
    tasks = []
    for relative in PAPER_MODELS:
        loaded = load_model(ROOT / relative, catalog)
        if not loaded.is_valid or loaded.model is None:
            raise SystemExit(f"{relative} is not a valid model: {loaded.report}")
        tasks.append((relative, build_task(loaded.model, catalog.get(loaded.model.object_id))))
    return tasks


def run_route(route: str, sizes: list[int], repeat: int, up_time_limit: float) -> dict[str, list[dict[str, Any]]]:
    """Measure one route on every case, in a worker process of its own (see ``measure_in_worker``)."""
    console = Console(width=WIDTH)
    cases: list[tuple[str, PlanningTask]] = [(name, task) for name, task in paper_tasks()]
    cases += [(f"synthetic/{size}", synthetic_task(size)) for size in sizes]
    results: dict[str, list[dict[str, Any]]] = {}
    for name, task in cases:
        console.print(f"  {route}: {name} ...", style="dim", highlight=False)
        run = ours(task) if route == "ours" else through_up(task, up_time_limit)
        results.setdefault("paper" if name.startswith("examples/") else "synthetic", []).append(
            asdict(measure(run, repeat))
        )
    return results


def measure_in_worker(route: str, sizes: list[int], repeat: int, up_time_limit: float) -> dict[str, list[RouteResult]]:
    """Run ``run_route`` in a fresh (spawned) process, so the routes cannot slow each other down.

    In one process, unified-planning's imports and heap (and a forked translator's copy of
    it, where the translator runs in a child) would be charged to our route.
    """
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=1, mp_context=context) as pool:
        raw = pool.submit(run_route, route, sizes, repeat, up_time_limit).result()
    return {group: [RouteResult(**item) for item in items] for group, items in raw.items()}


def parse_args(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--repeat", type=int, help="timed runs per case, after one warm-up (default 5; --quick: 1)")
    parser.add_argument("--sizes", help="synthetic object sizes in parts (default 10,40,80,160; --quick: 10,40,80)")
    parser.add_argument("--up-time-limit", type=float, help="seconds per UP run (default 20; --quick: 10)")
    parser.add_argument("--quick", action="store_true", help="smoke run with the --quick defaults above")
    parser.add_argument("--output", type=Path, default=RESULTS, help="where to write the JSON results")
    args = parser.parse_args(argv)
    defaults = (1, "10,40,80", 10.0) if args.quick else (5, ",".join(map(str, DEFAULT_SIZES)), 20.0)
    args.repeat = defaults[0] if args.repeat is None else args.repeat
    args.sizes = defaults[1] if args.sizes is None else args.sizes
    args.up_time_limit = defaults[2] if args.up_time_limit is None else args.up_time_limit
    if args.repeat < 1:
        parser.error("--repeat must be at least 1")
    try:
        args.size_list = [int(size) for size in args.sizes.split(",") if size.strip()]
    except ValueError:
        parser.error(f"--sizes must be numbers separated by commas, not {args.sizes!r}")
    if not args.size_list or not all(MIN_PARTS <= size <= MAX_PARTS for size in args.size_list):
        parser.error(f"--sizes must be between {MIN_PARTS} and {MAX_PARTS} parts")
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(sys.argv[1:] if argv is None else argv)
    console = Console(width=WIDTH)
    console.print(
        f"[bold]causalplan benchmark[/bold]: median wall time of {args.repeat} run(s) after a warm-up; "
        f"UP limit {args.up_time_limit:g} s; Python {platform.python_version()} on {platform.machine()}"
    )

    sizes = list(args.size_list)
    extra_target = TARGET_PARTS not in sizes
    mine = measure_in_worker("ours", [*sizes, TARGET_PARTS] if extra_target else sizes, args.repeat, 0.0)
    theirs = measure_in_worker("up", sizes, args.repeat, args.up_time_limit)
    target_route = mine["synthetic"].pop() if extra_target else mine["synthetic"][sizes.index(TARGET_PARTS)]
    paper_rows = [
        (name.removeprefix("examples/").removesuffix(".yaml"), a, b)
        for name, a, b in zip(PAPER_MODELS, mine["paper"], theirs["paper"], strict=True)
    ]
    fits = {size: len(synthetic_task(size).obj.fits) for size in sizes}
    synthetic_rows = [
        (f"{size} parts, {fits[size]} fits", a, b)
        for size, a, b in zip(sizes, mine.get("synthetic", []), theirs.get("synthetic", []), strict=True)
    ]
    console.print(table("(a) The paper's models: one plan from a PlanningTask", "model", paper_rows))
    console.print(table("(b) Synthetic objects (seed 0)", "object", synthetic_rows))

    target_met = target_route.median is not None and target_route.median < TARGET_SECONDS and bool(target_route.valid)
    verdict = "[green]yes[/green]" if target_met else "[red]NO[/red]"
    console.print(
        f"{TARGET_PARTS} parts solved under {TARGET_SECONDS:g} s with ours (fd): {verdict} "
        f"(median {fmt_seconds(target_route)}, plan valid: {target_route.valid})"
    )

    report = {
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
        "python": platform.python_version(),
        "machine": platform.machine(),
        "repeat": args.repeat,
        "up_time_limit_s": args.up_time_limit,
        "paper": [
            {"model": name, "ours": a.as_dict(), "up": b.as_dict(), "up_over_ours": ratio(a, b)}
            for name, (_, a, b) in zip(PAPER_MODELS, paper_rows, strict=True)
        ],
        "synthetic": [
            {
                "parts": size,
                "seed": 0,
                "ours": a.as_dict(),
                "up": b.as_dict(),
                "up_over_ours": ratio(a, b),
            }
            for size, (_, a, b) in zip(sizes, synthetic_rows, strict=True)
        ],
        "target": {
            "parts": TARGET_PARTS,
            "seconds": TARGET_SECONDS,
            "median_s": target_route.median,
            "met": target_met,
        },
    }
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
    console.print(f"Results written to {args.output}")
    return 0 if target_met else 1


if __name__ == "__main__":
    sys.exit(main())
