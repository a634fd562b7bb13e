"""The wisdom-of-crowds prediction: consensus vs mean individual transfer rate as crowds grow.

    python benchmarks/crowd.py [--draws 10] [--seed 0] [--simulate] [--out out/crowd]

Runs the same code as ``causalplan crowd-curve`` for crowds trained on the desk lamp (near:
flashlight; far: candle, kerosene lamp) and on the candle (near: kerosene lamp; far: flashlight,
desk lamp) at the population's default error rates, then the desk lamp again with most people
using the lamp's own words (object_specific 0.7), and once per --min-support in 0.3, 0.5, 0.7
(how the default was chosen). Prints one table per run and writes a PNG per run to --out.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from causalplan.consensus.curve import CurvePoint, crowd_curve, plot_curve
from causalplan.consensus.population import DEFAULT_RATES
from causalplan.objects.catalog import load_catalog


def show(title: str, points: list[CurvePoint]) -> None:
    print(f"\n{title}")
    print(f"{'test object':22} {'n':>4} {'consensus (95% CI)':>22} {'mean individual (2.5-97.5%)':>30}")
    for p in points:
        consensus = f"{p.consensus_rate:.2f} ({p.consensus_low:.2f}-{p.consensus_high:.2f})"
        individual = f"{p.individual_rate:.2f} ({p.individual_low:.2f}-{p.individual_high:.2f})"
        print(f"{p.test_object + ' (' + p.generalization + ')':22} {p.size:4d} {consensus:>22} {individual:>30}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--simulate", action="store_true", help="check plans in the physics simulator too")
    parser.add_argument("--out", type=Path, default=Path("out/crowd"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    catalog = load_catalog()
    runs: list[tuple[str, str, dict[str, float], float]] = [
        ("desk_lamp", "default rates", {}, 0.5),
        ("candle", "default rates", {}, 0.5),
        ("desk_lamp", "object_specific 0.7", {"object_specific": 0.7}, 0.5),
        ("desk_lamp", "min-support 0.3", {}, 0.3),
        ("desk_lamp", "min-support 0.7", {}, 0.7),
    ]
    print(f"default rates: {DEFAULT_RATES}; {args.draws} draws, seed {args.seed}, simulate {args.simulate}")
    for training, name, rates, support in runs:
        started = time.perf_counter()
        points = crowd_curve(
            training,
            catalog,
            draws=args.draws,
            seed=args.seed,
            rates=rates,
            min_support=support,
            simulate=args.simulate,
        )
        seconds = time.perf_counter() - started
        show(f"{training}, {name} (min-support {support}): {seconds:.1f} s", points)
        slug = f"{training}-{name.replace(' ', '-').replace('.', '')}"
        plot_curve(points, args.out / f"{slug}.png", f"{training}, {name}, {args.draws} draws")


if __name__ == "__main__":
    main()
