"""The ``causalplan`` command line: check, plan, transfer, compile, graph, objects, and more.

Built on click, and each command imports what it needs when it runs, so ``causalplan --help``
and ``causalplan plan`` start fast: the sentences are styled with click, and rich (tables,
progress bars) is loaded only by the commands that draw them. Exit codes: 0 success, 1 no
plan / no transfer, 2 invalid input, 3 the planner could not decide.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
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
    from causalplan.sim import SimulationReport
    from causalplan.transfer.verdict import TransferVerdict

EXIT_OK, EXIT_NO_PLAN, EXIT_INVALID, EXIT_UNDECIDED = 0, 1, 2, 3


@click.group(
    name="causalplan",
    context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 110, "show_default": True},
    epilog="Exit codes: 0 done, 1 no plan or no transfer, 2 invalid input, 3 the planner could not decide. "
    "Run `causalplan COMMAND --help` for a command's options.",
)
def app() -> None:
    """Teach a robot why an object works, then plan with that knowledge.

    A model file says which parts of an object carry which functions (step 1) and keyword rules
    such as 'provide electricity AND turn electricity into light CAUSES light' (step 2).
    A mapping file gives another object's parts the model's functions (step 3).

    Start with: causalplan plan examples/paper/desk_lamp.yaml
    """


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
    help="auto: Fast Downward, or the exact MDP when a fit may fail or FD fails. Also fd (LAMA, fast), "
    "fd-opt (shortest plan), mdp (most reliable plan), up:<engine>. `causalplan planners` lists them.",
)
time_limit_option = click.option(
    "--time-limit",
    type=click.FloatRange(0.1, 3600),
    default=30.0,
    help="Seconds the planner may run before it is stopped.",
)


def _exit(code: int) -> NoReturn:
    raise SystemExit(code)


def _say(message: str = "", *, err: bool = False) -> None:
    """Print one line; click drops the colours when the stream is not a terminal."""
    click.echo(message, err=err)


def _mark(ok: bool, yes: str = "yes", no: str = "no") -> str:
    return click.style(yes, fg="green") if ok else click.style(no, fg="red")


def _dim(text: str) -> str:
    return click.style(text, dim=True)


def _console(stderr: bool = False) -> Console:
    from rich.console import Console

    stream = sys.stderr if stderr else sys.stdout
    # Piped output gets a wide page, so tables are not cut to 80 columns in files and CI logs.
    width = None if stream.isatty() else 160
    return Console(stderr=stderr, highlight=False, soft_wrap=True, width=width)


def _progress_bar() -> Progress:
    """Return a progress bar on stderr (description, bar, done/total, time), gone when it ends."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    return Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=_console(stderr=True),
        transient=True,
    )


def _fail(code: str, message: str) -> NoReturn:
    _say(f"{click.style('error', fg='red', bold=True)}[{code}]: {message}", err=True)
    _exit(EXIT_INVALID)


def _catalog(folders: Sequence[Path]) -> Catalog:
    from causalplan.errors import CausalPlanError
    from causalplan.objects.catalog import load_catalog

    try:
        return load_catalog(folders)
    except CausalPlanError as exc:
        _fail(exc.code, exc.message)


def _print_json(data: object) -> None:
    sys.stdout.write(json.dumps(data, indent=2, ensure_ascii=False) + "\n")


def _print_report(report: Report, *, err: bool = False) -> None:
    for diagnostic in report.diagnostics:
        color = "red" if diagnostic.severity.value == "error" else "yellow"
        where = diagnostic.location.describe()
        severity = click.style(diagnostic.severity.value, fg=color, bold=True)
        _say(f"{severity}[{diagnostic.code}]{' ' + where if where else ''}: {diagnostic.message}", err=err)
        if diagnostic.hint:
            _say(f"  {_dim('hint:')} {diagnostic.hint}", err=err)


def _check_planner(planner: str) -> None:
    from causalplan.planners.pipeline import PLANNERS

    if planner not in PLANNERS:
        _fail("unknown_planner", f"Unknown planner '{planner}'; choose one of: {', '.join(PLANNERS)}.")


