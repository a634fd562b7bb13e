"""A synthetic run of the paper's far-generalization experiment, written as an export for ``analyze``."""

from __future__ import annotations

import json
from pathlib import Path

import click

from causalplan.cli.common import FILE, catalog_from, catalog_option, exit_on_error, say, writing


@click.command("synthetic-study", short_help="Run the paper's design with synthetic participants; write an export.")
@click.option("--n", "per_condition", type=click.IntRange(1, 1000), default=20, help="Participants per condition.")
@click.option("--seed", type=int, default=1, help="The same seed gives the same participants.")
@click.option(
    "--abstract",
    nargs=2,
    type=click.FloatRange(0.0, 1.0),
    default=(0.2, 0.2),
    help="Chance of wording the model in general terms: trained on one category, trained on both.",
)
@click.option(
    "--slip",
    nargs=2,
    type=click.FloatRange(0.0, 1.0),
    default=(0.1, 0.1),
    help="Chance of leaving a part out in step 3: trained on one category, trained on both.",
)
@click.option("--out", type=FILE, default=Path("out/synthetic-study.json"), help="The export (JSON) to write.")
@catalog_option
def synthetic_study(
    per_condition: int,
    seed: int,
    abstract: tuple[float, float],
    slip: tuple[float, float],
    out: Path,
    catalog: tuple[Path, ...],
) -> None:
    """Make the paper's far-generalization design from the catalog, fill it with synthetic participants,
    judge every trial with the transfer check, and write the export `analyze` reads.

    \b
    Example (the paper's prediction, then a population built the other way round):
        causalplan synthetic-study --n 20 --out out/study.json && causalplan analyze out/study.json
        causalplan synthetic-study --abstract 1 0 --slip 0.05 0.7 --out out/opposite.json
    """
    from causalplan.consensus.paper_study import synthetic_export
    from causalplan.consensus.population import paper_population
    from causalplan.studies.far_generalization import SPANS, far_generalization_conditions

    objects = catalog_from(catalog)
    knobs = {span: {"abstract": abstract[i], "slip": slip[i]} for i, span in enumerate(SPANS)}
    with exit_on_error():
        conditions = far_generalization_conditions(objects)
        lines = paper_population(conditions, objects, per_condition, seed, knobs)
    export = synthetic_export(lines, objects, name="synthetic far-generalization study")
    with writing(out):
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(export, indent=1) + "\n", encoding="utf-8")
    say(f"Wrote {out}: {len(export['trials'])} trials of {len(export['participants'])} participants.")
