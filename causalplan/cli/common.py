"""What every command shares: options, printing, exiting, loading inputs or exiting with 2."""

from __future__ import annotations

import json
import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

import click

if TYPE_CHECKING:
    from rich.console import Console
    from rich.progress import Progress

    from causalplan.causal.diagnostics import Report
    from causalplan.causal.model import CausalModel, Labelling
    from causalplan.objects.catalog import Catalog
    from causalplan.pddl.task import PlanningTask
    from causalplan.planners.result import PlanResult

EXIT_OK, EXIT_NO_PLAN, EXIT_INVALID, EXIT_UNDECIDED = 0, 1, 2, 3
EXIT_CODES = (
    "Exit codes: 0 done (yes), 1 no (no plan, no transfer, beyond the limits), 2 invalid input, "
    "3 could not decide (the planner timed out or failed)."
)
"""The one exit-code table every command keeps, as `causalplan --help` and the README give it."""

FILE = click.Path(path_type=Path)
catalog_option = click.option(
    "--catalog",
    type=FILE,
    multiple=True,
    show_default=False,
    help="A folder of your own object files (YAML/JSON) to add to the built-in catalog. Repeatable.",
)
json_option = click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON instead of sentences.")
planner_option = click.option(
    "--planner",
    "-p",
    default="auto",
    help="auto: Fast Downward when every fit that matters is certain, else the MDP (each falls back to the "
    "other). Also fd (LAMA, fast), fd-opt (shortest plan), mdp (most reliable plan, heuristic search), "
    "mdp-exact (the same over every state), up:<engine>. `causalplan planners` lists them.",
)
time_limit_option = click.option(
    "--time-limit",
    type=click.FloatRange(0.1, 3600),
    default=30.0,
    help="Seconds the planner may run before it is stopped.",
)

val_option = click.option(
    "--val/--no-val",
    default=True,
    show_default=True,
    help="Check every plan with VAL (KCL's plan validator) on the PDDL as you wrote it, one derived clause "
    "per rule, beside the replay. A plan VAL rejects is an error that quotes VAL.",
)


def exit_with(code: int) -> NoReturn:
    raise SystemExit(code)


def status_exit_code(status: str) -> int:
    """Return the exit code of a planner's outcome: 0 solved, 1 proven unsolvable, 3 undecided (timeout, ...)."""
    from causalplan.planners.result import PlanStatus

    if status == PlanStatus.SOLVED:
        return EXIT_OK
    return EXIT_NO_PLAN if status == PlanStatus.UNSOLVABLE else EXIT_UNDECIDED


def say(message: str = "", *, err: bool = False) -> None:
    """Print one line; click drops the colours when the stream is not a terminal."""
    click.echo(message, err=err)


def mark(ok: bool, yes: str = "yes", no: str = "no") -> str:
    return click.style(yes, fg="green") if ok else click.style(no, fg="red")


def dim(text: str) -> str:
    return click.style(text, dim=True)


def make_console(stderr: bool = False) -> Console:
    from rich.console import Console

    stream = sys.stderr if stderr else sys.stdout
    # Piped output gets a wide page, so tables are not cut to 80 columns in files and CI logs.
    width = None if stream.isatty() else 160
    return Console(stderr=stderr, highlight=False, soft_wrap=True, width=width)


