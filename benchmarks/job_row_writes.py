"""Bytes SQLite writes for one lease renewal of a running job, by the size of the job's stored request.

A job's row holds its request (up to 16 MB). SQLite rewrites a whole record when its stored size
changes, and overwrites only the changed pages when it does not; a renewal changes the lease's
time (always the same width) and the progress counts (whose width grows at 2, 128, 32768, ...).
So this counts, for requests of 1 KB (the reference), 1 MB and 8 MB, the bytes the process
writes (``wchar`` of ``/proc/self/io``: the WAL and the checkpoints) for

- a renewal whose counts keep their width (most renewals: the progress 10 -> 11 -> ...);
- two renewals across a width step (progress 127, then 128: the second changes width), which
  happens a few times in a job's life; both renewals' bytes are counted together.

    python benchmarks/job_row_writes.py [--renewals 20]
"""

from __future__ import annotations

import argparse
import tempfile
from collections.abc import Callable
from pathlib import Path

from sqlalchemy import Engine, text

from causalplan.service.storage import jobs as store
from causalplan.service.storage.migrate import upgrade
from causalplan.service.storage.session import create_database_engine

SIZES_MB = (1 / 1024, 1.0, 8.0)


def written() -> int:
    """Return the bytes this process has written so far (every write call, to any file)."""
    counters = dict(line.split(": ") for line in Path("/proc/self/io").read_text().splitlines())
    return int(counters["wchar"])


def running_job(folder: Path, megabytes: float) -> tuple[Engine, Callable[[tuple[int, int]], None]]:
    """Return a fresh SQLite database holding one claimed job with a request of ``megabytes``, and its renewal."""
    engine = create_database_engine(f"sqlite:///{folder / 'jobs.sqlite3'}")
    upgrade(engine)
    request = {"kind": "batch", "format": "jsonl", "trials": "x" * int(megabytes * 1024 * 1024)}
    store.create_job(engine, "batch", request, 1000, 100, owner="benchmark")
    job = store.claim_job(engine, "runner", 60.0, ["batch"])
    assert job is not None

    def renew(progress: tuple[int, int]) -> None:
        store.renew_lease(engine, job.id, "runner", 60.0, progress)

    renew((10, 1000))  # the counts at their width for the first measure
    with engine.connect() as connection:
        connection.execute(text("PRAGMA wal_checkpoint(TRUNCATE)"))
    return engine, renew


def per_renewal(renew: Callable[[tuple[int, int]], None], progress: list[tuple[int, int]]) -> float:
    """Return the mean bytes written by the renewals to each of ``progress``."""
    before = written()
    for each in progress:
        renew(each)
    return (written() - before) / len(progress)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--renewals", type=int, default=20, help="renewals measured per case (default 20)")
    args = parser.parse_args()
    rows = []
    for megabytes in SIZES_MB:
        with tempfile.TemporaryDirectory() as folder:
            engine, renew = running_job(Path(folder), megabytes)
            steady = per_renewal(renew, [(11 + i, 1000) for i in range(args.renewals)])
            across = per_renewal(renew, [(127, 1000), (128, 1000)]) * 2  # both; only the second changes width
            engine.dispose()
        rows.append((megabytes, steady, across))
    reference = rows[0][1]
    print(f"{'request':>10} | {'a renewal':>12} | {'vs 1 KB':>8} | {'127, 128 (both)':>20}")
    for megabytes, steady, across in rows:
        size = f"{megabytes * 1024:.0f} KB" if megabytes < 1 else f"{megabytes:.0f} MB"
        print(f"{size:>10} | {steady / 1024:>9.1f} KB | {steady / reference:>7.2f}x | {across / 1024:>17.0f} KB")


if __name__ == "__main__":
    main()
