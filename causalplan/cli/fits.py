"""The estimate-fits command: each fit's success probability measured by noisy robot insertions."""

from __future__ import annotations

from pathlib import Path

import click

from causalplan.cli import common
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
    as_json: bool,
    catalog: tuple[Path, ...],
) -> None:
    """Measure each fit of OBJECT in physics: the robot makes the joint, and N trials hold the part a little off.

    The Panda fetches the moving part, carries it and drives it home along the connector
    axis; in each trial the part sits in the gripper off by a random offset (--noise-mm per
    axis) and turn (--noise-deg), follows the robot's commands, and succeeds when it does not
    jam on the way and its connector still arrives within the fit's own tolerance (a thread
    is stricter than a clip). Prints each fit's success rate with its 95% Wilson interval and
    the commonest failure codes. For example:

    \b
        causalplan estimate-fits desk_lamp --trials 500 --noise-mm 0.5 --out overlay.yaml
        causalplan plan examples/paper/desk_lamp.yaml --planner mdp --catalog-overlay overlay.yaml
    """
    from causalplan.objects.overlay import overlay_data
    from causalplan.sim.fit_estimates import estimate_fit

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
    estimates = []
    with exit_on_error(), common.progress_bar() as progress:
        bar = progress.add_task("estimating", total=len(chosen))
        for fit in chosen:
            progress.update(bar, description=f"{fit.id}: {trials} trials")
            estimates.append(estimate_fit(obj, fit, trials, seed, noise_mm, noise_deg))
            progress.update(bar, advance=1)
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
