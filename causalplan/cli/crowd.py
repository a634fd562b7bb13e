"""The crowd's commands: consensus (one model from many), population (synthetic participants), crowd-curve."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import click

from causalplan.cli.cluster_options import cluster_options, trial_judge
from causalplan.cli.common import (
    EXIT_INVALID,
    EXIT_NO_PLAN,
    FILE,
    catalog_from,
    catalog_option,
    check_planner,
    exit_on_error,
    exit_with,
    fail,
    make_console,
    make_folder,
    planner_option,
    progress_bar,
    say,
    time_limit_option,
    writing,
)

if TYPE_CHECKING:
    from causalplan.cli.cluster_options import ClusterChoice
    from causalplan.consensus.judging import Judged
    from causalplan.objects.catalog import Catalog

# The default is consensus.build.MIN_SUPPORT, written out: importing build here would load numpy on every start.
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
@cluster_options("trials", default_chunk_size=250)
@catalog_option
def consensus(
    trials_file: Path,
    out: Path,
    min_support: float,
    planner: str,
    time_limit: float,
    simulate: bool,
    on_cluster: ClusterChoice | None,
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

    With --cluster or --workers the members' trials and the consensus's are judged on a Dask
    cluster in chunks of --chunk-size (the same verdicts as here; the bar moves per chunk).
    Exit 0 when the consensus transfers to some test object, 1 when to none, 2 when no valid
    consensus exists (or for invalid input).

    Example: causalplan population desk_lamp --n 30 --out crowd.jsonl &&
    causalplan consensus crowd.jsonl --out out/consensus --workers 2
    """
    from causalplan.consensus.build import build_consensus
    from causalplan.consensus.drawing import draw_consensus
    from causalplan.consensus.judging import judge, report
    from causalplan.consensus.participants import read_participants

    check_planner(planner)
    objects = catalog_from(catalog)
    if not trials_file.is_file():
        fail("file_not_found", f"There is no file {trials_file}.")
    with exit_on_error():
        participants = read_participants(trials_file)
        crowd = build_consensus(participants, objects, min_support)
    make_folder(out)
    with progress_bar() as progress:
        total = sum(len(p.mappings) for p in participants if p.id in crowd.members) + len(crowd.mappings)
        bar = progress.add_task("judging the crowd and its consensus", total=total)
        judged = judge(
            crowd,
            participants,
            objects,
            progress=lambda count: progress.advance(bar, count),
            judge_trials=trial_judge(on_cluster, objects, planner, time_limit, simulate),
        )
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
    _print_summary(judged, out, objects)
    if not crowd.loaded.is_valid:
        exit_with(EXIT_INVALID)
    if crowd.mappings and not any(judged.consensus_transfers(test) for test in crowd.mappings):
        exit_with(EXIT_NO_PLAN)


def _print_summary(judged: Judged, out: Path, objects: Catalog) -> None:
    from rich.table import Table

    from causalplan.transfer.verdict import generalization

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
    by_reason: dict[str, list[str]] = {}
    for who, why in crowd.left_out.items():
        by_reason.setdefault(why, []).append(who)
    for why, people in by_reason.items():
        names = ", ".join(people[:5]) + (f" and {len(people) - 5} more" if len(people) > 5 else "")
        console.print(f"Left out ({why}): {names}")
    if not crowd.loaded.is_valid:
        for problem in crowd.loaded.report.errors:
            console.print(f"[red]The consensus model is not valid:[/red] {problem.message}")
        best = max((rule.share for rule in crowd.rules), default=0.0)
        if best < crowd.min_support:
            lower = math.floor(best * 100) / 100
            console.print(
                f"No rule is held by {crowd.min_support:.0%} of the crowd (the most held: {best:.0%}): the crowd "
                f"is split between models. --min-support {lower:.2f} lets the most held rules in."
            )
    verdicts = Table("test object", "individuals who transfer", "consensus", title="Transfer")
    for test, result in judged.consensus_results.items():
        rate = judged.individual_rate(test)
        verdicts.add_row(
            f"{test} ({generalization(objects.get(crowd.training_object), objects.get(test))})",
            "-" if rate is None else f"{rate:.0%} of {len(crowd.mappings[test].mappers)}",
            result.verdict.verdict.value,
        )
    console.print(verdicts)
    console.print(f"Wrote consensus_model.yaml, the mappings, report.json and consensus_graph.png/.svg to {out}")


