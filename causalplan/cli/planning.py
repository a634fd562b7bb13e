"""Commands that plan: plan, transfer, and planners (what can run here)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from causalplan.cli.common import (
    FILE,
    catalog_from,
    catalog_option,
    check_planner,
    exit_on_error,
    exit_with,
    json_option,
    load_task,
    make_console,
    planner_option,
    print_json,
    print_plan,
    print_report,
    say,
    status_exit_code,
    time_limit_option,
    val_option,
    write_pddl,
)

if TYPE_CHECKING:
    from causalplan.causal.diagnostics import Report
    from causalplan.transfer.verdict import TransferVerdict


@click.command(short_help="Plan the assembly that makes the model's goal hold.")
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
@val_option
@click.option(
    "--catalog-overlay",
    type=FILE,
    help="Fit probabilities to use instead of the catalog's (the --out file of `causalplan estimate-fits`).",
)
@click.option(
    "--objective",
    type=click.Choice(["probability", "attempts"]),
    default="probability",
    help="What the MDP planners optimise: the highest success probability, or the fewest expected "
    "attempts that reach --required-success.",
)
@click.option(
    "--required-success",
    type=click.FloatRange(0.0, 1.0, min_open=True),
    help="The success probability the 'attempts' objective must reach.",
)
@json_option
@catalog_option
def plan(
    model: Path,
    mapping: Path | None,
    planner: str,
    time_limit: float,
    pddl_out: Path | None,
    up_validate: bool,
    val: bool,
    catalog_overlay: Path | None,
    objective: str,
    required_success: float | None,
    as_json: bool,
    catalog: tuple[Path, ...],
) -> None:
    """Plan how to assemble the object so the model's goal holds, and print the steps.

    MODEL is the causal model file (YAML or JSON). Every plan is replayed on the object before
    it is shown: against the model, and against the object's true mechanism; VAL checks it on
    the PDDL as written (--no-val skips that). Exit 0 with a plan, 1 when there is none (the
    planner proved it), 2 for invalid input or a plan VAL rejects, 3 when the planner could not
    decide (it timed out or failed).

    Example: causalplan plan examples/paper/desk_lamp.yaml --pddl-out out/desk_lamp
    """
    from causalplan.planners.pipeline import plan_task

    check_planner(planner)
    objects = catalog_from(catalog)
    if catalog_overlay is not None:
        from causalplan.objects.overlay import apply_overlay

        with exit_on_error():
            objects = apply_overlay(objects, catalog_overlay)
    task = load_task(model, mapping, objects, as_json)
    with exit_on_error():
        result = plan_task(
            task,
            planner,
            time_limit,
            include_pddl=pddl_out is not None,
            validate_up=up_validate,
            val=val,
            objective=objective,
            required_success=required_success,
        )
    if pddl_out is not None and result.pddl is not None:
        write_pddl(pddl_out, result.pddl["domain"], result.pddl["problem"])
    if as_json:
        data = result.as_dict()
        data.pop("pddl", None)
        print_json(data)
    else:
        print_plan(result)
    exit_with(status_exit_code(result.status))


def _print_verdict(verdict: TransferVerdict) -> None:
    colors = {"transfers": "green", "fails": "red", "invalid": "red", "undecided": "yellow"}
    kind = f" ({verdict.generalization}-generalization)" if verdict.generalization in ("near", "far") else ""
    value = click.style(verdict.verdict.value, fg=colors[verdict.verdict.value], bold=True)
    say(f"{value}: {verdict.training_object} → {verdict.test_object}{kind}, decided by {verdict.decided_by}")
    for reason in verdict.reasons:
        severity = click.style(reason.severity.value, fg="red" if reason.severity.value == "error" else "yellow")
        say(f"  {severity}[{reason.code}]: {reason.message}")
    if verdict.plan is not None and verdict.plan.has_plan:
        say("Plan:")
        for number, step in enumerate(verdict.plan.steps, start=1):
            say(f"  {number}. {step.text}")


def _print_invalid_inputs(*inputs: tuple[Path, Report, str]) -> None:
    """Say which input is invalid and print its problems as `check` does (codes, where, "did you mean")."""
    invalid = [(path, report, kind) for path, report, kind in inputs if not report.is_valid]
    which = " and the ".join(kind for _, _, kind in invalid)
    verb = "are" if len(invalid) > 1 else "is"
    say(f"{click.style('invalid', fg='red', bold=True)}: the {which} {verb} invalid, so nothing was planned.")
    for path, report, kind in invalid:
        print_report(report)
        option = " --kind mapping" if kind == "mapping" else ""
        say(
            f"{path}: {kind} is invalid ({len(report.errors)} error(s), {len(report.warnings)} warning(s)); "
            f"`causalplan check{option} {path}` checks it again after fixing it."
        )


@click.command(short_help="Test whether a model transfers to a new object (step 3).")
@click.argument("model", type=FILE)
@click.argument("mapping", type=FILE)
@planner_option
@time_limit_option
@val_option
@click.option(
    "--robot",
    is_flag=True,
    help="Also have the Franka Panda carry out the plan: a transfer it cannot carry out fails with "
    "robot_cannot_execute (its step and code, e.g. unreachable, no_collision_free_path).",
)
@click.option(
    "--repair",
    is_flag=True,
    help="When it fails: the smallest sets of edits (on the mapping or the model) that make it transfer, "
    "each re-checked by a full verdict (for researchers: participants in the test phase never see them).",
)
@json_option
@catalog_option
def transfer(
    model: Path,
    mapping: Path,
    planner: str,
    time_limit: float,
    val: bool,
    robot: bool,
    repair: bool,
    as_json: bool,
    catalog: tuple[Path, ...],
) -> None:
    """Test whether a model transfers to a new object (step 3), and say why or why not.

    MODEL is the causal model of the training object (steps 1-2); MAPPING maps a new object's
    parts to the model's functions (step 3). Exit 0 when it transfers, 1 when it fails, 2 when
    the model or mapping is invalid or VAL rejects the plan, 3 when the planner could not
    decide (e.g. it timed out). With --robot the robot has the last word: a plan it cannot
    carry out fails with robot_cannot_execute (the step, and unreachable, collision, ...):

    \b
        causalplan transfer examples/robot/walled_plate.yaml examples/robot/long_bench_mapping.yaml \\
            --robot --catalog examples/robot/catalog
    """
    from causalplan.inputs import load_mapping, load_model
    from causalplan.transfer.verdict import transfer_verdict

    check_planner(planner)
    objects = catalog_from(catalog)
    loaded_model, loaded_mapping = load_model(model, objects), load_mapping(mapping, objects)
    with exit_on_error():
        verdict = transfer_verdict(loaded_model, loaded_mapping, objects, planner, time_limit, val=val)
        if robot:
            from causalplan.transfer.robot_verdict import robot_judged

            verdict = robot_judged(verdict, objects)
        repairs = None
        if repair and verdict.verdict.value == "fails":
            from causalplan.explain.repair import search_repairs

            assert loaded_model.model is not None and loaded_mapping.mapping is not None
            repairs = search_repairs(
                loaded_model.model,
                loaded_mapping.mapping,
                objects,
                verdict,
                planner=planner,
                time_limit=time_limit,
                val=val,
            )
    if as_json:
        print_json({**verdict.as_dict(), **({"repairs": repairs.as_dict()} if repairs is not None else {})})
    elif verdict.verdict.value == "invalid" and not (loaded_model.report.is_valid and loaded_mapping.report.is_valid):
        _print_invalid_inputs((model, loaded_model.report, "model"), (mapping, loaded_mapping.report, "mapping"))
    else:
        _print_verdict(verdict)
        if repairs is not None:
            from causalplan.cli.explaining import print_repairs

            print_repairs(repairs)
    exit_with(verdict.verdict.exit_code)


@click.command(short_help="List the planners and whether each can run here.")
@json_option
def planners(as_json: bool) -> None:
    """List the planners, what each is for, and whether it can run on this machine."""
    from rich.table import Table

    from causalplan.planners.pipeline import DESCRIPTIONS, planner_availability

    availability = planner_availability()
    if as_json:
        print_json(
            [
                {"name": name, "description": DESCRIPTIONS[name], "available": problem is None, "problem": problem}
                for name, problem in availability.items()
            ]
        )
        return
    table = Table("planner", "what it does", "available")
    for name, problem in availability.items():
        table.add_row(name, DESCRIPTIONS[name], "yes" if problem is None else f"no: {problem}")
    console = make_console()
    console.print(table)
    console.print(f"VAL, which checks every plan (--no-val skips it): {_val_availability()}")


def _val_availability() -> str:
    from causalplan.errors import CausalPlanError
    from causalplan.planners.val import validate_binary

    try:
        validate_binary()
    except CausalPlanError as exc:
        return f"no: {exc.message}"
    return "yes"
