"""Commands over many tasks or trials: compare planners, batch-judge transfer trials."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from causalplan.cli.cluster_options import cluster_options
from causalplan.cli.common import (
    FILE,
    catalog_from,
    catalog_option,
    check_planner,
    exit_on_error,
    fail,
    make_console,
    make_folder,
    planner_option,
    progress_bar,
    time_limit_option,
    val_option,
)

if TYPE_CHECKING:
    from rich.progress import Progress

    from causalplan.cli.cluster_options import ClusterChoice
    from causalplan.objects.catalog import Catalog
    from causalplan.transfer.batch import WrittenResult
    from causalplan.transfer.cluster import JudgeOptions


def _int_list(text: str, what: str) -> list[int]:
    try:
        return [int(item) for item in text.split(",") if item.strip()]
    except ValueError:
        fail("invalid_option", f"{what} must be whole numbers separated by commas, e.g. 10,40,80; got '{text}'.")


@click.command(short_help="Compare planners on tasks: a table, CSV, JSON and a plot.")
@click.argument("tasks", nargs=-1, type=FILE)
@click.option(
    "--planners",
    "planners_option",
    default="fd,fd-opt,mdp,mdp-exact,up:fast-downward",
    help="Comma-separated planners (see `causalplan planners`).",
)
@click.option("--synthetic", help="Also synthetic objects of these sizes, e.g. 10,40,80.")
@click.option("--timeout", type=click.FloatRange(0.5, 3600), default=60.0, help="Seconds per run.")
@click.option("--memory", type=click.IntRange(min=256), default=4096, help="Memory limit per run, in MB.")
@click.option("--repeat", type=click.IntRange(1, 50), default=1, help="Runs per pair; medians are reported.")
@val_option
@click.option(
    "--out", type=FILE, default=Path("out/compare"), help="Folder for compare.csv, compare.json and compare.png."
)
@catalog_option
def compare(
    tasks: tuple[Path, ...],
    planners_option: str,
    synthetic: str | None,
    timeout: float,
    memory: int,
    repeat: int,
    val: bool,
    out: Path,
    catalog: tuple[Path, ...],
) -> None:
    """Run several planners on several tasks, one process per run, and compare them.

    TASKS are model files, or task files (YAML with model:, mapping:, catalog:); the default is
    the paper's examples (found under the current folder's examples/). Prints a table (status,
    plan length, time, success probability, valid), and writes CSV, JSON and a plot of time
    against the number of parts. A planner that fails is a row. Each run starts warm, from a
    fork server that has imported the planners. Every plan is checked by replay and (unless
    --no-val) VAL, those of up: planners also by unified-planning's validator, outside the
    timed part.

    Example: causalplan compare --planners fd,mdp --synthetic 10,40 --out out/compare
    """
    from rich.table import Table

    from causalplan.comparison import report
    from causalplan.comparison import tasks as comparison_tasks
    from causalplan.comparison.runner import compare as run_comparison
    from causalplan.comparison.runner import fork_server, total_runs

    chosen = [name.strip() for name in planners_option.split(",") if name.strip()]
    for name in chosen:
        check_planner(name)
    fork_server(chosen)  # started now, it preloads the planners while the tasks are read
    with exit_on_error():
        sizes = _int_list(synthetic, "--synthetic") if synthetic else []
        if tasks:
            selected = [comparison_tasks.from_argument(path, list(catalog)) for path in tasks]
        else:
            selected = comparison_tasks.default_tasks(Path.cwd())
        selected += [comparison_tasks.synthetic(size) for size in sizes]
    make_folder(out)
    console = make_console()
    report.load_plotting()
    with progress_bar() as progress:
        bar = progress.add_task("comparing", total=total_runs(selected, chosen, repeat))

        def advance(what: str) -> None:
            progress.update(bar, advance=1, description=what)

        rows = run_comparison(selected, chosen, timeout, memory, repeat, advance, val=val)
    table = Table(
        "task",
        "parts",
        "planner",
        "status",
        "length",
        "time",
        "P(success)",
        "valid",
        title=f"median of {repeat} run(s), limit {timeout:g} s per run",
    )
    for row in rows:
        probability = "-" if row.success_probability is None else f"{row.success_probability:.3f}"
        valid = "-" if row.valid is None else ("yes" if row.valid else "NO")
        used = f" ({row.planner_used})" if row.planner_used and row.planner_used != row.planner else ""
        table.add_row(
            row.task,
            str(row.parts),
            row.planner + used,
            row.status,
            "-" if row.plan_length is None else str(row.plan_length),
            report.format_seconds(row.seconds),
            probability,
            valid,
        )
    console.print(table)
    settings = {"planners": chosen, "timeout": timeout, "memory_mb": memory, "repeat": repeat, "val": val}
    report.write_csv(rows, out / "compare.csv")
    report.write_json(rows, out / "compare.json", settings)
    report.plot(rows, out / "compare.png", timeout)
    console.print(f"Wrote {out / 'compare.csv'}, {out / 'compare.json'} and {out / 'compare.png'}")


def _on_cluster(
    trials_file: Path,
    objects: Catalog,
    options: JudgeOptions,
    on_cluster: ClusterChoice,
    out: Path,
    progress: Progress,
) -> list[WrittenResult]:
    """Return the trials' results judged on a Dask cluster, appending each chunk's to verdicts.jsonl as it comes."""
    from causalplan.transfer.cluster import file_chunks, trials_in, write_batch_on_cluster

    parts = file_chunks(trials_file, on_cluster.chunk_size)
    bar = progress.add_task("judging trials", total=trials_in(parts))
    with (out / "verdicts.jsonl").open("w", encoding="utf-8") as stream:

        def write(results: list[WrittenResult]) -> None:
            stream.writelines(result.json_line + "\n" for result in results)
            stream.flush()
            progress.advance(bar, len(results))

        with exit_on_error():
            return write_batch_on_cluster(
                parts, objects, options, address=on_cluster.address, workers=on_cluster.workers, on_chunk=write
            )


TRIALS_FORMAT = 'A batch is JSON Lines (*.jsonl), one {"id", "model", "mapping"} a line, or a JSON/YAML list of them.'
BINARY_PEEK = 8192
"""Bytes read from a trials file's start to tell text from binary: a NUL there is not text (as git and grep judge)."""


