"""The path of one ``POST /v1/plans`` through the service's files, up to the planner pool (not a speed).

A running app (TestClient, one planner worker) answers a warm-up request, then one traced by
``sys.setprofile`` on every thread: which of the package's functions run, in which files, until
the request's thread calls ``PlannerPool.run`` (the call that hands the solve to a worker).
Printed: the calls and files of the whole request before that point (the middleware and
FastAPI's dependencies included), the service files from the route's handler to the work
layer's entry (``service/work/``) and to the pool, and how often the path came back into a file
it had left. Run it once per side to compare two versions, from a folder holding neither:

    cd /tmp && PYTHONPATH=/path/to/side python /path/to/side/benchmarks/request_path.py
"""

from __future__ import annotations

import sys
import tempfile
import threading
from pathlib import Path
from types import FrameType

import yaml

import causalplan

ROOT = Path(causalplan.__file__).parent
Call = tuple[int, str, str]


def re_entries(files: list[str]) -> int:
    """Return how often a sequence of files comes back into a file it had left."""
    seen: set[str] = set()
    count, previous = 0, None
    for name in files:
        if name != previous and name in seen:
            count += 1
        seen.add(name)
        previous = name
    return count


def traced_request(example: Path) -> list[Call]:
    """Return the package's calls (thread, file, function) of one plan request, in order."""
    from fastapi.testclient import TestClient

    from causalplan.service.main import create_app
    from causalplan.settings import Settings

    calls: list[Call] = []
    recording = False

    def profile(frame: FrameType, event: str, _: object) -> None:
        path = frame.f_code.co_filename
        if recording and event == "call" and path.startswith(str(ROOT)):
            calls.append((threading.get_ident(), str(Path(path).relative_to(ROOT)), frame.f_code.co_name))

    folder = tempfile.mkdtemp(prefix="causalplan-request-path-")
    settings = Settings(
        database_url=f"sqlite:///{folder}/db.sqlite3", planning_workers=1, job_runners=0, draw_plans_ahead=False
    )
    model = yaml.safe_load(example.read_text(encoding="utf-8"))
    threading.setprofile(profile)
    sys.setprofile(profile)
    try:
        with TestClient(create_app(settings)) as client:
            client.post("/v1/plans", json={"model": model, "time_limit": 5})  # warm: imports, caches
            recording = True
            answer = client.post("/v1/plans", json={"model": model, "time_limit": 6})  # not the cached one
            recording = False
            answer.raise_for_status()
    finally:
        sys.setprofile(None)
        threading.setprofile(None)
    return calls


def main() -> None:
    calls = traced_request(ROOT.parent / "examples" / "paper" / "desk_lamp.yaml")
    route = next(thread for thread, name, _ in calls if name.startswith("service/api/routes/plans"))
    before: list[Call] = []
    for call in calls:
        if call[0] == route and call[1] == "service/pool/pool.py" and call[2] == "run":
            break
        before.append(call)
    files = list(dict.fromkeys(name for _, name, _ in before))
    service = [name for name in files if name.startswith("service/")]
    print(f"whole request before the pool: {len(before)} calls of {len({(n, f) for _, n, f in before})} functions")
    print(f"  in {len(files)} files of the package, {len(service)} of the service: {', '.join(service)}")
    handler = [name for thread, name, function in before if thread == route and name.startswith("service/")]
    handler = handler[next(i for i, name in enumerate(handler) if name.startswith("service/api/routes/plans")) :]
    to_work = handler[: next((i for i, name in enumerate(handler) if name.startswith("service/work/")), len(handler))]
    print(f"route handler -> work layer: {list(dict.fromkeys(to_work))} (then the work layer)")
    print(f"route handler -> pool: {list(dict.fromkeys(handler))}, came back into a file {re_entries(handler)} times")


if __name__ == "__main__":
    main()
