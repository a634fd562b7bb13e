"""Batch transfer speed: 1,000 simulated participants' trials through ``causalplan batch``.

    python benchmarks/batch.py [--trials 1000] [--seed 0] [--keep FILE] [--base CHECKOUT] [--rounds 3]

Participants are simulated from the paper's scenarios (desk lamp -> flashlight, candle ->
kerosene lamp, an energy model -> candle, the paper's failed model): each words the functions
in their own way (one of several phrasings per concept, random case and spacing), some forget
to map a function, add one the model never used, or write a broken rule. The trials are
judged twice in the same run: by ``causalplan batch`` (one process, the fast path), and, as the
reference, by the plain path: one ``evaluate_transfer`` per trial with every cache emptied
first, on a sample. It prints trials per second for both, the ratio, and checks that both
paths gave the same verdicts on the sample. Target: >= 200 trials per second.

With ``--base CHECKOUT`` (another checkout of causalplan, e.g. ``git worktree add /tmp/base
96c4986``), that checkout's ``causalplan batch`` judges the same trials too, with this Python
and the checkout first on ``PYTHONPATH``, the two interleaved over ``--rounds`` rounds; the
ratio of their median throughputs is checked against ``BASE_RATIO``. Ours runs as a user
runs it (VAL on every plan) and once more with ``--no-val``.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TARGET = 200.0
BASE_RATIO = 0.8
"""Our throughput must be at least this fraction of the base checkout's, measured in the same run."""

PHRASES = {
    "power": ["provide electricity", "supply power", "give energy", "power source", "electricity"],
    "convert": ["turn electricity into light", "make light from power", "glow", "convert energy to light"],
    "close": ["close the circuit", "complete the circuit", "connect the circuit"],
    "fuel": ["provide fuel", "hold the fuel", "fuel source", "store wax"],
    "draw": ["draw up the fuel", "soak up fuel", "carry the fuel"],
    "flame": ["start a flame", "ignite", "light it", "make fire"],
    "diffuse": ["diffuse light", "spread light"],
    "hold": ["hold things together", "keep parts in place"],
}

SCENARIOS = [
    # (training object, {part: concepts}, rules as concept lists, test object, {part: concepts})
    (
        "desk_lamp",
        {"base_with_cables": ["power"], "light_bulb": ["convert", "close"]},
        [(["power", "close"], "flow"), (["flow", "convert"], "light")],
        "flashlight",
        {"batteries": ["power"], "head": ["convert", "close"]},
    ),
    (
        "candle",
        {"wax": ["fuel"], "wick": ["draw"], "match": ["flame"]},
        [(["fuel", "draw"], "tip"), (["tip", "flame"], "light")],
        "kerosene_lamp",
        {"fuel_tank": ["fuel"], "wick": ["draw"], "lighter": ["flame"]},
    ),
    (
        "desk_lamp",
        {"base_with_cables": ["power", "flame"], "light_bulb": ["convert"]},
        [(["power", "flame"], "release"), (["release", "convert"], "light")],
        "candle",
        {"wax": ["power"], "wick": ["convert"], "match": ["flame"]},
    ),
    (
        "desk_lamp",
        {"shade": ["diffuse"], "light_bulb": ["convert"], "base_with_cables": ["power"]},
        [(["power", "convert", "diffuse"], "light")],
        "flashlight",
        {"case": ["hold"], "head": ["diffuse", "power"], "batteries": ["power"]},
    ),
]
EFFECTS = {
    "flow": ["electricity flows", "current runs"],
    "tip": ["fuel at the tip", "wet wick"],
    "release": ["energy is released", "energy comes out"],
    "light": ["light"],
}


def _noise(rng: random.Random, label: str) -> str:
    if rng.random() < 0.2:
        label = label.upper() if rng.random() < 0.5 else label.title()
    return label.replace(" ", "  ") if rng.random() < 0.1 else label


def participant(rng: random.Random, number: int) -> dict[str, object]:
    """Return one simulated participant's trial."""
    training, step1, rules, test, step3 = rng.choice(SCENARIOS)
    words = {concept: rng.choice(options) for concept, options in {**PHRASES, **EFFECTS}.items()}
    functions = {part: [_noise(rng, words[c]) for c in concepts] for part, concepts in step1.items()}
    rule_texts = [
        " AND ".join(_noise(rng, words[c]) for c in causes) + " CAUSES " + words[effect] for causes, effect in rules
    ]
    if rng.random() < 0.08:  # a broken rule
        rule_texts[0] = rule_texts[0].replace(" CAUSES ", " ")
    mapping = {part: [_noise(rng, words[c]) for c in concepts] for part, concepts in step3.items()}
    if rng.random() < 0.15:  # forgets a function in step 3
        part = rng.choice(list(mapping))
        mapping[part] = mapping[part][1:]
    if rng.random() < 0.15:  # adds one the model never used
        part = rng.choice(list(mapping))
        mapping[part] = [*mapping[part], words["hold"]]
    if rng.random() < 0.1:  # words one function differently in step 3
        part = rng.choice(list(mapping))
        if mapping[part]:
            mapping[part] = [rng.choice(PHRASES["power"]), *mapping[part][1:]]
    return {
        "id": f"p{number:04d}",
        "model": {"object": training, "functions": functions, "rules": rule_texts},
        "mapping": {"object": test, "functions": mapping},
    }


def write_trials(path: Path, count: int, seed: int) -> None:
    """Write ``count`` simulated trials as JSON Lines."""
    rng = random.Random(seed)
    with path.open("w", encoding="utf-8") as handle:
        for number in range(count):
            handle.write(json.dumps(participant(rng, number)) + "\n")