def _rate_options(function: Callable[..., None]) -> Callable[..., None]:
    """Add one --rate-<kind> option per error kind (default: the population's default rates)."""
    from causalplan.consensus.population import DEFAULT_RATES, ERROR_KINDS

    helps = {
        "non_causal": "a function that does not cause light ('hold things together') made a necessary cause",
        "effect_as_cause": "an effect of the light ('diffuse light') made a necessary cause",
        "uncaused_intermediate": "the rule producing the intermediate effect left out (an invalid model)",
        "object_specific": "this object's own words ('provide electricity'), unmapped on the other category",
        "paraphrase": "each label worded another way that means the same",
        "missed_part": "one part given no function in step 3",
    }
    for kind in reversed(ERROR_KINDS):
        function = click.option(
            f"--rate-{kind.replace('_', '-')}",
            kind,
            type=click.FloatRange(0.0, 1.0),
            default=DEFAULT_RATES[kind],
            help=f"Share of participants: {helps[kind]}.",
        )(function)
    return function


def _rates(options: dict[str, float]) -> dict[str, float]:
    from causalplan.consensus.population import ERROR_KINDS

    return {kind: options[kind] for kind in ERROR_KINDS}


@click.command(short_help="Make synthetic participants with the paper's error kinds, as a trials file.")
@click.argument("training_object", metavar="OBJECT")
@click.option("--n", "count", type=click.IntRange(1, 100_000), default=30, help="How many participants.")
@click.option("--seed", type=int, default=0, help="Random seed: the same seed gives the same participants.")
@click.option("--test", "tests", multiple=True, help="A test object each participant maps (repeatable; default: all).")
@click.option("--out", type=FILE, default=Path("out/population.jsonl"), help="The JSON Lines file to write.")
@_rate_options
def population(training_object: str, count: int, seed: int, tests: tuple[str, ...], out: Path, **rates: float) -> None:
    """Write N synthetic participants trained on OBJECT (desk_lamp or candle), one line per test object.

    Each line is {"id", "model", "mapping", "errors"}, as `batch` and `consensus` read; "errors"
    lists the error kinds that participant made. Every kind happens to a participant with its
    own --rate-<kind>. Making them is quick; judging them is the work, and `batch` and
    `consensus` do it on a Dask cluster with --cluster ADDRESS or --workers N.

    \b
    Example:
        causalplan population desk_lamp --n 30 --seed 1 --rate-effect-as-cause 0.6 --out crowd.jsonl
        causalplan batch crowd.jsonl --workers 2 --out out/crowd
    """
    from causalplan.consensus.population import population as make_population

    with exit_on_error():
        lines = make_population(training_object, count, seed, _rates(rates), tests)
    with writing(out):
        out.parent.mkdir(parents=True, exist_ok=True)
        with out.open("w", encoding="utf-8") as handle:
            handle.writelines(json.dumps(line, ensure_ascii=False) + "\n" for line in lines)
    made: dict[str, int] = {}
    people = {str(line["id"]): line["errors"] for line in lines}
    for errors in people.values():
        for kind in errors if isinstance(errors, list) else []:
            made[kind] = made.get(kind, 0) + 1
    summary = ", ".join(f"{kind} {number}" for kind, number in sorted(made.items())) or "none"
    say(f"Wrote {len(people)} participants ({len(lines)} trials) to {out}. Errors made: {summary}.")


