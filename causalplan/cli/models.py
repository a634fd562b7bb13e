"""Commands on one model or mapping file: check, compile, graph; and the catalog: objects."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING

import click

from causalplan.cli.common import (
    EXIT_INVALID,
    EXIT_OK,
    FILE,
    catalog_from,
    catalog_option,
    exit_on_error,
    exit_with,
    fail,
    json_option,
    load_task,
    looks_like_a_mapping,
    make_console,
    mark,
    print_json,
    print_report,
    say,
    stop_if_invalid,
    write_pddl,
    writing,
)

if TYPE_CHECKING:
    from causalplan.objects.model import AssemblyObject


@click.command(short_help="Validate a model (or, with --kind mapping, a mapping): what is wrong, where, how to fix it.")
@click.argument("file", metavar="FILE", type=FILE)
@click.option(
    "--kind",
    type=click.Choice(["model", "mapping"]),
    default="model",
    help="What FILE is: a model (steps 1-2: object, functions, rules) or a step-3 mapping (object, functions). "
    "The option decides, never the file's contents.",
)
@json_option
@catalog_option
def check(file: Path, kind: str, as_json: bool, catalog: tuple[Path, ...]) -> None:
    """Validate a model, or a step-3 mapping: errors with a code, where, and how to fix them.

    FILE is read as a model (YAML or JSON), unless --kind mapping says it is a step-3
    mapping; what the file holds never changes how it is read, so a model whose 'rules' are
    misspelled or missing is an invalid model, as `plan` says too. Exit 0 when valid
    (warnings allowed), 2 when invalid.

    \b
        causalplan check examples/paper/desk_lamp.yaml
        causalplan check --kind mapping examples/paper/flashlight_mapping.yaml
    """
    from causalplan.inputs import load_mapping, load_model

    objects = catalog_from(catalog)
    report = load_mapping(file, objects).report if kind == "mapping" else load_model(file, objects).report
    if as_json:
        print_json({"file": str(file), "kind": kind, **report.as_dict()})
    else:
        print_report(report)
        verdict = mark(report.is_valid, "valid", "invalid")
        say(f"{file}: {kind} is {verdict} ({len(report.errors)} error(s), {len(report.warnings)} warning(s))")
        if kind == "model" and not report.is_valid and looks_like_a_mapping(file):
            say(f"If {file} is a step-3 mapping, check it as one: causalplan check --kind mapping {file}")
    exit_with(EXIT_OK if report.is_valid else EXIT_INVALID)


@click.command(name="compile", short_help="Write the model as PDDL (domain and problem), without planning.")
@click.argument("model", type=FILE)
@click.option("--out", "-o", type=FILE, required=True, help="Folder to write domain.pddl and problem.pddl to.")
@click.option("--mapping", "-m", type=FILE, help="Compile for a step-3 mapping's object.")
@catalog_option
def compile_command(model: Path, out: Path, mapping: Path | None, catalog: tuple[Path, ...]) -> None:
    """Compile a model to a PDDL 2.2 domain and problem with derived predicates, without planning.

    MODEL is the causal model file (YAML or JSON). Exit 0 when written, 2 for invalid input
    (the model's or mapping's problems are printed, as `check` prints them).
    """
    from causalplan.pddl.writer import compile_task

    objects = catalog_from(catalog)
    compiled = compile_task(load_task(model, mapping, objects, False))
    write_pddl(out, compiled.domain, compiled.problem)
    say(f"Wrote {out / 'domain.pddl'} and {out / 'problem.pddl'}")


@click.command(short_help="Draw the model's causal graph (PNG, SVG, PDF or DOT).")
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

    MODEL is the causal model file (YAML or JSON). An invalid model is not drawn: its
    problems are printed (as `check` prints them), nothing is written, and the exit code is 2.
    Exit 0 when drawn.
    """
    from causalplan.causal.render import PICTURE_SUFFIXES, draw, to_dot, to_json
    from causalplan.inputs import load_model

    if out is not None and out.suffix.lower() not in (*PICTURE_SUFFIXES, ".dot"):
        fail("unknown_format", f"Cannot tell the format of {out}: use .png, .svg, .pdf or .dot.")
    loaded = load_model(model, catalog_from(catalog))
    stop_if_invalid(loaded.report, model, as_json, f"{model}: the model is invalid, so nothing was drawn.")
    assert loaded.model is not None
    if as_json:
        print_json(to_json(loaded.model))
    elif out is None:
        sys.stdout.write(to_dot(loaded.model))
    elif out.suffix.lower() == ".dot":
        with writing(out):
            out.write_text(to_dot(loaded.model), encoding="utf-8")
    else:
        with writing(out):
            draw(loaded.model, out)
    if out is not None:
        say(f"Wrote {out}", err=True)
    exit_with(EXIT_OK)


