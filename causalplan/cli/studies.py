"""The analyze command: an experiment export turned into rates, tests and conclusions."""

from __future__ import annotations

import json
from pathlib import Path

import click

from causalplan.cli.common import (
    EXIT_OK,
    FILE,
    catalog_from,
    catalog_option,
    exit_on_error,
    exit_with,
    json_option,
    make_console,
    print_json,
    writing,
)


@click.command(short_help="Analyse an experiment export: rates, the paper's predictions tested, plots.")
@click.argument("export", type=FILE)
@click.option(
    "--out",
    type=FILE,
    default=Path("out/analysis"),
    help="Folder for trials.csv, codebook.csv, analysis.json, rates.png/.svg.",
)
@click.option(
    "--near-misses",
    is_flag=True,
    help="Also count, per condition, the failed transfers one or two edits would fix, and which edits "
    "(a repair search per failed trial).",
)
@click.option(
    "--troubleshooting",
    is_flag=True,
    help="Also, per condition and test object, the expected actions the participants' models need to repair "
    "the broken test object, against no model (uniform) and the catalog's fault priors (oracle).",
)
@json_option
@catalog_option
def analyze(
    export: Path, out: Path, near_misses: bool, troubleshooting: bool, as_json: bool, catalog: tuple[Path, ...]
) -> None:
    """Analyse an experiment export (the research page's JSON export).

    Prints the transfer rate of every condition on every test object with its 95% Wilson
    interval, tests the paper's predictions (trained on one category, models transfer more to
    that category's test object; trained on both, to both) with Fisher's exact tests
    (Holm-corrected) and a logistic GEE with the participant as cluster, and says in plain
    words what the data show. Writes a tidy CSV (one row per trial) with its codebook, the
    JSON of everything, and the plot.
    """
    from rich.markup import escape
    from rich.table import Table

    from causalplan.consensus.plausibility import MappingPlausibility
    from causalplan.studies.analysis import analyse_export
    from causalplan.studies.outputs import write_outputs
    from causalplan.studies.trials import read_export

    objects = catalog_from(catalog)
    with exit_on_error():
        data = read_export(export)
        analysis = analyse_export(data, objects, MappingPlausibility(objects))
    with writing(out, "write to"):
        written = write_outputs(analysis, out)
    misses = None
    if near_misses:
        from causalplan.explain.near_misses import near_misses as count_near_misses

        with exit_on_error():
            misses = count_near_misses(data, objects)
    repairs = None
    if troubleshooting:
        from causalplan.troubleshoot.study import troubleshooting_by_object

        repairs = troubleshooting_by_object(data, objects)
    if as_json:
        extra: dict[str, object] = (
            {"near_misses": [counts.as_dict() for counts in misses]} if misses is not None else {}
        )
        if repairs is not None:
            extra["troubleshooting"] = [row.as_dict() for row in repairs]
        print_json({**analysis.as_dict(), **extra, "files": [str(path) for path in written]})
        exit_with(EXIT_OK)
    console = make_console()
    table = Table(
        "condition",
        "training",
        "test object",
        "generalization",
        "transferred",
        "rate (95% CI)",
        "left out: undecided",
        "left out: excluded",
        title=f"Transfer rates from {export}: {analysis.table.left_out.says()}",
    )
    for rate in analysis.rates:
        share = rate.share
        shown = "-" if share.rate is None else f"{share.rate:.0%} ({share.low:.0%}-{share.high:.0%})"
        table.add_row(
            escape(rate.condition),
            rate.training_span or "",
            rate.test_object,
            rate.generalization or "",
            f"{rate.transfers}/{rate.trials}",
            shown,
            str(rate.undecided),
            str(rate.excluded),
        )
    console.print(table)
    for condition, reasons in analysis.reasons.items():
        if reasons:
            listed = ", ".join(f"{code} {count}" for code, count in reasons.items())
            console.print(f"Why models failed in {escape(condition)}: {listed}")
    for counts in misses or []:
        console.print(f"Near misses in {escape(counts.summary())}")
    if misses == []:
        console.print("Near misses: there is no failed transfer to check (among participants not excluded).")
    for row in repairs or []:
        console.print(f"Troubleshooting, {escape(row.summary())}")
    console.print("[bold]Conclusions[/]")
    for conclusion in analysis.conclusions:
        console.print(f"  - {escape(conclusion)}")
    if analysis.sensitivity is not None:
        found = analysis.sensitivity
        console.print(f"[bold]Mapping plausibility[/]: {escape(found.says())}")
        if found.implausible:
            without = {(rate.condition, rate.test_object): rate for rate in found.without.rates}
            for before in analysis.rates:
                after = without.get((before.condition, before.test_object))
                console.print(
                    f"  {escape(before.condition)} on {before.test_object}: {before.transfers}/{before.trials} "
                    f"with every transfer, {after.transfers if after else 0}/{after.trials if after else 0} "
                    "without the implausible ones"
                )
            for item in found.implausible:
                mapping = json.dumps(item.mapping.get("functions", item.mapping), ensure_ascii=False)
                console.print(
                    f"  trial {item.trial_id[:8]} (participant {item.participant_id[:8]}, {item.test_object}): "
                    f"score {item.score:.2f}, mapping {escape(mapping)}"
                )
    console.print(f"Wrote {', '.join(str(path) for path in written)}")
    exit_with(EXIT_OK)