@click.command("crowd-curve", short_help="Consensus vs the mean individual's transfer rate as crowds grow.")
@click.argument("training_object", metavar="OBJECT", default="desk_lamp")
@click.option("--sizes", default="1,3,10,30,100", help="Crowd sizes, comma-separated.")
@click.option("--draws", type=click.IntRange(1, 1000), default=10, help="Independent populations per size.")
@click.option("--seed", type=int, default=0, help="Seed of the first draw (draw k uses seed + k).")
@click.option("--test", "tests", multiple=True, help="Test objects (repeatable; default: the scenario's near and far).")
@support_option
@click.option("--simulate/--no-simulate", default=False, help="Check plans in the physics simulator too (slower).")
@click.option("--out", type=FILE, default=Path("out/crowd-curve"), help="Folder for curve.csv, curve.json, curve.png.")
@planner_option
@time_limit_option
@cluster_options("trials", default_chunk_size=250)
@catalog_option
@_rate_options
def crowd_curve(
    training_object: str,
    sizes: str,
    draws: int,
    seed: int,
    tests: tuple[str, ...],
    min_support: float,
    simulate: bool,
    out: Path,
    planner: str,
    time_limit: float,
    on_cluster: ClusterChoice | None,
    catalog: tuple[Path, ...],
    **rates: float,
) -> None:
    """Test the paper's prediction: is the crowd's model more accurate than the average person's?

    For each draw, a synthetic population of OBJECT's participants (see `population`) is judged,
    and the consensus of its first n members is built and judged, for each crowd size n. Prints
    a table and writes curve.csv, curve.json and curve.png (rates with 95% intervals over draws).
    All the draws' trials are judged as one batch: with --cluster or --workers, on a Dask cluster
    in chunks of --chunk-size (the same curve as here; the bar moves per chunk).

    Example: causalplan crowd-curve desk_lamp --draws 20 --rate-object-specific 0.7 --workers 2
    """
    import csv

    from rich.table import Table

    from causalplan.consensus.curve import crowd_curve as measure
    from causalplan.consensus.curve import plot_curve

    check_planner(planner)
    objects = catalog_from(catalog)
    try:
        crowd_sizes = sorted({int(size) for size in sizes.split(",") if size.strip()})
    except ValueError:
        fail("invalid_sizes", f"--sizes must be whole numbers separated by commas, not '{sizes}'.")
    if not crowd_sizes or crowd_sizes[0] < 1:
        fail("invalid_sizes", "--sizes needs at least one crowd size of 1 or more.")
    make_folder(out)
    chosen = _rates(rates)
    with progress_bar() as progress:
        bar = progress.add_task("building crowds", total=None)

        def judged(done: int, total: int) -> None:
            progress.update(bar, description="judging crowds and their consensus", completed=done, total=total)

        with exit_on_error():
            points = measure(
                training_object,
                objects,
                crowd_sizes,
                draws,
                seed,
                chosen,
                tests,
                min_support,
                progress=judged,
                judge_trials=trial_judge(on_cluster, objects, planner, time_limit, simulate),
            )
    rows = [point.as_dict() for point in points]
    with (out / "curve.csv").open("w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    settings = {
        "training_object": training_object,
        "draws": draws,
        "seed": seed,
        "rates": chosen,
        "min_support": min_support,
        "simulate": simulate,
    }
    (out / "curve.json").write_text(
        json.dumps({"settings": settings, "points": rows}, indent=1) + "\n", encoding="utf-8"
    )
    rate_text = ", ".join(f"{kind} {value:g}" for kind, value in chosen.items())
    plot_curve(points, out / "curve.png", f"{training_object}: {draws} draws; rates {rate_text}")
    table = Table(
        "test object",
        "crowd",
        "consensus transfers (95% CI)",
        "mean individual (2.5-97.5%)",
        title=f"Crowds trained on {training_object}, {draws} draws each",
    )
    for point in points:
        table.add_row(
            f"{point.test_object} ({point.generalization})",
            str(point.size),
            f"{point.consensus_rate:.0%} ({point.consensus_low:.0%}-{point.consensus_high:.0%})",
            f"{point.individual_rate:.0%} ({point.individual_low:.0%}-{point.individual_high:.0%})",
        )
    console = make_console()
    console.print(table)
    console.print(f"Wrote {out / 'curve.csv'}, {out / 'curve.json'} and {out / 'curve.png'}")
