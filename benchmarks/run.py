"""Time our direct Fast Downward route against unified-planning's, on the paper's models and synthetic objects.

    python benchmarks/run.py [--repeat K] [--sizes 10,40,80,160] [--quick] [--up-time-limit S]

Both routes start from the same ``PlanningTask``: ours is ``plan_task(task, "fd")`` (compile to
PDDL with derived predicates, translate in a forked worker, search, replay); UP's is
``solve_with_up(task, "fast-downward")`` (build the axiom-free UP problem, then
``OneshotPlanner(name="fast-downward")``, which writes PDDL and runs FD's driver). Every case
is run once to warm up, then ``--repeat`` times; the tables show medians of wall time.
Results also go to ``benchmarks/results/latest.json``. See benchmarks/README.md.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

from rich.console import Console
from rich.table import Table

from causalplan.inputs import load_model
from causalplan.objects.catalog import load_catalog
from causalplan.objects.synthetic import synthetic_task
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


def parse_args(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="timed runs per case, after one warm-up (default 5)")
    parser.add_argument(
        "--sizes",
        default=",".join(map(str, DEFAULT_SIZES)),
        help="synthetic object sizes in parts (default 10,40,80,160)",
    )
    parser.add_argument("--up-time-limit", type=float, default=20.0, help="seconds per UP run (default 20)")
    parser.add_argument("--quick", action="store_true", help="smoke run: 1 repeat, sizes 10,40,80, UP limit 10 s")
    parser.add_argument("--output", type=Path, default=RESULTS, help="where to write the JSON results")
    args = parser.parse_args(argv)
    if args.quick:
        args.repeat, args.sizes, args.up_time_limit = 1, "10,40,80", min(args.up_time_limit, 10.0)
    if args.repeat < 1:
        parser.error("--repeat must be at least 1")
    try:
        args.size_list = [int(size) for size in args.sizes.split(",") if size.strip()]
    except ValueError:
        parser.error(f"--sizes must be numbers separated by commas, not {args.sizes!r}")
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(sys.argv[1:] if argv is None else argv)
    console = Console()
    console.print(
        f"[bold]causalplan benchmark[/bold]: median wall time of {args.repeat} run(s) after a warm-up; "
        f"UP limit {args.up_time_limit:g} s; Python {platform.python_version()} on {platform.machine()}"
    )

    paper_rows = []
    for name, task in paper_tasks():
        console.print(f"  {name} ...", style="dim")
        paper_rows.append(
            (name, measure(ours(task), args.repeat), measure(through_up(task, args.up_time_limit), args.repeat))
        )
    console.print(table("(a) The paper's models: one plan from a PlanningTask", "model", paper_rows))

    synthetic_rows = []
    for size in args.size_list:
        console.print(f"  synthetic, {size} parts ...", style="dim")
        task = synthetic_task(size)
        synthetic_rows.append(
            (
                f"{size} parts ({len(task.obj.fits)} fits)",
                measure(ours(task), args.repeat),
                measure(through_up(task, args.up_time_limit), args.repeat),
            )
        )
    console.print(table("(b) Synthetic objects (seed 0)", "object", synthetic_rows))

    target_route = next(
        (mine for size, (_, mine, _) in zip(args.size_list, synthetic_rows, strict=True) if size == TARGET_PARTS), None
    )
    if target_route is None:
        console.print(f"  synthetic, {TARGET_PARTS} parts (for the target line) ...", style="dim")
        target_route = measure(ours(synthetic_task(TARGET_PARTS)), args.repeat)
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
            {"model": name, "ours": mine.as_dict(), "up": theirs.as_dict(), "up_over_ours": ratio(mine, theirs)}
            for name, mine, theirs in paper_rows
        ],
        "synthetic": [
            {
                "parts": size,
                "seed": 0,
                "ours": mine.as_dict(),
                "up": theirs.as_dict(),
                "up_over_ours": ratio(mine, theirs),
            }
            for size, (_, mine, theirs) in zip(args.size_list, synthetic_rows, strict=True)
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