def _stop_unless_trials(path: Path) -> None:
    """Exit with 2, saying why, when ``path`` is empty, blank or binary: there is nothing to judge in it."""
    try:
        with path.open("rb") as handle:
            start = handle.read(BINARY_PEEK)
            blank = not start.strip() and not handle.read(1)
    except OSError as exc:
        fail("input_file_error", f"Cannot read the trials file {path}: {exc.strerror}.")
    if blank:
        fail("no_trials", f"{path} is empty: there are no trials to judge. {TRIALS_FORMAT}")
    nul = start.find(b"\x00")
    if nul >= 0:
        fail("unreadable_trials", f"{path} is not text (a NUL byte at byte {nul}): it is not a batch. {TRIALS_FORMAT}")


@click.command(short_help="Judge many transfer trials; write their verdicts and reasons.")
@click.argument("trials_file", metavar="TRIALS", type=FILE)
@planner_option
@time_limit_option
@click.option("--simulate/--no-simulate", default=True, help="Check plans in the physics simulator (as transfer does).")
@val_option
@click.option(
    "--robot",
    is_flag=True,
    help="Also have the Franka Panda carry out each plan that transfers: one it cannot carry out fails "
    "with robot_cannot_execute.",
)
@click.option("--out", type=FILE, default=Path("out/batch"), help="Folder for verdicts.csv and verdicts.json.")
@cluster_options("trials", default_chunk_size=250)
@catalog_option
def batch(
    trials_file: Path,
    planner: str,
    time_limit: float,
    simulate: bool,
    val: bool,
    robot: bool,
    out: Path,
    on_cluster: ClusterChoice | None,
    catalog: tuple[Path, ...],
) -> None:
    """Judge many transfer trials (e.g. a study's participants) and write their verdicts and reasons.

    TRIALS is a JSON Lines file, one {"id", "model", "mapping"} per line (or a JSON/YAML list).
    What can be decided without the planner is (a line that cannot be read, an invalid model
    or mapping, a function no part carries); equal planning problems are solved once. The
    verdicts are those `causalplan transfer` gives one trial at a time; VAL checks each
    distinct plan once (--no-val skips it), and a trial whose plan VAL rejects is undecided.

    With --cluster or --workers the trials go to a Dask cluster in chunks; each finished
    chunk's verdicts are appended to verdicts.jsonl as they come (a run that is stopped keeps
    them), and the final files list every trial in the file's order, as a local run does.

    A trial that cannot be read is judged invalid and the batch goes on; a file with no
    trials at all (empty, blank, binary, or not readable as a whole) is invalid input. Exit 0
    when the verdicts are written, whatever they are; 2 for invalid input.
    """
    import csv
    import time

    from rich.table import Table

    from causalplan.transfer.batch import CSV_COLUMNS, read_trials, repeated_ids, repeated_ids_warning, run_batch
    from causalplan.transfer.cluster import JudgeOptions

    check_planner(planner)
    objects = catalog_from(catalog)
    if not trials_file.is_file():
        fail("file_not_found", f"There is no file {trials_file}.")
    _stop_unless_trials(trials_file)
    judge = None
    if robot:
        from causalplan.transfer.robot_verdict import robot_judged

        judge = robot_judged
    started = time.perf_counter()
    trials = list(read_trials(trials_file)) if on_cluster is None else []
    if trials and trials[0].is_whole_file:
        fail("unreadable_trials", f"{trials_file}: {trials[0].problem}")
    if on_cluster is None and not trials:
        fail("no_trials", f"{trials_file} holds no trials. {TRIALS_FORMAT}")
    make_folder(out)
    with progress_bar() as progress:
        if on_cluster is None:
            bar = progress.add_task("judging trials", total=len(trials))
            judged = run_batch(
                trials, objects, planner, time_limit, simulate, lambda: progress.advance(bar), val=val, judge=judge
            )
            results = [result.written() for result in judged]
        else:
            options = JudgeOptions(planner, time_limit, simulate, val, judge)
            results = _on_cluster(trials_file, objects, options, on_cluster, out, progress)
    seconds = time.perf_counter() - started
    with (out / "verdicts.csv").open("w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=CSV_COLUMNS)
        writer.writeheader()
        writer.writerows(result.row for result in results)
    with (out / "verdicts.json").open("w", encoding="utf-8") as handle:  # a list, one trial a line
        handle.write("[\n" + ",\n".join(result.json_line for result in results) + "\n]\n" if results else "[]\n")
    console = make_console()
    table = Table("verdict", "trials", "decided by", title=f"{len(results)} trials from {trials_file}")
    deciders: dict[str, dict[str, int]] = {}
    for result in results:
        counts = deciders.setdefault(str(result.row["verdict"]), {})
        counts[str(result.row["decided_by"])] = counts.get(str(result.row["decided_by"]), 0) + 1
    for value, counts in sorted(deciders.items()):
        table.add_row(value, str(sum(counts.values())), ", ".join(f"{name} {n}" for name, n in sorted(counts.items())))
    console.print(table)
    repeated = repeated_ids(str(result.row["id"]) for result in results)
    if repeated:
        # markup off: the ids are the file's words, and rich would read "[...]" in them as styles.
        console.print(f"warning[duplicate_ids]: {repeated_ids_warning(repeated)}", style="yellow", markup=False)
    rate = len(results) / seconds if seconds > 0 else float("inf")
    written = [out / "verdicts.csv", out / "verdicts.json"] + ([] if on_cluster is None else [out / "verdicts.jsonl"])
    console.print(
        f"{len(results)} trials in {seconds:.2f} s ({rate:.0f} trials/s). "
        f"Wrote {', '.join(map(str, written[:-1]))} and {written[-1]}"
    )