def _write_reference_model(obj: AssemblyObject, out: Path | None, as_json: bool) -> None:
    """Print the object's reference model, or write it and its mapping to ``out``."""
    import yaml

    from causalplan.objects.reference import reference_mapping, reference_model

    model, mapping = reference_model(obj), reference_mapping(obj)
    if out is None:
        if as_json:
            print_json({"model": model, "mapping": mapping})
        else:
            sys.stdout.write(f"# The reference model of the {obj.name}: its true mechanism as a causal model.\n")
            sys.stdout.write(yaml.safe_dump(model, sort_keys=False, allow_unicode=True, width=100))
        return
    files = {out / f"{obj.id}.yaml": model, out / f"{obj.id}_mapping.yaml": mapping}
    with writing(out):
        out.mkdir(parents=True, exist_ok=True)
        for path, document in files.items():
            path.write_text(yaml.safe_dump(document, sort_keys=False, allow_unicode=True, width=100), encoding="utf-8")
    if as_json:
        print_json({"model": str(out / f"{obj.id}.yaml"), "mapping": str(out / f"{obj.id}_mapping.yaml")})
    else:
        say(f"Wrote {', '.join(str(path) for path in files)}")


@click.command(short_help="List the catalog's objects, or show one in detail.")
@click.argument("object_id", required=False, metavar="[OBJECT]")
@click.option(
    "--reference-model",
    is_flag=True,
    help="Give OBJECT's true mechanism as a causal model (the expert's gold standard) and its step-3 mapping.",
)
@click.option(
    "--out", "-o", type=FILE, help="With --reference-model: the folder to write OBJECT.yaml and OBJECT_mapping.yaml to."
)
@json_option
@catalog_option
def objects(
    object_id: str | None, reference_model: bool, out: Path | None, as_json: bool, catalog: tuple[Path, ...]
) -> None:
    """List the catalog's objects, or show one (OBJECT): parts, connectors, fits, true mechanism.

    With --reference-model, print OBJECT's reference model (or write it with its mapping to
    --out), ready for `check`, `plan`, `transfer` and `simulate`:

    \b
        causalplan objects headlamp --reference-model --out out/reference
        causalplan simulate out/reference/headlamp.yaml --robot
    """
    from dataclasses import asdict

    from rich.markup import escape
    from rich.table import Table

    if (reference_model or out is not None) and object_id is None:
        fail(
            "missing_object",
            "--reference-model and --out need an OBJECT: e.g. `causalplan objects candle --reference-model`.",
        )
    if out is not None and not reference_model:
        fail("missing_option", "--out goes with --reference-model: add it, or leave --out out.")
    known = catalog_from(catalog)
    console = make_console()
    if object_id is not None:
        with exit_on_error():
            obj = known.get(object_id)
        if reference_model:
            _write_reference_model(obj, out, as_json)
            return
        if as_json:
            print_json(asdict(obj))
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
            function = f"; function: {escape(requirement.function)}" if requirement.function else ""
            after = f"; after {', '.join(requirement.after)}" if requirement.after else ""
            console.print(f"  - {escape(requirement.says)} ({' or '.join(requirement.any_of)}{function}{after})")
        if obj.faults:
            title = f"Faults ({obj.fault_priors} priors)"
            faults = Table("part", "p", "fault", "visible on inspection", title=title, title_justify="left")
            for fault in obj.faults:
                visible = "yes" if fault.visible else "no"
                faults.add_row(fault.part, f"{fault.probability:g}", escape(fault.looks), visible)
            console.print(faults)
        else:
            console.print("No faults listed: `causalplan troubleshoot` cannot use this object.")
        return
    if as_json:
        print_json(
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
