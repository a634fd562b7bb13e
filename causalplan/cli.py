"""The ``causalplan`` command line: check, plan, transfer, compile, graph, objects.

Each command imports what it needs when it runs, so ``causalplan --help`` and quick
commands start fast. Exit codes: 0 success, 1 no plan / no transfer, 2 invalid input,
3 the planner could not decide.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, NoReturn

import typer

if TYPE_CHECKING:
    from rich.console import Console

    from causalplan.causal.diagnostics import Report
    from causalplan.causal.model import CausalModel, Labelling
    from causalplan.objects.catalog import Catalog
    from causalplan.planners.result import PlanResult
    from causalplan.transfer.verdict import TransferVerdict

EXIT_OK, EXIT_NO_PLAN, EXIT_INVALID, EXIT_UNDECIDED = 0, 1, 2, 3

app = typer.Typer(
    name="causalplan",
    help=(
        "Teach a robot why an object works, then plan with that knowledge.\n\n"
        "A model file says which parts of an object carry which functions (step 1) and keyword rules "
        "such as 'provide electricity AND turn electricity into light CAUSES light' (step 2). "
        "A mapping file gives another object's parts the model's functions (step 3).\n\n"
        "Start with: causalplan plan examples/paper/desk_lamp.yaml"
    ),
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)

CatalogOption = Annotated[
    list[Path] | None,
    typer.Option(
        "--catalog",
        help="A folder of your own object files (YAML/JSON) to add to the built-in catalog. Repeatable.",
        show_default=False,
    ),
]
JsonOption = Annotated[bool, typer.Option("--json", help="Print machine-readable JSON instead of sentences.")]
PlannerOption = Annotated[
    str,
    typer.Option(
        "--planner",
        "-p",
        help="auto: Fast Downward, or the exact MDP when a fit may fail or FD fails. Also fd (LAMA, fast), "
        "fd-opt (shortest plan), mdp (most reliable plan), up:<engine>. `causalplan planners` lists them.",
    ),
]
TimeLimitOption = Annotated[
    float, typer.Option("--time-limit", min=0.1, max=3600, help="Seconds the planner may run before it is stopped.")
]


def _console(stderr: bool = False) -> Console:
    from rich.console import Console

    stream = sys.stderr if stderr else sys.stdout
    # Piped output gets a wide page, so tables are not cut to 80 columns in files and CI logs.
    width = None if stream.isatty() else 160
    return Console(stderr=stderr, highlight=False, soft_wrap=True, width=width)


def _fail(code: str, message: str) -> NoReturn:
    from rich.markup import escape

    _console(stderr=True).print(f"[bold red]error[/]\\[{code}]: {escape(message)}")
    raise typer.Exit(EXIT_INVALID)


def _catalog(folders: list[Path] | None) -> Catalog:
    from causalplan.errors import CausalPlanError
    from causalplan.objects.catalog import load_catalog

    try:
        return load_catalog(folders or ())
    except CausalPlanError as exc:
        _fail(exc.code, exc.message)


def _print_json(data: object) -> None:
    sys.stdout.write(json.dumps(data, indent=2, ensure_ascii=False) + "\n")


def _print_report(report: Report, console: Console) -> None:
    from rich.markup import escape

    for diagnostic in report.diagnostics:
        color = "red" if diagnostic.severity.value == "error" else "yellow"
        where = diagnostic.location.describe()
        console.print(
            f"[bold {color}]{diagnostic.severity.value}[/]\\[{diagnostic.code}]"
            f"{' ' + escape(where) if where else ''}: {escape(diagnostic.message)}"
        )
        if diagnostic.hint:
            console.print(f"  [dim]hint:[/] {escape(diagnostic.hint)}")


def _check_planner(planner: str) -> None:
    from causalplan.planners.pipeline import PLANNERS

    if planner not in PLANNERS:
        _fail("unknown_planner", f"Unknown planner '{planner}'; choose one of: {', '.join(PLANNERS)}.")


def _is_mapping_file(path: Path) -> bool:
    """Return whether a file looks like a step-3 mapping (no 'rules' field) rather than a model."""
    from causalplan.causal.documents import read_document

    data, _, problems = read_document(path)
    return not problems and isinstance(data, dict) and "rules" not in data


@app.command()
def check(
    model: Annotated[Path, typer.Argument(help="A model file (or a step-3 mapping file) in YAML or JSON.")],
    as_json: JsonOption = False,
    catalog: CatalogOption = None,
) -> None:
    """Validate a model (or mapping): errors with a code, where, and how to fix them.

    Exit 0 when valid (warnings allowed), 2 when invalid.
    """
    from causalplan.inputs import load_mapping, load_model

    objects = _catalog(catalog)
    kind = "mapping" if _is_mapping_file(model) else "model"
    report = load_mapping(model, objects).report if kind == "mapping" else load_model(model, objects).report
    if as_json:
        _print_json({"file": str(model), "kind": kind, **report.as_dict()})
    else:
        console = _console()
        _print_report(report, console)
        verdict = "[green]valid[/]" if report.is_valid else "[red]invalid[/]"
        counts = f"{len(report.errors)} error(s), {len(report.warnings)} warning(s)"
        from rich.markup import escape

        console.print(f"{escape(str(model))}: {kind} is {verdict} ({counts})")
    raise typer.Exit(EXIT_OK if report.is_valid else EXIT_INVALID)


def _stop_if_invalid(report: Report, path: Path, as_json: bool, advice: str = "") -> None:
    """Print the problems of an invalid input (as JSON or words) and exit with 2; return if it is valid."""
    if report.is_valid:
        return
    if as_json:
        _print_json({"status": "invalid", "file": str(path), **report.as_dict()})
    else:
        console = _console(stderr=True)
        _print_report(report, console)
        if advice:
            console.print(advice)
    raise typer.Exit(EXIT_INVALID)


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


def _write_pddl(folder: Path, domain: str, problem: str) -> None:
    try:
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "domain.pddl").write_text(domain, encoding="utf-8")
        (folder / "problem.pddl").write_text(problem, encoding="utf-8")
    except OSError as exc:
        _fail("output_not_writable", f"Cannot write the PDDL to {folder}: {exc.strerror}.")


def _print_plan(result: PlanResult, console: Console) -> None:
    from rich.markup import escape

    if not result.has_plan:
        console.print(f"[bold red]No plan[/] ({result.status.value}): {escape(result.message)}")
        return
    if not result.steps:
        console.print("The goal already holds: no step is needed.")
    for number, step in enumerate(result.steps, start=1):
        console.print(f"{number}. {escape(step.text)}")
    mark = "[green]yes[/]" if result.valid_under_true_mechanism else "[red]no[/]"
    console.print(
        f"[dim]{len(result.steps)} step(s) by {result.planner_used}, replayed: goal holds under the "
        f"model;[/] the real object works: {mark}"
    )
    if result.success_probability is not None and result.success_probability < 1.0:
        console.print(
            f"Success probability {result.success_probability:.4f} (some fits may fail); expected attempts "
            f"{result.expected_actions:.2f}."
        )
    if result.validated_by_up is not None:
        console.print(
            f"unified-planning's validator: {'[green]valid[/]' if result.validated_by_up else '[red]INVALID[/]'}"
        )
    if result.fallback_reason:
        console.print(f"[dim]Used {result.planner_used} because {escape(result.fallback_reason)}.[/]")
    if result.message:
        console.print(f"[yellow]{escape(result.message)}[/]")


@app.command()
def plan(
    model: Annotated[Path, typer.Argument(help="The causal model file (YAML or JSON).")],
    mapping: Annotated[
        Path | None,
        typer.Option(
            "--mapping",
            "-m",
            help="A step-3 mapping: plan for that object instead, with its parts carrying the model's functions.",
        ),
    ] = None,
    planner: PlannerOption = "auto",
    time_limit: TimeLimitOption = 30.0,
    pddl_out: Annotated[
        Path | None, typer.Option("--pddl-out", help="Also write domain.pddl and problem.pddl to this folder.")
    ] = None,
    up_validate: Annotated[
        bool, typer.Option("--up-validate", help="Also check the plan with unified-planning's plan validator.")
    ] = False,
    as_json: JsonOption = False,
    catalog: CatalogOption = None,
) -> None:
    """Plan how to assemble the object so the model's goal holds, and print the steps.

    Every plan is replayed on the object before it is shown: against the model, and against
    the object's true mechanism. Exit 0 with a plan, 1 without one, 2 for invalid input.
    """
    from causalplan.errors import CausalPlanError
    from causalplan.pddl.task import build_task
    from causalplan.planners.pipeline import plan_task

    _check_planner(planner)
    objects = _catalog(catalog)
    causal_model = _load_valid_model(model, objects, as_json)
    labelling = _load_valid_mapping(mapping, objects, as_json) if mapping else None
    target = objects.get((labelling or causal_model.labelling).object_id)
    try:
        result = plan_task(
            build_task(causal_model, target, labelling),
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
        _print_plan(result, _console())
    raise typer.Exit(EXIT_OK if result.has_plan else EXIT_NO_PLAN)


def _print_verdict(verdict: TransferVerdict, console: Console) -> None:
    from rich.markup import escape

    colors = {"transfers": "green", "fails": "red", "invalid": "red", "undecided": "yellow"}
    kind = f" ({verdict.generalization}-generalization)" if verdict.generalization in ("near", "far") else ""
    console.print(
        f"[bold {colors[verdict.verdict.value]}]{verdict.verdict.value}[/]: "
        f"{verdict.training_object} → {verdict.test_object}{kind}, decided by {verdict.decided_by}"
    )
    for reason in verdict.reasons:
        color = "red" if reason.severity.value == "error" else "yellow"
        console.print(f"  [{color}]{reason.severity.value}[/]\\[{reason.code}]: {escape(reason.message)}")
    if verdict.plan is not None and verdict.plan.has_plan:
        console.print("Plan:")
        for number, step in enumerate(verdict.plan.steps, start=1):
            console.print(f"  {number}. {escape(step.text)}")


@app.command()
def transfer(
    model: Annotated[Path, typer.Argument(help="The causal model of the training object (steps 1-2).")],
    mapping: Annotated[Path, typer.Argument(help="The step-3 mapping of a new object's parts to functions.")],
    planner: PlannerOption = "auto",
    time_limit: TimeLimitOption = 30.0,
    as_json: JsonOption = False,
    catalog: CatalogOption = None,
) -> None:
    """Test whether a model transfers to a new object (step 3), and say why or why not.

    Exit 0 when it transfers, 1 when it fails, 2 when the model or mapping is invalid,
    3 when the planner could not decide (e.g. it timed out).
    """
    from causalplan.errors import CausalPlanError
    from causalplan.inputs import load_mapping, load_model
    from causalplan.transfer.verdict import evaluate_transfer, invalid_verdict

    _check_planner(planner)
    objects = _catalog(catalog)
    loaded_model, loaded_mapping = load_model(model, objects), load_mapping(mapping, objects)
    if loaded_model.is_valid and loaded_mapping.is_valid:
        assert loaded_model.model is not None and loaded_mapping.mapping is not None
        try:
            verdict = evaluate_transfer(loaded_model.model, loaded_mapping.mapping, objects, planner, time_limit)
        except CausalPlanError as exc:
            _fail(exc.code, exc.message)
    else:
        verdict = invalid_verdict(
            loaded_model.report,
            loaded_mapping.report,
            loaded_model.model.object_id if loaded_model.model else None,
            loaded_mapping.mapping.object_id if loaded_mapping.mapping else None,
        )
    if as_json:
        _print_json(verdict.as_dict())
    else:
        _print_verdict(verdict, _console())
    raise typer.Exit(verdict.verdict.exit_code)


@app.command(name="compile")
def compile_command(
    model: Annotated[Path, typer.Argument(help="The causal model file (YAML or JSON).")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Folder to write domain.pddl and problem.pddl to.")],
    mapping: Annotated[
        Path | None, typer.Option("--mapping", "-m", help="Compile for a step-3 mapping's object.")
    ] = None,
    catalog: CatalogOption = None,
) -> None:
    """Compile a model to a PDDL 2.2 domain and problem with derived predicates, without planning."""
    from causalplan.pddl.task import build_task
    from causalplan.pddl.writer import compile_task

    objects = _catalog(catalog)
    causal_model = _load_valid_model(model, objects, False)
    labelling = _load_valid_mapping(mapping, objects, False) if mapping else None
    target = objects.get((labelling or causal_model.labelling).object_id)
    compiled = compile_task(build_task(causal_model, target, labelling))
    _write_pddl(out, compiled.domain, compiled.problem)
    _console().print(f"Wrote {out / 'domain.pddl'} and {out / 'problem.pddl'}")


@app.command()
def graph(
    model: Annotated[Path, typer.Argument(help="The causal model file (YAML or JSON).")],
    out: Annotated[
        Path | None,
        typer.Option(
            "--out",
            "-o",
            help="Write a picture (.png, .svg, .pdf) or Graphviz text (.dot); without it, DOT goes to the screen.",
        ),
    ] = None,
    as_json: JsonOption = False,
    catalog: CatalogOption = None,
) -> None:
    """Draw the model's causal graph, left to right from the parts' functions to the goal.

    Invalid models are drawn too (causes nothing produces are red), to help see what is wrong.
    """
    from causalplan.causal.render import PICTURE_SUFFIXES, draw, to_dot, to_json
    from causalplan.inputs import load_model

    loaded = load_model(model, _catalog(catalog))
    if loaded.model is None:
        _print_report(loaded.report, _console(stderr=True))
        raise typer.Exit(EXIT_INVALID)
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
        _console(stderr=True).print(f"Wrote {out}")
    raise typer.Exit(EXIT_OK if loaded.report.is_valid else EXIT_INVALID)


def _int_list(text: str, what: str) -> list[int]:
    try:
        return [int(item) for item in text.split(",") if item.strip()]
    except ValueError:
        _fail("invalid_option", f"{what} must be whole numbers separated by commas, e.g. 10,40,80; got '{text}'.")


@app.command()
def compare(
    tasks: Annotated[
        list[Path] | None,
        typer.Argument(
            help="Model files, or task files (YAML with model:, mapping:, catalog:). Default: the paper's examples "
            "(found under the current folder's examples/).",
            show_default=False,
        ),
    ] = None,
    planners_option: Annotated[
        str, typer.Option("--planners", help="Comma-separated planners (see `causalplan planners`).")
    ] = "fd,fd-opt,mdp,up:fast-downward",
    synthetic: Annotated[
        str | None, typer.Option("--synthetic", help="Also synthetic objects of these sizes, e.g. 10,40,80.")
    ] = None,
    timeout: Annotated[float, typer.Option("--timeout", min=0.5, max=3600, help="Seconds per run.")] = 60.0,
    memory: Annotated[int, typer.Option("--memory", min=256, help="Memory limit per run, in MB.")] = 4096,
    repeat: Annotated[int, typer.Option("--repeat", min=1, max=50, help="Runs per pair; medians are reported.")] = 1,
    out: Annotated[Path, typer.Option("--out", help="Folder for compare.csv, compare.json and compare.png.")] = Path(
        "out/compare"
    ),
    catalog: CatalogOption = None,
) -> None:
    """Run several planners on several tasks, one process per run, and compare them.

    Prints a table (status, plan length, time, success probability, valid), and writes CSV,
    JSON and a plot of time against the number of parts. A planner that fails is a row.
    """
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
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
            selected = [comparison_tasks.from_argument(path, list(catalog or [])) for path in tasks]
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
    with Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=_console(stderr=True),
        transient=True,
    ) as progress:
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


@app.command()
def batch(
    trials_file: Annotated[
        Path,
        typer.Argument(help='Trials: JSON Lines, one {"id", "model", "mapping"} per line (or a JSON/YAML list).'),
    ],
    planner: PlannerOption = "auto",
    time_limit: TimeLimitOption = 30.0,
    simulate: Annotated[
        bool, typer.Option("--simulate/--no-simulate", help="Check plans in the physics simulator (as transfer does).")
    ] = True,
    out: Annotated[Path, typer.Option("--out", help="Folder for verdicts.csv and verdicts.json.")] = Path("out/batch"),
    catalog: CatalogOption = None,
) -> None:
    """Judge many transfer trials (e.g. a study's participants) and write their verdicts and reasons.

    What can be decided without the planner is (invalid input, a function no part carries);
    equal planning problems are solved once. The verdicts are those `causalplan transfer`
    gives one trial at a time.
    """
    import csv
    import time

    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
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
    with Progress(
        TextColumn("judging trials"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=_console(stderr=True),
        transient=True,
    ) as progress:
        bar = progress.add_task("trials", total=len(trials))
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


@app.command()
def planners(as_json: JsonOption = False) -> None:
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


@app.command()
def serve(
    host: Annotated[str, typer.Option("--host", help="Address to listen on (0.0.0.0: every interface).")] = "127.0.0.1",
    port: Annotated[int, typer.Option("--port", min=1, max=65535, help="Port to listen on.")] = 8000,
    workers: Annotated[
        int | None,
        typer.Option(
            "--workers",
            min=1,
            max=64,
            help="Planner worker processes (default: CAUSALPLAN_PLANNING_WORKERS, else 2).",
            show_default=False,
        ),
    ] = None,
    database_url: Annotated[
        str | None,
        typer.Option(
            "--database-url",
            help="SQLAlchemy URL, e.g. postgresql://user:password@host/db (default: CAUSALPLAN_DATABASE_URL, "
            "else a SQLite file in ~/.local/share/causalplan, created on first start).",
            show_default=False,
        ),
    ] = None,
) -> None:
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
    _console(stderr=True).print(
        f"causalplan service on http://{host}:{port} (API docs: /docs), database {database}, "
        f"{settings.planning_workers} planner worker(s)"
    )
    run_service(settings, host, port)


if TYPE_CHECKING:
    from causalplan.sim import SimulationReport


def _print_simulation(report: SimulationReport, console: Console) -> None:
    from rich.markup import escape

    console.print(f"Simulated {len(report.steps)} step(s) on the {escape(report.object_name)} (headless PyBullet):")
    for step in report.steps:
        reach = ""
        if step.reach is not None:
            verb = "reaches" if step.reach.reachable else "cannot reach"
            reach = f" [dim](arm {verb}: {step.reach.error_mm:.1f} mm)[/]"
        if step.status.value == "passed":
            console.print(f"  {step.number}. {escape(step.text)} [green]passed[/]{reach}")
        elif step.status.value == "failed":
            failure = step.failure.value if step.failure else "failed"
            console.print(
                f"  {step.number}. {escape(step.text)} [bold red]FAILED[/]\\[{failure}]: {escape(step.message)}{reach}"
            )
        else:
            console.print(f"  {step.number}. {escape(step.text)} [dim]not run[/]")
    drift = report.stability[0]
    still = "[green]yes[/]" if report.is_stable else "[red]no[/]"
    console.print(f"Holds still while it settles: {still} ({escape(drift.detail)}; tolerance {drift.tolerance:g} mm)")
    console.print("True mechanism on the simulated assembly:")
    for requirement in report.requirements:
        mark = "[green]yes[/]" if requirement.met else "[red]no[/]"
        console.print(f"  {mark} {escape(requirement.says)}: {escape(requirement.detail)}")
    produces = "[green]yes[/]" if report.produces_goal else "[red]no[/]"
    console.print(f"Produces {escape(report.goal)}: {produces}")


@app.command()
def simulate(
    model: Annotated[Path, typer.Argument(help="The causal model file (YAML or JSON).")],
    mapping: Annotated[
        Path | None,
        typer.Option("--mapping", "-m", help="A step-3 mapping: simulate on that object instead."),
    ] = None,
    plan_file: Annotated[
        Path | None,
        typer.Option(
            "--plan",
            help="The plan to run: the JSON of `causalplan plan --json`, or its 'plan' list. Without it, plan first.",
        ),
    ] = None,
    png: Annotated[Path | None, typer.Option("--png", help="Write a picture of the final assembly (PNG).")] = None,
    frames: Annotated[
        Path | None, typer.Option("--frames", help="Write a picture per step to this folder, and strip.png.")
    ] = None,
    gif: Annotated[Path | None, typer.Option("--gif", help="Write the steps as an animated GIF.")] = None,
    arm: Annotated[
        bool, typer.Option("--arm", help="Add a Panda arm and report whether it reaches each step's grasp poses.")
    ] = False,
    as_json: JsonOption = False,
    catalog: CatalogOption = None,
) -> None:
    """Run a plan in a headless physics simulation, check every step, and draw it.

    Each step is checked (connectors fit, the path is clear, the joint is aligned, nothing
    falls), then the object's true mechanism is judged on the simulated assembly. Exit 0 when
    everything passes and the object produces its goal, 1 when not (or no plan is found),
    2 for invalid input, 3 when the planner could not decide.
    """
    from causalplan.errors import CausalPlanError
    from causalplan.pddl.task import build_task
    from causalplan.planners.pipeline import plan_task
    from causalplan.sim import RenderMode, read_plan_steps, simulate_plan
    from causalplan.sim.render import animation, strip

    objects = _catalog(catalog)
    causal_model = _load_valid_model(model, objects, as_json)
    labelling = _load_valid_mapping(mapping, objects, as_json) if mapping else None
    target = objects.get((labelling or causal_model.labelling).object_id)
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
            result = plan_task(build_task(causal_model, target, labelling))
            if not result.has_plan:
                if as_json:
                    _print_json({"status": result.status.value, "message": result.message, "simulation": None})
                else:
                    _print_plan(result, _console())
                raise typer.Exit(EXIT_NO_PLAN if result.status.is_final() else EXIT_UNDECIDED)
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
        console = _console()
        _print_simulation(report, console)
        for path in written:
            console.print(f"Wrote {path}")
    raise typer.Exit(EXIT_OK if report.passed else EXIT_NO_PLAN)


@app.command()
def objects(
    object_id: Annotated[str | None, typer.Argument(help="Show one object in detail.")] = None,
    as_json: JsonOption = False,
    catalog: CatalogOption = None,
) -> None:
    """List the catalog's objects, or show one: parts, connectors, fits, true mechanism."""
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
    app()


if __name__ == "__main__":
    main()
