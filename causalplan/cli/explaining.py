"""The ``explain`` command (why this step, why not …?) and what ``transfer --repair`` prints."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from causalplan.cli.common import (
    EXIT_OK,
    FILE,
    catalog_from,
    catalog_option,
    check_planner,
    dim,
    exit_on_error,
    exit_with,
    json_option,
    load_task,
    print_json,
    say,
    status_exit_code,
    time_limit_option,
    val_option,
)

if TYPE_CHECKING:
    from causalplan.explain.explanation import Explanation
    from causalplan.explain.repair import RepairSearch

QUESTIONS = (
    "attach PART | leave out PART | leave out step N | PART before PART | use FIT; "
    "PART is a part's id or name (light_bulb, 'light bulb'), FIT a fit's id"
)


def _print_explanation(explanation: Explanation) -> None:
    for number, step in enumerate(explanation.plan.steps, start=1):
        say(f"{number}. {step.text}")
    checked = ", ".join(f"{name} {verdict}" for name, verdict in explanation.plan.validated_by.items())
    say(dim(f"{len(explanation.plan.steps)} step(s) by {explanation.plan.planner_used}; checked by {checked}."))
    for why in explanation.steps:
        say(f"{click.style(f'Why step {why.number}?', bold=True)} {why.message}")
    contrast = explanation.contrast
    if contrast is None:
        return
    say(f"{click.style(contrast.text, bold=True)} [{contrast.code}] {contrast.message}")
    alternative = contrast.alternative
    if alternative.has_plan and alternative is not explanation.plan:
        checked = ", ".join(f"{name} {verdict}" for name, verdict in alternative.validated_by.items())
        say(dim(f"The alternative ({len(alternative.steps)} step(s), checked by {checked}):"))
        for number, step in enumerate(alternative.steps, start=1):
            say(f"  {number}. {step.text}")


@click.command(short_help="Explain a plan: why this step, why not another.")
@click.argument("model", type=FILE)
@click.option("--mapping", "-m", type=FILE, help="A step-3 mapping: explain the plan for that object.")
@click.option("--why", "why", metavar="STEP", help="A step number, the part a step attaches, or 'all' (the default).")
@click.option("--why-not", "why_not", metavar="QUESTION", help=f"A contrastive question: {QUESTIONS}.")
@click.option(
    "--planner",
    "-p",
    default="fd",
    help="The planner of the plan explained (`causalplan planners`); alternatives are shortest plans (fd-opt).",
)
@time_limit_option
@val_option
@click.option("--simulate", is_flag=True, help="When an order cannot be done, also try it in the simulator.")
@json_option
@catalog_option
def explain(
    model: Path,
    mapping: Path | None,
    why: str | None,
    why_not: str | None,
    planner: str,
    time_limit: float,
    val: bool,
    simulate: bool,
    as_json: bool,
    catalog: tuple[Path, ...],
) -> None:
    """Plan MODEL and explain the plan in the model's own words.

    --why STEP: the causal chain a step serves (which part it attaches, which function that
    part carries, which rule it enables, up to the goal). --why-not QUESTION: plan again with
    the question's constraint and compare the two plans, naming the rule or function that
    decides it; the alternative plan is replayed and checked by VAL like any plan.
    Exit 0 answered, 1 no plan to explain, 2 invalid input or question (its code, e.g.
    unknown_part, invalid_question), 3 when the planner could not decide (it timed out).

    \b
        causalplan explain examples/paper/failed_desk_lamp.yaml --why-not "shade before light_bulb"
        causalplan explain examples/paper/failed_desk_lamp.yaml --why-not "leave out shade"
    """
    from causalplan.explain.contrast import PlanUnavailableError
    from causalplan.explain.explanation import explain_plan

    check_planner(planner)
    objects = catalog_from(catalog)
    task = load_task(model, mapping, objects, as_json)
    with exit_on_error():
        try:
            explanation = explain_plan(task, why, why_not, planner, time_limit, val, simulate)
        except PlanUnavailableError as exc:
            if as_json:
                print_json({"status": "no_plan", "code": exc.code, "message": exc.message})
            else:
                say(f"{click.style('No plan to explain', fg='red', bold=True)}: {exc.message}")
            exit_with(status_exit_code(str(exc.details.get("status", "unsolvable"))))
    if as_json:
        print_json(explanation.as_dict())
    else:
        _print_explanation(explanation)
    exit_with(EXIT_OK)


def print_repairs(search: RepairSearch) -> None:
    """Print the repairs of a failed transfer, smallest first, saying how many of them are shown."""
    shown, found = search.shown(), len(search.repairs)
    sizes = ", ".join(
        f"{count} with {size} edit{'s' if size > 1 else ''}" for size, count in search.by_size().items() if count
    )
    checked = f"{search.checked} edit set(s) checked by a full verdict"
    if not found:
        say(f"Repairs: none found with up to {search.max_edits} edit(s); {checked}.")
        return
    listed = f"{len(shown)} of {found} shown, smallest first" if len(shown) < found else "all shown"
    say(f"Repairs: {found} found ({sizes}), {listed}; {checked}.")
    for repair in shown:
        say(f"  [{len(repair.edits)}] {repair.describe()}")
