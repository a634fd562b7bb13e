"""The estimate-fits command: each fit's success probability measured by noisy robot insertions."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from causalplan.cli import common
from causalplan.cli.cluster_options import chunk_mapper, cluster_options
from causalplan.cli.common import (
    FILE,
    catalog_from,
    catalog_option,
    exit_on_error,
    fail,
    json_option,
    print_json,
    say,
    writing,
)

if TYPE_CHECKING:
    from causalplan.cli.cluster_options import ClusterChoice


@click.command("estimate-fits", short_help="Measure each fit's success probability by noisy robot insertions.")
@click.argument("object_id", metavar="OBJECT")
@click.option("--trials", "-n", type=click.IntRange(1, 100_000), default=200, help="Insertions per fit.")
@click.option("--seed", type=int, default=0, help="Random seed of the grasp noise: the same seed, the same numbers.")
@click.option(
    "--noise-mm",
    type=click.FloatRange(0.0, 20.0),
    default=1.0,
    help="Standard deviation of where the part sits in the gripper, per axis (millimetres).",
)
@click.option(
    "--noise-deg",
    type=click.FloatRange(0.0, 30.0),
    default=1.0,
    help="Standard deviation of how it is turned in the gripper (degrees).",
)
@click.option("--fit", "fit_ids", multiple=True, help="Only this fit (repeatable); default: every fit.")
@click.option(
    "--out",
    type=FILE,
    help="Write the probabilities as a catalog overlay (YAML) for `plan --catalog-overlay`.",
)
# 1000 is sim.fit_estimates.DEFAULT_CHUNK_INSERTIONS, written out: importing sim here loads PyBullet on every start.
@cluster_options("insertions", default_chunk_size=1000)
@json_option
@catalog_option
def estimate_fits_command(
    object_id: str,
    trials: int,
    seed: int,
    noise_mm: float,
    noise_deg: float,
    fit_ids: tuple[str, ...],
    out: Path | None,
    on_cluster: ClusterChoice | None,
    as_json: bool,
    catalog: tuple[Path, ...],
) -> None:
    """Measure each fit of OBJECT in physics: the robot makes the joint, and N trials hold the part a little off.

    The Panda fetches the moving part, carries it and drives it home along the connector
    axis; in each trial the part sits in the gripper off by a random offset (--noise-mm per
    axis) and turn (--noise-deg), follows the robot's commands, and succeeds when it does not
    jam on the way and its connector still arrives within the fit's own tolerance (a thread
    is stricter than a clip). Prints each fit's success rate with its 95% Wilson interval and
    the commonest failure codes.

    With --cluster or --workers every fit's insertions go to a Dask cluster in chunks of
    --chunk-size, all fits at once; each chunk repeats the robot's nominal run (the same run
    everywhere), so keep chunks large. The noises are drawn before the chunks are cut, so the
    numbers are those of the run here for the same --seed. For example:

    \b
        causalplan estimate-fits desk_lamp --trials 500 --noise-mm 0.5 --out overlay.yaml
        causalplan plan examples/paper/desk_lamp.yaml --planner mdp --catalog-overlay overlay.yaml
        causalplan estimate-fits desk_lamp --trials 20000 --workers 2
    """
    from causalplan.objects.overlay import overlay_data
    from causalplan.sim.fit_estimates import DEFAULT_CHUNK_INSERTIONS, estimate_fits

    objects = catalog_from(catalog)
    with exit_on_error():
        obj = objects.get(object_id)
    known = {fit.id for fit in obj.fits}
    unknown = sorted(set(fit_ids) - known)
    if unknown:
        fail("unknown_fit", f"The {obj.name} has no fit '{unknown[0]}'; its fits are: {', '.join(sorted(known))}.")
    chosen = [fit for fit in obj.fits if not fit_ids or fit.id in fit_ids]
    if not chosen:
        fail("unknown_fit", f"The {obj.name} has no fits to estimate.")
    where = "here" if on_cluster is None else "on the cluster"
    with exit_on_error(), common.progress_bar() as progress:
        bar = progress.add_task(f"{len(chosen)} fits, {trials} insertions each, {where}", total=len(chosen) * trials)
        estimates = estimate_fits(
            obj,
            trials,
            seed,
            noise_mm,
            noise_deg,
            [fit.id for fit in chosen],
            map_chunks=chunk_mapper(on_cluster),
            chunk_size=on_cluster.chunk_size if on_cluster is not None else DEFAULT_CHUNK_INSERTIONS,
            progress=lambda count: progress.advance(bar, count),
        )
    rows = [estimate.as_dict() for estimate in estimates]
    data = {"object": obj.id, "noise": {"mm": noise_mm, "deg": noise_deg}, "seed": seed, "fits": rows}
    if out is not None:
        import yaml

        command = (
            f"causalplan estimate-fits {obj.id} --trials {trials} --seed {seed} "
            f"--noise-mm {noise_mm:g} --noise-deg {noise_deg:g}"
        )
        with writing(out):
            out.write_text(yaml.safe_dump(overlay_data({obj.id: rows}, command), sort_keys=False), encoding="utf-8")
    if as_json:
        print_json({**data, "overlay": str(out) if out else None})
        return
    say(f"Fits of the {obj.name}, {trials} noisy insertions each (grasp noise {noise_mm:g} mm, {noise_deg:g}°):")
    for estimate in estimates:
        low, high = estimate.interval
        ranked = sorted(estimate.failures.items(), key=lambda item: (-item[1], item[0]))
        failures = ", ".join(f"{code} {count}" for code, count in ranked)
        catalog_value = obj.fit(estimate.fit).probability
        say(
            f"  {estimate.fit}: {estimate.probability:.3f} (95% {low:.3f}-{high:.3f}; catalog {catalog_value:g})"
            + (f"; failed: {failures}" if failures else "")
        )
    if out is not None:
        say(f"Wrote {out}: use it with `causalplan plan MODEL --catalog-overlay {out}`.")
