"""The comparison's outputs: a table for people, CSV and JSON for programs, a plot for the eye."""

from __future__ import annotations

import csv
import importlib
import json
import threading
from pathlib import Path

from causalplan.comparison.runner import RunRecord

COLUMNS = (
    "task",
    "parts",
    "planner",
    "status",
    "planner_used",
    "plan_length",
    "seconds",
    "success_probability",
    "valid",
    "repeats",
    "message",
)


def format_seconds(seconds: float | None) -> str:
    """Return a duration for the table: ms below a second."""
    if seconds is None:
        return "-"
    return f"{seconds * 1000:.1f} ms" if seconds < 1 else f"{seconds:.2f} s"


def write_csv(rows: list[RunRecord], path: Path) -> None:
    """Write one line per (task, planner)."""
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=COLUMNS)
        writer.writeheader()
        for row in rows:
            writer.writerow(row.as_dict())


def write_json(rows: list[RunRecord], path: Path, settings: dict[str, object]) -> None:
    """Write the rows with the settings that produced them."""
    path.write_text(
        json.dumps({"settings": settings, "runs": [row.as_dict() for row in rows]}, indent=2) + "\n", encoding="utf-8"
    )


def load_plotting() -> threading.Thread:
    """Start importing matplotlib in a thread and return it: the plot then need not wait for the import.

    Meant to run beside the runs, while this process only waits for their records.
    """
    loading = threading.Thread(target=importlib.import_module, args=("matplotlib.figure",), daemon=True)
    loading.start()
    return loading


def plot(rows: list[RunRecord], path: Path, time_limit: float) -> None:
    """Plot planning time against the number of parts, one line per planner, log scale.

    Runs without a plan (timeout, too large, error) are drawn hollow on the time-limit line.
    """
    from matplotlib.figure import Figure

    figure = Figure(figsize=(8, 5))
    axes = figure.add_subplot()
    planners = sorted({row.planner for row in rows})
    markers = "osD^v<>ph*"
    for index, planner in enumerate(planners):
        mine = sorted((row for row in rows if row.planner == planner), key=lambda row: (row.parts, row.task))
        by_size: dict[int, list[float]] = {}
        for row in mine:
            if row.status in ("solved", "unsolvable") and row.seconds is not None:
                by_size.setdefault(row.parts, []).append(row.seconds)
        sizes = sorted(by_size)
        line = axes.plot(
            sizes,
            [max(by_size[size]) for size in sizes],
            marker=markers[index % len(markers)],
            label=planner,
            linewidth=1.5,
        )[0]
        failed = [row.parts for row in mine if row.status not in ("solved", "unsolvable")]
        if failed:  # hollow markers at the limit, nudged apart so planners failing together all show
            nudge = 1.0 + 0.04 * (index - len(planners) / 2)
            axes.scatter(
                [size * nudge for size in failed],
                [time_limit] * len(failed),
                s=70,
                linewidths=1.5,
                marker=markers[index % len(markers)],
                facecolors="none",
                edgecolors=line.get_color(),
            )
    axes.set_xscale("log")
    axes.set_yscale("log")
    all_sizes = sorted({row.parts for row in rows})
    axes.set_xticks(all_sizes, [str(size) for size in all_sizes])
    axes.minorticks_off()
    axes.set_xlabel("parts in the object (log scale)")
    axes.set_ylabel("planning time, seconds (log scale)")
    axes.set_title("Planning time by planner (hollow markers on the dotted line: no plan within the limit)")
    axes.axhline(time_limit, color="#999999", linestyle=":", linewidth=1)
    axes.grid(True, which="both", alpha=0.3)
    axes.legend(fontsize=9)
    figure.tight_layout()
    figure.savefig(path, dpi=120)