def _is_mapping_file(path: Path) -> bool:
    """Return whether a file looks like a step-3 mapping (no 'rules' field) rather than a model."""
    from causalplan.causal.documents import read_document

    data, _, problems = read_document(path)
    return not problems and isinstance(data, dict) and "rules" not in data


@app.command(short_help="Validate a model or mapping: what is wrong, where, how to fix it.")
@click.argument("model", type=FILE)
@json_option
@catalog_option
def check(model: Path, as_json: bool, catalog: tuple[Path, ...]) -> None:
    """Validate a model (or mapping): errors with a code, where, and how to fix them.

    MODEL is a model file (or a step-3 mapping file) in YAML or JSON. Exit 0 when valid
    (warnings allowed), 2 when invalid.
    """
    from causalplan.inputs import load_mapping, load_model

    objects = _catalog(catalog)
    kind = "mapping" if _is_mapping_file(model) else "model"
    report = load_mapping(model, objects).report if kind == "mapping" else load_model(model, objects).report
    if as_json:
        _print_json({"file": str(model), "kind": kind, **report.as_dict()})
    else:
        _print_report(report)
        verdict = _mark(report.is_valid, "valid", "invalid")
        _say(f"{model}: {kind} is {verdict} ({len(report.errors)} error(s), {len(report.warnings)} warning(s))")
    _exit(EXIT_OK if report.is_valid else EXIT_INVALID)


def _stop_if_invalid(report: Report, path: Path, as_json: bool, advice: str = "") -> None:
    """Print the problems of an invalid input (as JSON or words) and exit with 2; return if it is valid."""
    if report.is_valid:
        return
    if as_json:
        _print_json({"status": "invalid", "file": str(path), **report.as_dict()})
    else:
        _print_report(report, err=True)
        if advice:
            _say(advice, err=True)
    _exit(EXIT_INVALID)


def _load_valid_model(path: Path, objects: Catalog, as_json: bool) -> CausalModel:
    from causalplan.inputs import load_model

    loaded = load_model(path, objects)
    advice = (
        f"{path}: the model is invalid, so there is nothing to plan. Run `causalplan check {path}` after fixing it."
    )
    _stop_if_invalid(loaded.report, path, as_json, advice)
    assert loaded.model is not None
    return loaded.model


def _load_valid_mapping(path: Path, objects: Catalog, as_json: bool) -> Labelling:
    from causalplan.inputs import load_mapping

    loaded = load_mapping(path, objects)
    _stop_if_invalid(loaded.report, path, as_json)
    assert loaded.mapping is not None
    return loaded.mapping


def _load_task(model: Path, mapping: Path | None, objects: Catalog, as_json: bool) -> PlanningTask:
    """Return the planning task of a valid model (on a valid mapping's object, if given); else exit with 2."""
    from causalplan.pddl.task import build_task

    causal_model = _load_valid_model(model, objects, as_json)
    labelling = _load_valid_mapping(mapping, objects, as_json) if mapping else None
    return build_task(causal_model, objects.get((labelling or causal_model.labelling).object_id), labelling)


def _write_pddl(folder: Path, domain: str, problem: str) -> None:
    try:
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "domain.pddl").write_text(domain, encoding="utf-8")
        (folder / "problem.pddl").write_text(problem, encoding="utf-8")
    except OSError as exc:
        _fail("output_not_writable", f"Cannot write the PDDL to {folder}: {exc.strerror}.")


