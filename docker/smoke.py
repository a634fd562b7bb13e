"""A running service's smoke test: /health answers ok, one plan is found, one transfer is judged.

    python docker/smoke.py BASE_URL        e.g. http://127.0.0.1:8000 (waits up to 120 s for it)

.ci/run runs it against the service container; it needs only httpx and PyYAML (the project's
own dependencies). Exits non-zero, saying what was wrong, when any answer is not as expected.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any

import httpx
import yaml

EXAMPLES = Path(__file__).resolve().parent.parent / "examples" / "paper"
WAIT_SECONDS = 120.0


def example(name: str) -> Any:
    return yaml.safe_load((EXAMPLES / name).read_text(encoding="utf-8"))


def wait_for(client: httpx.Client) -> dict[str, Any]:
    """Return /health once the service answers it."""
    deadline = time.monotonic() + WAIT_SECONDS
    while True:
        try:
            answer = client.get("/health")
            if answer.status_code in (200, 503):
                health: dict[str, Any] = answer.json()
                return health
        except httpx.TransportError:
            pass
        if time.monotonic() > deadline:
            raise SystemExit(f"smoke: the service did not answer /health within {WAIT_SECONDS:g} s")
        time.sleep(0.5)


def main(base: str) -> None:
    with httpx.Client(base_url=base, timeout=120) as client:
        health = wait_for(client)
        assert health["status"] == "ok", f"smoke: /health says {health['status']}: {health}"
        print(f"health: ok (causalplan {health['version']}, schema {health['database']['revision']})")
        plan = client.post("/v1/plans", json={"model": example("desk_lamp.yaml")})
        assert plan.status_code == 200 and plan.json()["status"] == "solved", f"smoke: plan: {plan.text}"
        print(f"plan: {len(plan.json()['plan'])} steps")
        body = {"model": example("desk_lamp.yaml"), "mapping": example("flashlight_mapping.yaml")}
        transfer = client.post("/v1/transfers", json=body)
        assert transfer.status_code == 200, f"smoke: transfer: {transfer.text}"
        verdict = transfer.json()["verdict"]
        assert verdict == "transfers", f"smoke: the desk lamp's model should transfer to the flashlight: {verdict}"
        print(f"transfer: desk lamp -> flashlight {verdict}")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python docker/smoke.py BASE_URL")
    main(sys.argv[1])
