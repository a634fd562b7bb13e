"""Commands that write the task in other planners' formats: export-rddl."""

from __future__ import annotations

from pathlib import Path

import click

from causalplan.cli.common import FILE, catalog_from, catalog_option, load_task, say, writing


@click.command("export-rddl", short_help="Write the task's MDP as an RDDL domain and instance.")
@click.argument("model", type=FILE)
@click.option("--mapping", "-m", type=FILE, help="A step-3 mapping: export the task on that object instead.")
@click.option("--out", "out", type=FILE, required=True, help="The folder to write domain.rddl and instance.rddl to.")
@catalog_option
def export_rddl_command(model: Path, mapping: Path | None, out: Path, catalog: tuple[Path, ...]) -> None:
    """Write the task's MDP (fits that may fail, the model's rules as the goal) in RDDL.

    RDDL is the format of the International Probabilistic Planning Competitions, read by PROST
    and pyRDDLGym. A step attempts one fit; the state fluent `lit` becomes true one step after
    the model's goal holds.

    Example: causalplan export-rddl examples/paper/desk_lamp.yaml --out out/desk_lamp_rddl
    """
    from causalplan.planners.rddl import export_rddl

    task = load_task(model, mapping, catalog_from(catalog), as_json=False)
    exported = export_rddl(task)
    with writing(out, "write the RDDL to"):
        out.mkdir(parents=True, exist_ok=True)
        (out / "domain.rddl").write_text(exported.domain, encoding="utf-8")
        (out / "instance.rddl").write_text(exported.instance, encoding="utf-8")
    say(f"Wrote {out / 'domain.rddl'} and {out / 'instance.rddl'} ({len(exported.fit_names)} fits).")