def _print_plan(result: PlanResult) -> None:
    if not result.has_plan:
        _say(f"{click.style('No plan', fg='red', bold=True)} ({result.status.value}): {result.message}")
        return
    if not result.steps:
        _say("The goal already holds: no step is needed.")
    for number, step in enumerate(result.steps, start=1):
        _say(f"{number}. {step.text}")
    replayed = _dim(f"{len(result.steps)} step(s) by {result.planner_used}, replayed: goal holds under the model;")
    _say(f"{replayed} the real object works: {_mark(result.valid_under_true_mechanism)}")
    if result.success_probability is not None and result.success_probability < 1.0:
        _say(
            f"Success probability {result.success_probability:.4f} (some fits may fail); expected attempts "
            f"{result.expected_actions:.2f}."
        )
    if result.validated_by_up is not None:
        _say(f"unified-planning's validator: {_mark(result.validated_by_up, 'valid', 'INVALID')}")
    if result.fallback_reason:
        _say(_dim(f"Used {result.planner_used} because {result.fallback_reason}."))
    if result.message:
        _say(click.style(result.message, fg="yellow"))


@app.command(short_help="Plan the assembly that makes the model's goal hold.")
@click.argument("model", type=FILE)
@click.option(
    "--mapping",
    "-m",
    type=FILE,
    help="A step-3 mapping: plan for that object instead, with its parts carrying the model's functions.",
)
@planner_option
@time_limit_option
@click.option("--pddl-out", type=FILE, help="Also write domain.pddl and problem.pddl to this folder.")
@click.option("--up-validate", is_flag=True, help="Also check the plan with unified-planning's plan validator.")
@json_option
@catalog_option
def plan(
    model: Path,
    mapping: Path | None,
    planner: str,
    time_limit: float,
    pddl_out: Path | None,
    up_validate: bool,
    as_json: bool,
    catalog: tuple[Path, ...],
) -> None:
    """Plan how to assemble the object so the model's goal holds, and print the steps.

    MODEL is the causal model file (YAML or JSON). Every plan is replayed on the object before
    it is shown: against the model, and against the object's true mechanism. Exit 0 with a
    plan, 1 without one, 2 for invalid input.
    """
    from causalplan.errors import CausalPlanError
    from causalplan.planners.pipeline import plan_task

    _check_planner(planner)
    objects = _catalog(catalog)
    task = _load_task(model, mapping, objects, as_json)
    try:
        result = plan_task(
            task,
            planner,
            time_limit,
            include_pddl=pddl_out is not None,
            validate_up=up_validate,
        )
    except CausalPlanError as exc:
        _fail(exc.code, exc.message)
    if pddl_out is not None and result.pddl is not None:
        _write_pddl(pddl_out, result.pddl["domain"], result.pddl["problem"])
    if as_json:
        data = result.as_dict()
        data.pop("pddl", None)
        _print_json(data)
    else:
        _print_plan(result)
    _exit(EXIT_OK if result.has_plan else EXIT_NO_PLAN)


def _print_verdict(verdict: TransferVerdict) -> None:
    colors = {"transfers": "green", "fails": "red", "invalid": "red", "undecided": "yellow"}
    kind = f" ({verdict.generalization}-generalization)" if verdict.generalization in ("near", "far") else ""
    value = click.style(verdict.verdict.value, fg=colors[verdict.verdict.value], bold=True)
    _say(f"{value}: {verdict.training_object} → {verdict.test_object}{kind}, decided by {verdict.decided_by}")
    for reason in verdict.reasons:
        severity = click.style(reason.severity.value, fg="red" if reason.severity.value == "error" else "yellow")
        _say(f"  {severity}[{reason.code}]: {reason.message}")
    if verdict.plan is not None and verdict.plan.has_plan:
        _say("Plan:")
        for number, step in enumerate(verdict.plan.steps, start=1):
            _say(f"  {number}. {step.text}")


