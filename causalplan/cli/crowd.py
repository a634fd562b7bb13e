"""The crowd's commands: consensus (one model from many), population (synthetic participants), crowd-curve."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import click

from causalplan.cli.common import (
    EXIT_INVALID,
    EXIT_NO_PLAN,
    FILE,
    catalog_from,
    catalog_option,
    check_planner,
    exit_with,
    fail,
    make_console,
    planner_option,
    progress_bar,
    time_limit_option,
)

if TYPE_CHECKING:
    from causalplan.consensus.judging import Judged

support_option = click.option(
    "--min-support",
    type=click.FloatRange(0.0, 1.0, min_open=True),
    default=0.5,
    help="Share of the crowd a rule (or a function's place on a part) needs to enter the consensus.",
)


def _write_yaml(path: Path, data: object, header: str) -> None:
    import yaml

    text = yaml.safe_dump(data, sort_keys=False, allow_unicode=True, width=110)
    path.write_text(f"# {header}\n{text}", encoding="utf-8")


@click.command(short_help="One causal model from many participants' models; who holds each rule.")
@click.argument("trials_file", metavar="TRIALS", type=FILE)
@click.option("--out", type=FILE, default=Path("out/consensus"), help="Folder for the model, mappings, report, graph.")
@support_option
@planner_option
@time_limit_option
@click.option("--simulate/--no-simulate", default=True, help="Check plans in the physics simulator (as transfer does).")
@catalog_option
def consensus(
    trials_file: Path,
    out: Path,
    min_support: float,
    planner: str,
    time_limit: float,
    simulate: bool,
    catalog: tuple[Path, ...],
) -> None:
    """Build the crowd's model from many participants trained on the same object, and judge it.

    TRIALS is a JSON Lines file as `batch` reads, one {"id", "model", "mapping"} a line (the
    mapping may be absent; lines with the same id are one person mapping several objects), or
    an experiment export (the research page's JSON). Labels that mean the same (words and the
    part they sit on) become one node; a rule enters when at least --min-support of the crowd
    holds it. Writes to --out: consensus_model.yaml (checks, plans and transfers like any
    model), consensus_mapping_<object>.yaml per test object, report.json (each rule's
    support and holders, the label clusters, every verdict, individual_transfer_rate,
    consensus_verdict) and consensus_graph.png/.svg (line width = support).

    Example: causalplan consensus examples/batch/trials.jsonl --out out/consensus
    """
    from causalplan.consensus.build import build_consensus
    from causalplan.consensus.drawing import draw_consensus
    from causalplan.consensus.judging import judge, report
    from causalplan.consensus.participants import read_participants
    from causalplan.errors import CausalPlanError

    check_planner(planner)
    objects = catalog_from(catalog)
    if not trials_file.is_file():
        fail("file_not_found", f"There is no file {trials_file}.")
    try:
        participants = read_participants(trials_file)
        crowd = build_consensus(participants, objects, min_support)
    except CausalPlanError as exc:
        fail(exc.code, exc.message)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        fail("output_not_writable", f"Cannot create {out}: {exc.strerror}.")
    with progress_bar() as progress:
        total = sum(len(p.mappings) for p in participants if p.id in crowd.members) + len(crowd.mappings)
        bar = progress.add_task("judging the crowd and its consensus", total=total)
        judged = judge(crowd, participants, objects, planner, time_limit, simulate, lambda: progress.advance(bar))
    _write_yaml(
        out / "consensus_model.yaml",
        crowd.model_data,
        f"The consensus of {len(crowd.members)} participants' models (rules held by >= {min_support:.0%}).",
    )
    for test, mapping in crowd.mappings.items():
        _write_yaml(
            out / f"consensus_mapping_{test}.yaml",
            mapping.data,
            f"The consensus step-3 mapping of the {test} ({len(mapping.mappers)} participants mapped it).",
        )
    data = report(judged)
    (out / "report.json").write_text(json.dumps(data, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    draw_consensus(crowd, crowd.models, out)
    _print_summary(judged, out)
    if not crowd.loaded.is_valid:
        exit_with(EXIT_INVALID)
    if crowd.mappings and not any(judged.consensus_transfers(test) for test in crowd.mappings):
        exit_with(EXIT_NO_PLAN)


def _print_summary(judged: Judged, out: Path) -> None:
    from rich.table import Table

    crowd = judged.consensus
    console = make_console()
    table = Table("rule", "support", "held by", "in the consensus", title=f"Rules of {len(crowd.members)} participants")
    for rule in crowd.rules[:15]:
        held = ", ".join(rule.holders[:4]) + (f" and {len(rule.holders) - 4} more" if len(rule.holders) > 4 else "")
        table.add_row(
            crowd.rule_text(rule), f"{rule.share:.0%}", held, "yes" if rule.entered else rule.why_left_out or ""
        )
    if len(crowd.rules) > 15:
        table.caption = f"and {len(crowd.rules) - 15} more rules held by fewer people (report.json has all)"
    console.print(table)
    if crowd.left_out:
        console.print(f"Left out: {'; '.join(f'{who}: {why}' for who, why in crowd.left_out.items())}")
    if not crowd.loaded.is_valid:
        for problem in crowd.loaded.report.errors:
            console.print(f"[red]The consensus model is not valid:[/red] {problem.message}")
    verdicts = Table("test object", "individuals who transfer", "consensus", title="Transfer")
    for test, result in judged.consensus_results.items():
        rate = judged.individual_rate(test)
        verdicts.add_row(
            f"{test} ({result.verdict.generalization})",
            "-" if rate is None else f"{rate:.0%} of {len(crowd.mappings[test].mappers)}",
            result.verdict.verdict.value,
        )
    console.print(verdicts)
    console.print(f"Wrote consensus_model.yaml, the mappings, report.json and consensus_graph.png/.svg to {out}")