def plain_path(path: Path, sample: int) -> tuple[float, dict[str, str]]:
    """Judge the first ``sample`` trials one by one with every cache emptied; return (trials/s, verdicts)."""
    from causalplan import caches
    from causalplan.objects.catalog import load_catalog
    from causalplan.transfer.batch import evaluate_trial, read_trials

    catalog = load_catalog()
    trials = list(read_trials(path))[:sample]
    verdicts: dict[str, str] = {}
    started = time.perf_counter()
    for trial in trials:
        caches.fresh()
        verdicts[trial.id] = evaluate_trial(trial, catalog, "auto", 30.0, True).verdict.verdict.value
    return len(trials) / (time.perf_counter() - started), verdicts


def batch_seconds(trials: Path, out: Path, base: Path | None = None, *options: str) -> float:
    """Return the wall time of one ``causalplan batch`` process on ``trials`` (ours, or ``base``'s code)."""
    if base is None:
        command = [str(Path(sys.executable).with_name("causalplan")), "batch", str(trials), "--out", str(out)]
        environment = None
    else:
        command = [sys.executable, "-m", "causalplan.cli", "batch", str(trials), "--out", str(out)]
        environment = {**os.environ, "PYTHONPATH": str(base)}
    started = time.perf_counter()
    subprocess.run(
        [*command, *options],
        check=True,
        cwd=base or ROOT,
        env=environment,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    return time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--trials", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--sample", type=int, default=100, help="trials judged by the plain path")
    parser.add_argument("--keep", type=Path, help="also keep the generated trials in this file")
    parser.add_argument("--base", type=Path, help="a checkout of the code to compare with (same trials, same run)")
    parser.add_argument("--rounds", type=int, default=3, help="interleaved runs of each with --base")
    parser.add_argument("--output", type=Path, default=ROOT / "benchmarks" / "results" / "batch.json")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        trials = Path(folder) / "trials.jsonl"
        write_trials(trials, args.trials, args.seed)
        if args.keep:
            args.keep.write_text(trials.read_text())
        ours_out, base_out = Path(folder) / "ours", Path(folder) / "base"
        ours_seconds, base_seconds = [], []
        for _ in range(args.rounds if args.base else 1):
            ours_seconds.append(batch_seconds(trials, ours_out))
            if args.base:
                base_seconds.append(batch_seconds(trials, base_out, args.base.resolve()))
        no_val_seconds = batch_seconds(trials, Path(folder) / "no-val", None, "--no-val")
        fast_seconds = statistics.median(ours_seconds)
        fast = json.loads((ours_out / "verdicts.json").read_text())
        base_same = None
        if args.base:
            base_verdicts = {row["id"]: row["verdict"] for row in json.loads((base_out / "verdicts.json").read_text())}
            base_same = all(row["verdict"] == base_verdicts[row["id"]] for row in fast)
        plain_rate, plain = plain_path(trials, args.sample)
    fast_rate = args.trials / fast_seconds
    counts: dict[str, int] = {}
    deciders: dict[str, int] = {}
    for row in fast:
        counts[row["verdict"]] = counts.get(row["verdict"], 0) + 1
        deciders[row["decided_by"]] = deciders.get(row["decided_by"], 0) + 1
    same = all(row["verdict"] == plain[row["id"]] for row in fast if row["id"] in plain)
    print(f"{args.trials} trials: {counts}; decided by {deciders}")
    print(f"causalplan batch (whole process, VAL on): {fast_seconds:.2f} s = {fast_rate:.0f} trials/s")
    print(f"causalplan batch --no-val: {no_val_seconds:.2f} s = {args.trials / no_val_seconds:.0f} trials/s")
    print(f"plain path (one trial at a time, caches emptied, {args.sample} trials): {plain_rate:.1f} trials/s")
    print(f"ratio fast/plain: {fast_rate / plain_rate:.1f}x; same verdicts on the sample: {same}")
    print(f"target >= {TARGET:.0f} trials/s: {'met' if fast_rate >= TARGET else 'NOT met'}")
    base_ratio = None
    if args.base:
        base_rate = args.trials / statistics.median(base_seconds)
        base_ratio = fast_rate / base_rate
        print(
            f"base checkout {args.base}: {base_rate:.0f} trials/s (median of {args.rounds}, interleaved); "
            f"ours/base {base_ratio:.2f} (target >= {BASE_RATIO}: {'met' if base_ratio >= BASE_RATIO else 'NOT met'}); "
            f"same verdicts as the base: {base_same}"
        )
    report = {
        "trials": args.trials,
        "seed": args.seed,
        "verdicts": counts,
        "decided_by": deciders,
        "fast_seconds": fast_seconds,
        "fast_seconds_each": ours_seconds,
        "fast_trials_per_s": fast_rate,
        "no_val_trials_per_s": args.trials / no_val_seconds,
        "plain_sample": args.sample,
        "plain_trials_per_s": plain_rate,
        "same_verdicts_on_sample": same,
        "target_trials_per_s": TARGET,
        "base": str(args.base) if args.base else None,
        "base_seconds_each": base_seconds,
        "base_ratio": base_ratio,
        "base_ratio_target": BASE_RATIO,
        "same_verdicts_as_base": base_same,
        "met": fast_rate >= TARGET and same and (base_ratio is None or (base_ratio >= BASE_RATIO and bool(base_same))),
    }
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