@app.command(short_help="Test whether a model transfers to a new object (step 3).")
@click.argument("model", type=FILE)
@click.argument("mapping", type=FILE)
@planner_option
@time_limit_option
@json_option
@catalog_option
def transfer(
    model: Path, mapping: Path, planner: str, time_limit: float, as_json: bool, catalog: tuple[Path, ...]
) -> None:
    """Test whether a model transfers to a new object (step 3), and say why or why not.

    MODEL is the causal model of the training object (steps 1-2); MAPPING maps a new object's
    parts to the model's functions (step 3). Exit 0 when it transfers, 1 when it fails, 2 when
    the model or mapping is invalid, 3 when the planner could not decide (e.g. it timed out).
    """
    from causalplan.errors import CausalPlanError
    from causalplan.inputs import load_mapping, load_model
    from causalplan.transfer.verdict import transfer_verdict

    _check_planner(planner)
    objects = _catalog(catalog)
    loaded_model, loaded_mapping = load_model(model, objects), load_mapping(mapping, objects)
    try:
        verdict = transfer_verdict(loaded_model, loaded_mapping, objects, planner, time_limit)
    except CausalPlanError as exc:
        _fail(exc.code, exc.message)
    if as_json:
        _print_json(verdict.as_dict())
    else:
        _print_verdict(verdict)
    _exit(verdict.verdict.exit_code)


@app.command(name="compile", short_help="Write the model as PDDL (domain and problem), without planning.")
@click.argument("model", type=FILE)
@click.option("--out", "-o", type=FILE, required=True, help="Folder to write domain.pddl and problem.pddl to.")
@click.option("--mapping", "-m", type=FILE, help="Compile for a step-3 mapping's object.")
@catalog_option
def compile_command(model: Path, out: Path, mapping: Path | None, catalog: tuple[Path, ...]) -> None:
    """Compile a model to a PDDL 2.2 domain and problem with derived predicates, without planning.

    MODEL is the causal model file (YAML or JSON).
    """
    from causalplan.pddl.writer import compile_task

    objects = _catalog(catalog)
    compiled = compile_task(_load_task(model, mapping, objects, False))
    _write_pddl(out, compiled.domain, compiled.problem)
    _say(f"Wrote {out / 'domain.pddl'} and {out / 'problem.pddl'}")


@app.command(short_help="Draw the model's causal graph (PNG, SVG, PDF or DOT).")
@click.argument("model", type=FILE)
@click.option(
    "--out",
    "-o",
    type=FILE,
    help="Write a picture (.png, .svg, .pdf) or Graphviz text (.dot); without it, DOT goes to the screen.",
)
@json_option
@catalog_option
def graph(model: Path, out: Path | None, as_json: bool, catalog: tuple[Path, ...]) -> None:
    """Draw the model's causal graph, left to right from the parts' functions to the goal.

    MODEL is the causal model file (YAML or JSON). Invalid models are drawn too (causes
    nothing produces are red), to help see what is wrong.
    """
    from causalplan.causal.render import PICTURE_SUFFIXES, draw, to_dot, to_json
    from causalplan.inputs import load_model

    loaded = load_model(model, _catalog(catalog))
    if loaded.model is None:
        _print_report(loaded.report, err=True)
        _exit(EXIT_INVALID)
    if as_json:
        _print_json(to_json(loaded.model))
    elif out is None:
        sys.stdout.write(to_dot(loaded.model))
    elif out.suffix.lower() == ".dot":
        try:
            out.write_text(to_dot(loaded.model), encoding="utf-8")
        except OSError as exc:
            _fail("output_not_writable", f"Cannot write {out}: {exc.strerror}.")
    elif out.suffix.lower() in PICTURE_SUFFIXES:
        try:
            draw(loaded.model, out)
        except OSError as exc:
            _fail("output_not_writable", f"Cannot write {out}: {exc.strerror}.")
    else:
        _fail("unknown_format", f"Cannot tell the format of {out}: use .png, .svg, .pdf or .dot.")
    if out is not None:
        _say(f"Wrote {out}", err=True)
    _exit(EXIT_OK if loaded.report.is_valid else EXIT_INVALID)


def _int_list(text: str, what: str) -> list[int]:
    try:
        return [int(item) for item in text.split(",") if item.strip()]
    except ValueError:
        _fail("invalid_option", f"{what} must be whole numbers separated by commas, e.g. 10,40,80; got '{text}'.")


