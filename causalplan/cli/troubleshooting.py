"""`causalplan troubleshoot`: repair a broken object with a person's causal model, beside the baselines."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import click

from causalplan.cli.common import (
    EXIT_INVALID,
    EXIT_NO_PLAN,
    EXIT_OK,
    EXIT_UNDECIDED,
    FILE,
    catalog_from,
    catalog_option,
    dim,
    exit_with,
    fail,
    json_option,
    load_valid_mapping,
    load_valid_model,
    make_console,
    print_json,
    say,
    writing,
)

if TYPE_CHECKING:
    from causalplan.troubleshoot.task import TroubleshootingTask

STRATEGY_WORDS = {
    "model": "the person's causal model",
    "uniform": "no model: every part equally suspect",
    "oracle": "the catalog's fault priors",
}


@click.command(short_help="Repair a broken object: the fewest expected actions with the model, and without.")
@click.argument("model", type=FILE)
@click.option("--mapping", "-m", type=FILE, help="A step-3 mapping: troubleshoot that object with the model.")
@click.option("--object", "object_id", help="The broken object's id (default: the mapping's, else the model's).")
@click.option("--fault", help="The broken part: run one episode and print each action with what it showed.")
@click.option(
    "--all-faults", is_flag=True, help="Print the strategies' table: every fault, under the catalog's priors."
)
@click.option(
    "--strategy",
    type=click.Choice(["model", "uniform", "oracle"]),
    default="model",
    help="With --fault: whose policy runs the episode.",
)
@click.option(
    "--physics",
    is_flag=True,
    help="With --fault: rebuild the object as the episode left it at its last test, in physics (PyBullet), "
    "and say whether it gives its goal there (parts move themselves; --robot has the Panda do each action).",
)
@click.option(
    "--robot",
    is_flag=True,
    help="With --fault: the Franka Panda carries out the episode in physics, action by action (detach, set "
    "aside, take the spare, attach, light), within its datasheet's limits.",
)
@click.option(
    "--motors",
    is_flag=True,
    help="With --robot: also play the motor commands through the Panda's joint motors in physics (as "
    "`simulate --robot --motors`), and report the tracking error, slip and whether it still gives the goal.",
)
@click.option("--trajectory", type=FILE, help="With --robot: write the Panda's motor commands (check-trajectory).")
@json_option
@catalog_option
def troubleshoot(
    model: Path,
    mapping: Path | None,
    object_id: str | None,
    fault: str | None,
    all_faults: bool,
    strategy: str,
    physics: bool,
    robot: bool,
    motors: bool,
    trajectory: Path | None,
    as_json: bool,
    catalog: tuple[Path, ...],
) -> None:
    """Troubleshoot a broken OBJECT (one part is faulty) with the causal MODEL as the robot's prior.

    The robot tests (switch on, light it), inspects a part whose fault shows, detaches and
    attaches parts (a part is reached once what blocks it or sits on it is off), and replaces a
    part with a spare; every action costs 1. Each strategy's policy is exact: the fewest
    expected actions under its prior ('model', 'uniform', 'oracle').

    \b
        causalplan troubleshoot examples/paper/desk_lamp.yaml --fault light_bulb
        causalplan troubleshoot examples/paper/desk_lamp.yaml -m examples/paper/flashlight_mapping.yaml --all-faults

    Exit codes: 0 done, 1 no goal in physics (--physics: the rebuilt object; --robot: the
    Panda could not carry out the episode, or its last test gave no goal, or with --motors
    driven by its motors it did not), 2 invalid input, 3 too large to solve exactly.
    """
    from causalplan.errors import CausalPlanError
    from causalplan.troubleshoot.errors import TooLargeError
    from causalplan.troubleshoot.task import troubleshooting_task

    if (fault is not None) == all_faults:
        fail("missing_option", "Give --fault PART (one episode) or --all-faults (the strategies' table), not both.")
    if (physics or robot) and fault is None:
        fail("missing_option", "--physics and --robot go with --fault PART: they rebuild that episode's object.")
    if trajectory is not None and not robot:
        fail("missing_option", "--trajectory needs --robot (the robot's motor commands are what it writes).")
    if motors and not robot:
        fail("missing_option", "--motors needs --robot (it plays the robot's motor commands through its motors).")
    known = catalog_from(catalog)
    causal_model = load_valid_model(model, known, as_json)
    labelling = load_valid_mapping(mapping, known, as_json) if mapping else None
    chosen = object_id or (labelling or causal_model.labelling).object_id
    try:
        task = troubleshooting_task(known.get(chosen), causal_model, labelling)
        if fault is not None:
            if robot:
                _robot_episode(task, fault, strategy, trajectory, motors, as_json)
            else:
                _episode(task, fault, strategy, physics, as_json)
        else:
            _table(task, as_json)
    except TooLargeError as exc:
        _refuse(exc.code, exc.message, as_json, EXIT_UNDECIDED)
    except CausalPlanError as exc:
        _refuse(exc.code, exc.message, as_json, EXIT_INVALID)


def _refuse(code: str, message: str, as_json: bool, exit_code: int) -> None:
    if as_json:
        print_json({"status": "error", "error": {"code": code, "message": message}})
    else:
        say(f"{click.style('error', fg='red', bold=True)}[{code}]: {message}", err=True)
    exit_with(exit_code)


def _say_episode(task: TroubleshootingTask, fault: str, strategy: str) -> None:
    obj = task.obj
    episode = task.episode(strategy, fault)
    others = {name: task.episode(name, fault).actions for name in task.strategies}
    looks = next((f.looks for f in obj.faults if f.part == fault), "a fault the catalog does not list")
    say(f"The {obj.name} gives no {obj.goal}: the {obj.part(fault).name} is broken ({looks}).")
    say(dim(f"Strategy {strategy}: {STRATEGY_WORDS[strategy]}."))
    for number, step in enumerate(episode.steps, start=1):
        say(f"{number:>3}. {step.text(obj.goal)}")
    compared = ", ".join(f"{name} {actions}" for name, actions in others.items())
    say(f"Repaired in {episode.actions} actions ({compared}).")


def _episode(task: TroubleshootingTask, fault: str, strategy: str, in_physics: bool, as_json: bool) -> None:
    from causalplan.troubleshoot.answer import episode_answer

    obj = task.obj
    episode = task.episode(strategy, fault)
    rebuilt = None
    if in_physics:
        from causalplan.sim.troubleshooting import repair_in_physics

        rebuilt = repair_in_physics(obj, episode)
    works = rebuilt is None or rebuilt.produces_goal
    if as_json:
        answer = episode_answer(task, fault, strategy)
        print_json(
            {
                "status": "repaired" if works else "not_repaired_in_physics",
                "object": obj.id,
                **answer,
                **({"physics": rebuilt.as_dict()} if rebuilt is not None else {}),
            }
        )
        exit_with(EXIT_OK if works else EXIT_NO_PLAN)
    _say_episode(task, fault, strategy)
    if rebuilt is not None:
        order = ", ".join(rebuilt.order)
        if works:
            say(f"In physics, rebuilt in that order ({order}): the {obj.name} gives {obj.goal}.")
        else:
            why = rebuilt.report.explanation() or f"the broken {fault} was never replaced"
            say(click.style(f"In physics, rebuilt in that order ({order}): no {obj.goal}, {why}.", fg="red"))
        exit_with(EXIT_OK if works else EXIT_NO_PLAN)


def _robot_episode(
    task: TroubleshootingTask, fault: str, strategy: str, trajectory: Path | None, motors: bool, as_json: bool
) -> None:
    from causalplan.sim.robot_episode import robot_episode
    from causalplan.troubleshoot.answer import episode_answer

    obj = task.obj
    run = robot_episode(obj, task.episode(strategy, fault), motors=motors)
    if trajectory is not None and run.commands is not None:
        with writing(trajectory):
            trajectory.write_text(json.dumps(run.commands.as_dict()), encoding="utf-8")
    works = run.produces_goal
    if as_json:
        print_json(
            {
                "status": "repaired" if works else "not_repaired_in_physics",
                "object": obj.id,
                **episode_answer(task, fault, strategy),
                "robot": run.as_dict(),
            }
        )
        exit_with(EXIT_OK if works else EXIT_NO_PLAN)
    _say_episode(task, fault, strategy)
    for action in run.actions:
        motions = ", ".join(action.motions) or "no motion"
        said = f"{action.number:>3}. the Panda: {motions}" + (f" ({action.observed})" if action.observed else "")
        say(said if action.passed else click.style(f"{said}: {action.failure}: {action.message}", fg="red"))
    driven = run.motors
    if driven is not None:
        tracked = f"tracking within {driven.joint_error:.4f} rad, {driven.gripper_error_mm:.1f} mm at the gripper"
        failure = driven.failure
        outcome = "" if failure is None else f"; {failure.value} at action {driven.step}: {driven.message}"
        goal = f"gives {obj.goal}" if driven.produces_goal else f"no {obj.goal}"
        say(f"Driven by its motors: {goal}, {tracked}{outcome}.")
    if works:
        say(f"In physics, the Panda repaired the {obj.name}: it gives {obj.goal} ({run.as_dict()['seconds']} s).")
    else:
        why = "the broken part was never replaced" if run.carried_out else "the robot could not carry it out"
        if run.carried_out and run.broken_part_replaced and run.mechanism_works:
            why = "driven by its motors, the robot did not repair it"
        say(click.style(f"In physics, no {obj.goal}: {why}.", fg="red"))
    exit_with(EXIT_OK if works else EXIT_NO_PLAN)


def _table(task: TroubleshootingTask, as_json: bool) -> None:
    from rich.table import Table

    from causalplan.troubleshoot.answer import table_answer
    from causalplan.troubleshoot.measures import REPAIR_BONUS

    obj = task.obj
    if as_json:
        print_json(table_answer(task))
        return
    table = task.table()
    console = make_console()
    columns = ["strategy", "expected actions", "worst", "reward share"] + [
        f"{fault.part} ({fault.probability:g})" for fault in obj.faults
    ]
    grid = Table(*columns, title=f"Troubleshooting the {obj.name} ({obj.fault_priors} priors)", title_justify="left")
    for name, result in table.items():
        per_fault = [str(fault.actions) for fault in result.faults]
        grid.add_row(
            name, f"{result.expected_actions:.2f}", str(result.worst_actions), f"{result.reward_share:.3f}", *per_fault
        )
    console.print(grid)
    say(
        dim(
            f"Actions per fault location; reward: -1 per action, +{REPAIR_BONUS:g} for the repair, as a share of a "
            "robot's that knew the broken part, averaged over the fault locations."
        )
    )