def progress_bar() -> Progress:
    """Return a progress bar on stderr (description, bar, done/total, time), gone when it ends."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    return Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=make_console(stderr=True),
        transient=True,
    )


def fail(code: str, message: str) -> NoReturn:
    say(f"{click.style('error', fg='red', bold=True)}[{code}]: {message}", err=True)
    exit_with(EXIT_INVALID)


@contextmanager
def exit_on_error() -> Iterator[None]:
    """Print a ``CausalPlanError`` raised inside as its code and message, and exit with 2."""
    from causalplan.errors import CausalPlanError

    try:
        yield
    except CausalPlanError as exc:
        fail(exc.code, exc.message)


@contextmanager
def writing(path: Path, verb: str = "write") -> Iterator[None]:
    """Exit with 2, naming ``path``, when writing inside fails (no such folder, no permission, disk full)."""
    try:
        yield
    except OSError as exc:
        fail("output_not_writable", f"Cannot {verb} {path}: {exc.strerror}.")


def make_folder(folder: Path) -> None:
    """Create ``folder`` (and its parents) or exit with 2 saying why not."""
    with writing(folder, "create"):
        folder.mkdir(parents=True, exist_ok=True)


def catalog_from(folders: Sequence[Path]) -> Catalog:
    from causalplan.objects.catalog import load_catalog

    with exit_on_error():
        return load_catalog(folders)


def print_json(data: object) -> None:
    sys.stdout.write(json.dumps(data, indent=2, ensure_ascii=False) + "\n")


def print_report(report: Report, *, err: bool = False) -> None:
    for diagnostic in report.diagnostics:
        color = "red" if diagnostic.severity.value == "error" else "yellow"
        where = diagnostic.location.describe()
        severity = click.style(diagnostic.severity.value, fg=color, bold=True)
        say(f"{severity}[{diagnostic.code}]{' ' + where if where else ''}: {diagnostic.message}", err=err)
        if diagnostic.hint:
            say(f"  {dim('hint:')} {diagnostic.hint}", err=err)


def check_planner(planner: str) -> None:
    from causalplan.planners.pipeline import PLANNERS

    if planner not in PLANNERS:
        fail("unknown_planner", f"Unknown planner '{planner}'; choose one of: {', '.join(PLANNERS)}.")


def looks_like_a_mapping(path: Path) -> bool:
    """Return whether a file has a mapping's fields (object, functions) and nothing else.

    Used only for advice after a model is found invalid: a file is read as a model or a
    mapping by the command and its options, never by what it holds.
    """
    from causalplan.causal.documents import read_document

    data, _, problems = read_document(path)
    return not problems and isinstance(data, dict) and bool(data) and set(data) <= {"object", "functions"}


def stop_if_invalid(report: Report, path: Path, as_json: bool, advice: str = "") -> None:
    """Print the problems of an invalid input (as JSON or words) and exit with 2; return if it is valid."""
    if report.is_valid:
        return
    if as_json:
        print_json({"status": "invalid", "file": str(path), **report.as_dict()})
    else:
        print_report(report, err=True)
        if advice:
            say(advice, err=True)
    exit_with(EXIT_INVALID)


def load_valid_model(path: Path, objects: Catalog, as_json: bool) -> CausalModel:
    from causalplan.inputs import load_model

    loaded = load_model(path, objects)
    advice = (
        f"{path}: the model is invalid, so there is nothing to plan. Run `causalplan check {path}` after fixing it."
    )
    stop_if_invalid(loaded.report, path, as_json, advice)
    assert loaded.model is not None
    return loaded.model


def load_valid_mapping(path: Path, objects: Catalog, as_json: bool) -> Labelling:
    from causalplan.inputs import load_mapping

    loaded = load_mapping(path, objects)
    stop_if_invalid(loaded.report, path, as_json)
    assert loaded.mapping is not None
    return loaded.mapping


def load_task(model: Path, mapping: Path | None, objects: Catalog, as_json: bool) -> PlanningTask:
    """Return the planning task of a valid model (on a valid mapping's object, if given); else exit with 2."""
    from causalplan.pddl.task import catalog_task

    causal_model = load_valid_model(model, objects, as_json)
    labelling = load_valid_mapping(mapping, objects, as_json) if mapping else None
    return catalog_task(causal_model, objects, labelling)


def write_pddl(folder: Path, domain: str, problem: str) -> None:
    with writing(folder, "write the PDDL to"):
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "domain.pddl").write_text(domain, encoding="utf-8")
        (folder / "problem.pddl").write_text(problem, encoding="utf-8")


def print_plan(result: PlanResult) -> None:
    if not result.has_plan:
        say(f"{click.style('No plan', fg='red', bold=True)} ({result.status.value}): {result.message}")
        return
    if not result.steps:
        say("The goal already holds: no step is needed.")
    for number, step in enumerate(result.steps, start=1):
        say(f"{number}. {step.text}")
    replayed = dim(f"{len(result.steps)} step(s) by {result.planner_used}, replayed: goal holds under the model;")
    say(f"{replayed} the real object works: {mark(result.valid_under_true_mechanism)}")
    if result.success_probability is not None and result.success_probability < 1.0:
        attempts = "unknown" if result.expected_actions is None else f"{result.expected_actions:.2f}"
        say(f"Success probability {result.success_probability:.4f} (some fits may fail); expected attempts {attempts}.")
    if result.mdp is not None:
        solved = "the highest success probability"
        if result.mdp.get("objective") == "attempts":
            solved = f"the fewest expected attempts for success probability {result.mdp.get('required_success')}"
        say(dim(f"Solved for {solved}; {result.mdp.get('optimality')}."))
    checked = ", ".join(f"{name} {verdict}" for name, verdict in result.validated_by.items() if name != "replay")
    if checked:
        say(dim(f"Checked by {checked}."))
    if result.fallback_reason:
        say(dim(f"Used {result.planner_used} because {result.fallback_reason}."))
    if result.message:
        say(click.style(result.message, fg="yellow"))