@app.command(short_help="Compare planners on tasks: a table, CSV, JSON and a plot.")
@click.argument("tasks", nargs=-1, type=FILE)
@click.option(
    "--planners",
    "planners_option",
    default="fd,fd-opt,mdp,up:fast-downward",
    help="Comma-separated planners (see `causalplan planners`).",
)
@click.option("--synthetic", help="Also synthetic objects of these sizes, e.g. 10,40,80.")
@click.option("--timeout", type=click.FloatRange(0.5, 3600), default=60.0, help="Seconds per run.")
@click.option("--memory", type=click.IntRange(min=256), default=4096, help="Memory limit per run, in MB.")
@click.option("--repeat", type=click.IntRange(1, 50), default=1, help="Runs per pair; medians are reported.")
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
    out: Path,
    catalog: tuple[Path, ...],
) -> None:
    """Run several planners on several tasks, one process per run, and compare them.

    TASKS are model files, or task files (YAML with model:, mapping:, catalog:); the default is
    the paper's examples (found under the current folder's examples/). Prints a table (status,
    plan length, time, success probability, valid), and writes CSV, JSON and a plot of time
    against the number of parts. A planner that fails is a row.
    """
    from rich.table import Table

    from causalplan.comparison import report
    from causalplan.comparison import tasks as comparison_tasks
    from causalplan.comparison.runner import compare as run_comparison
    from causalplan.comparison.runner import total_runs
    from causalplan.errors import CausalPlanError

    chosen = [name.strip() for name in planners_option.split(",") if name.strip()]
    for name in chosen:
        _check_planner(name)
    try:
        sizes = _int_list(synthetic, "--synthetic") if synthetic else []
        if tasks:
            selected = [comparison_tasks.from_argument(path, list(catalog)) for path in tasks]
        else:
            selected = comparison_tasks.default_tasks(Path.cwd())
        selected += [comparison_tasks.synthetic(size) for size in sizes]
    except CausalPlanError as exc:
        _fail(exc.code, exc.message)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        _fail("output_not_writable", f"Cannot create {out}: {exc.strerror}.")
    console = _console()
    with _progress_bar() as progress:
        bar = progress.add_task("comparing", total=total_runs(selected, chosen, repeat))

        def advance(what: str) -> None:
            progress.update(bar, advance=1, description=what)

        rows = run_comparison(selected, chosen, timeout, memory, repeat, advance)
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
    settings = {"planners": chosen, "timeout": timeout, "memory_mb": memory, "repeat": repeat}
    report.write_csv(rows, out / "compare.csv")
    report.write_json(rows, out / "compare.json", settings)
    report.plot(rows, out / "compare.png", timeout)
    console.print(f"Wrote {out / 'compare.csv'}, {out / 'compare.json'} and {out / 'compare.png'}")


