"""How long the service takes to read a request body as JSON: ``parse_json`` against ``json.loads``.

    python benchmarks/body_json.py [--rounds 2000] [--base CHECKOUT]

``parse_json`` refuses what ``json.loads`` takes silently (a key twice, deep nesting, long
integers, NaN), so it does more; the ratio says how much more, on a plan request for the
paper's desk lamp and on a model with 200 rules. With ``--base CHECKOUT`` the older code's
``parse_json`` is timed too, in its own process, the runs interleaved.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent.parent

TIMER = """
import json, sys, time
sys.path.insert(0, sys.argv[1])
from causalplan.service.documents import parse_json
bodies = json.loads(sys.stdin.read())
rounds = int(sys.argv[2])
out = {}
for name, text in bodies.items():
    body = text.encode()
    for read, label in ((parse_json, "parse_json"), (json.loads, "json.loads")):
        read(body)
        started = time.perf_counter()
        for _ in range(rounds):
            read(body)
        out[f"{name} {label}"] = (time.perf_counter() - started) / rounds
print(json.dumps(out))
"""


def bodies() -> dict[str, str]:
    """Return the bodies timed: a plan request for the desk lamp, and one with 200 rules."""
    lamp = {
        "object": "desk_lamp",
        "functions": {"base_with_cables": ["provide electricity"], "light_bulb": ["turn electricity into light"]},
        "rules": ["provide electricity AND turn electricity into light CAUSES light"],
    }
    many = {**lamp, "rules": [f"provide electricity AND effect {n} CAUSES effect {n + 1}" for n in range(200)]}
    return {
        "desk lamp": json.dumps({"model": lamp, "planner": "fd"}, indent=2),
        "200 rules": json.dumps({"model": many, "planner": "fd"}, indent=2),
    }


def timed(checkout: Path, rounds: int) -> dict[str, float]:
    """Return the seconds per read of every body, by the parse_json of ``checkout`` and by json.loads."""
    run = subprocess.run(
        [sys.executable, "-c", TIMER, str(checkout), str(rounds)],
        input=json.dumps(bodies()),
        capture_output=True,
        text=True,
        check=True,
    )
    result: dict[str, float] = json.loads(run.stdout)
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=2000, help="reads of each body per measurement")
    parser.add_argument("--repeat", type=int, default=5, help="interleaved measurements of each checkout")
    parser.add_argument("--base", type=Path, help="a checkout of the older code, measured in the same run")
    args = parser.parse_args()
    checkouts = {"ours": HERE, **({"base": args.base.resolve()} if args.base else {})}
    runs: dict[str, list[dict[str, float]]] = {name: [] for name in checkouts}
    for _ in range(args.repeat):
        for name, checkout in checkouts.items():
            runs[name].append(timed(checkout, args.rounds))
    median = {name: {key: statistics.median(r[key] for r in found) for key in found[0]} for name, found in runs.items()}
    for body in bodies():
        ours = median["ours"][f"{body} parse_json"]
        plain = median["ours"][f"{body} json.loads"]
        print(f"{body}: parse_json / json.loads = {ours / plain:.2f}x")
        if "base" in median:
            print(f"{body}: parse_json ours / base = {ours / median['base'][f'{body} parse_json']:.2f}x")


if __name__ == "__main__":
    main()