@app.command(short_help="Judge many transfer trials; write their verdicts and reasons.")
@click.argument("trials_file", metavar="TRIALS", type=FILE)
@planner_option
@time_limit_option
@click.option("--simulate/--no-simulate", default=True, help="Check plans in the physics simulator (as transfer does).")
@click.option("--out", type=FILE, default=Path("out/batch"), help="Folder for verdicts.csv and verdicts.json.")
@catalog_option
def batch(
    trials_file: Path, planner: str, time_limit: float, simulate: bool, out: Path, catalog: tuple[Path, ...]
) -> None:
    """Judge many transfer trials (e.g. a study's participants) and write their verdicts and reasons.

    TRIALS is a JSON Lines file, one {"id", "model", "mapping"} per line (or a JSON/YAML list).
    What can be decided without the planner is (a line that cannot be read, an invalid model
    or mapping, a function no part carries); equal planning problems are solved once. The
    verdicts are those `causalplan transfer` gives one trial at a time.
    """
    import csv
    import time

    from rich.table import Table

    from causalplan.transfer.batch import CSV_COLUMNS, read_trials, run_batch

    _check_planner(planner)
    objects = _catalog(catalog)
    if not trials_file.is_file():
        _fail("file_not_found", f"There is no file {trials_file}.")
    trials = list(read_trials(trials_file))
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        _fail("output_not_writable", f"Cannot create {out}: {exc.strerror}.")
    started = time.perf_counter()
    with _progress_bar() as progress:
        bar = progress.add_task("judging trials", total=len(trials))
        results = run_batch(trials, objects, planner, time_limit, simulate, lambda: progress.advance(bar))
    seconds = time.perf_counter() - started
    with (out / "verdicts.csv").open("w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=CSV_COLUMNS)
        writer.writeheader()
        writer.writerows(result.row() for result in results)
    (out / "verdicts.json").write_text(
        json.dumps([{"id": result.trial_id, **result.verdict.as_dict()} for result in results], indent=1) + "\n",
        encoding="utf-8",
    )
    console = _console()
    table = Table("verdict", "trials", "decided by", title=f"{len(results)} trials from {trials_file}")
    verdicts = sorted({result.verdict.verdict.value for result in results})
    for value in verdicts:
        mine = [result for result in results if result.verdict.verdict.value == value]
        deciders: dict[str, int] = {}
        for result in mine:
            deciders[result.verdict.decided_by] = deciders.get(result.verdict.decided_by, 0) + 1
        table.add_row(value, str(len(mine)), ", ".join(f"{name} {count}" for name, count in sorted(deciders.items())))
    console.print(table)
    rate = len(results) / seconds if seconds > 0 else float("inf")
    console.print(
        f"{len(results)} trials in {seconds:.2f} s ({rate:.0f} trials/s). "
        f"Wrote {out / 'verdicts.csv'} and {out / 'verdicts.json'}"
    )


@app.command(short_help="List the planners and whether each can run here.")
@json_option
def planners(as_json: bool) -> None:
    """List the planners, what each is for, and whether it can run on this machine."""
    from rich.table import Table

    from causalplan.planners.pipeline import DESCRIPTIONS, planner_availability

    availability = planner_availability()
    if as_json:
        _print_json(
            [
                {"name": name, "description": DESCRIPTIONS[name], "available": problem is None, "problem": problem}
                for name, problem in availability.items()
            ]
        )
        return
    table = Table("planner", "what it does", "available")
    for name, problem in availability.items():
        table.add_row(name, DESCRIPTIONS[name], "yes" if problem is None else f"no: {problem}")
    _console().print(table)


@app.command(short_help="Run the HTTP planning service (JSON API and participant pages).")
@click.option("--host", default="127.0.0.1", help="Address to listen on (0.0.0.0: every interface).")
@click.option("--port", type=click.IntRange(1, 65535), default=8000, help="Port to listen on.")
@click.option(
    "--workers",
    type=click.IntRange(1, 64),
    show_default=False,
    help="Planner worker processes (default: CAUSALPLAN_PLANNING_WORKERS, else 2).",
)
@click.option(
    "--database-url",
    show_default=False,
    help="SQLAlchemy URL, e.g. postgresql://user:password@host/db (default: CAUSALPLAN_DATABASE_URL, "
    "else a SQLite file in ~/.local/share/causalplan, created on first start).",
)
@click.option(
    "--access-log/--no-access-log",
    default=None,
    help="Log one line per request (default: CAUSALPLAN_ACCESS_LOG, else on). Errors are logged either way.",
)
def serve(host: str, port: int, workers: int | None, database_url: str | None, access_log: bool | None) -> None:
    """Run the HTTP planning service: JSON API under /v1, OpenAPI docs at /docs, /health.

    Other settings come from CAUSALPLAN_* environment variables (see causalplan/service/settings.py).
    The database is migrated to the newest schema on start. Stop with Ctrl-C.
    """
    from pydantic import ValidationError

    from causalplan.errors import CausalPlanError
    from causalplan.service.settings import Settings

    overrides: dict[str, object] = {}
    if workers is not None:
        overrides["planning_workers"] = workers
    if database_url is not None:
        overrides["database_url"] = database_url
    if access_log is not None:
        overrides["access_log"] = access_log
    try:
        settings = Settings(**overrides)  # type: ignore[arg-type]  # the rest from the environment
    except ValidationError as exc:
        problems = "; ".join(f"{'.'.join(map(str, e['loc'])) or 'settings'}: {e['msg']}" for e in exc.errors())
        _fail("invalid_settings", f"The service settings are invalid: {problems}.")
    from causalplan.service.main import check_startup
    from causalplan.service.main import serve as run_service

    try:
        database = check_startup(settings)
    except CausalPlanError as exc:
        _fail(exc.code, exc.message)
    _say(
        f"causalplan service on http://{host}:{port} (API docs: /docs), database {database}, "
        f"{settings.planning_workers} planner worker(s)",
        err=True,
    )
    run_service(settings, host, port)


def _print_simulation(report: SimulationReport) -> None:
    _say(f"Simulated {len(report.steps)} step(s) on the {report.object_name} (headless PyBullet):")
    for step in report.steps:
        reach = ""
        if step.reach is not None:
            verb = "reaches" if step.reach.reachable else "cannot reach"
            reach = " " + _dim(f"(arm {verb}: {step.reach.error_mm:.1f} mm)")
        if step.status.value == "passed":
            _say(f"  {step.number}. {step.text} {_mark(True, 'passed')}{reach}")
        elif step.status.value == "failed":
            failure = step.failure.value if step.failure else "failed"
            failed = click.style("FAILED", fg="red", bold=True)
            _say(f"  {step.number}. {step.text} {failed}[{failure}]: {step.message}{reach}")
        else:
            _say(f"  {step.number}. {step.text} {_dim('not run')}")
    drift = report.stability[0]
    _say(f"Holds still while it settles: {_mark(report.is_stable)} ({drift.detail}; tolerance {drift.tolerance:g} mm)")
    _say("True mechanism on the simulated assembly:")
    for requirement in report.requirements:
        _say(f"  {_mark(requirement.met)} {requirement.says}: {requirement.detail}")
    _say(f"Produces {report.goal}: {_mark(report.produces_goal)}")


@app.command(short_help="Check a plan in a headless physics simulation, and draw it.")
@click.argument("model", type=FILE)
@click.option("--mapping", "-m", type=FILE, help="A step-3 mapping: simulate on that object instead.")
@click.option(
    "--plan",
    "plan_file",
    type=FILE,
    help="The plan to run: the JSON of `causalplan plan --json`, or its 'plan' list. Without it, plan first.",
)
@click.option("--png", type=FILE, help="Write a picture of the final assembly (PNG).")
@click.option("--frames", type=FILE, help="Write a picture per step to this folder, and strip.png.")
@click.option("--gif", type=FILE, help="Write the steps as an animated GIF.")
@click.option("--arm", is_flag=True, help="Add a Panda arm and report whether it reaches each step's grasp poses.")
@json_option
@catalog_option
def simulate(
    model: Path,
    mapping: Path | None,
    plan_file: Path | None,
    png: Path | None,
    frames: Path | None,
    gif: Path | None,
    arm: bool,
    as_json: bool,
    catalog: tuple[Path, ...],
) -> None:
    """Run a plan in a headless physics simulation, check every step, and draw it.

    MODEL is the causal model file (YAML or JSON). Each step is checked (connectors fit, the
    path is clear, the joint is aligned, nothing falls), then the object's true mechanism is
    judged on the simulated assembly. Exit 0 when everything passes and the object produces
    its goal, 1 when not (or no plan is found), 2 for invalid input, 3 when the planner could
    not decide.
    """
    from causalplan.errors import CausalPlanError
    from causalplan.planners.pipeline import plan_task
    from causalplan.sim import RenderMode, read_plan_steps, simulate_plan
    from causalplan.sim.render import animation, strip

    objects = _catalog(catalog)
    task = _load_task(model, mapping, objects, as_json)
    target = task.obj
    render = RenderMode.FRAMES if frames or gif else RenderMode.FINAL if png else RenderMode.NONE
    try:
        if plan_file is not None:
            try:
                data = json.loads(plan_file.read_text(encoding="utf-8"))
            except OSError as exc:
                _fail("input_file_error", f"Cannot read the plan file {plan_file}: {exc.strerror}.")
            except (UnicodeDecodeError, json.JSONDecodeError) as exc:
                _fail("invalid_plan", f"{plan_file} is not JSON: {exc}.")
            steps = read_plan_steps(data, target)
        else:
            result = plan_task(task)
            if not result.has_plan:
                if as_json:
                    _print_json({"status": result.status.value, "message": result.message, "simulation": None})
                else:
                    _print_plan(result)
                _exit(EXIT_NO_PLAN if result.status.is_final() else EXIT_UNDECIDED)
            steps = read_plan_steps([step.as_dict() for step in result.steps], target)
        report = simulate_plan(target, steps, render=render, arm=arm)
    except CausalPlanError as exc:
        _fail(exc.code, exc.message)
    written: list[str] = []
    try:
        if png is not None and report.picture is not None:
            png.write_bytes(report.picture.png())
            written.append(str(png))
        if frames is not None:
            frames.mkdir(parents=True, exist_ok=True)
            for number, picture in enumerate(report.frames):
                (frames / f"step_{number:02d}.png").write_bytes(picture.png())
            (frames / "strip.png").write_bytes(strip(report.frames).png())
            written.append(str(frames))
        if gif is not None:
            gif.write_bytes(animation(report.frames))
            written.append(str(gif))
    except OSError as exc:
        _fail("output_not_writable", f"Cannot write {exc.filename}: {exc.strerror}.")
    if as_json:
        _print_json({**report.as_dict(), "files": written})
    else:
        _print_simulation(report)
        for path in written:
            _say(f"Wrote {path}")
    _exit(EXIT_OK if report.passed else EXIT_NO_PLAN)


@app.command(short_help="List the catalog's objects, or show one in detail.")
@click.argument("object_id", required=False, metavar="[OBJECT]")
@json_option
@catalog_option
def objects(object_id: str | None, as_json: bool, catalog: tuple[Path, ...]) -> None:
    """List the catalog's objects, or show one (OBJECT): parts, connectors, fits, true mechanism."""
    from dataclasses import asdict

    from rich.markup import escape
    from rich.table import Table

    from causalplan.errors import CausalPlanError

    known = _catalog(catalog)
    console = _console()
    if object_id is not None:
        try:
            obj = known.get(object_id)
        except CausalPlanError as exc:
            _fail(exc.code, exc.message)
        if as_json:
            _print_json(asdict(obj))
            return
        console.print(f"[bold]{escape(obj.name)}[/] ({obj.id}, {obj.category}, goal: {escape(obj.goal)})")
        console.print(escape(obj.description))
        parts = Table("part", "name", "connectors (kind, spec)", title="Parts", title_justify="left")
        for part in obj.parts:
            base = " (base)" if part.id == obj.base else ""
            parts.add_row(part.id + base, part.name, "; ".join(f"{c.id}: {c.kind}, {c.spec}" for c in part.connectors))
        console.print(parts)
        fits = Table("fit", "step", "p", "blocks", title="Fits", title_justify="left")
        for fit in obj.fits:
            fits.add_row(fit.id, obj.step_text(fit), f"{fit.probability:g}", ", ".join(".".join(b) for b in fit.blocks))
        console.print(fits)
        console.print("[bold]True mechanism:[/] " + escape(obj.mechanism_explanation))
        for requirement in obj.mechanism:
            console.print(f"  - {escape(requirement.says)} ({' or '.join(requirement.any_of)})")
        return
    if as_json:
        _print_json(
            [
                {
                    "id": obj.id,
                    "name": obj.name,
                    "category": obj.category,
                    "goal": obj.goal,
                    "parts": [{"id": part.id, "name": part.name} for part in obj.parts],
                }
                for obj in known.objects.values()
            ]
        )
        return
    table = Table("id", "name", "category", "goal", "parts")
    for obj in known.objects.values():
        table.add_row(obj.id, obj.name, obj.category, obj.goal, ", ".join(obj.part_ids))
    console.print(table)


def main() -> None:
    """Run the command line."""
    app(prog_name="causalplan")


if __name__ == "__main__":
    main()
