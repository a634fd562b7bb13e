"""The jobs table's fair sharing: round-robin claims across owners, anonymous work's caps."""

from __future__ import annotations

import uuid
from collections.abc import Iterator

import pytest
from sqlalchemy import Engine, event

from causalplan.service.errors import JobNotFoundError, TooManyJobsError, TooManyJobsInFlightError
from causalplan.service.owners import address_owner, job_limits, key_owner, participant_owner
from causalplan.service.storage import jobs as store
from causalplan.service.storage.jobs import OwnerLimits
from causalplan.service.storage.migrate import upgrade
from causalplan.service.storage.session import create_database_engine
from causalplan.settings import Settings
from tests.service.fixtures import API_KEY

CAP = 10
ROOMY = OwnerLimits(100, 10**9)


@pytest.fixture
def engine(database_url: str) -> Iterator[Engine]:
    """A migrated database: SQLite, then PostgreSQL (the claim's order is SQL both must run)."""
    engine = create_database_engine(database_url)
    upgrade(engine)
    yield engine
    engine.dispose()


def _queue(engine: Engine, owner: str, kind: str = "batch", limits: OwnerLimits | None = ROOMY) -> str:
    return str(store.create_job(engine, kind, {"x": 1}, 1, CAP, owner=owner, limits=limits).id)


def test_the_runner_takes_jobs_round_robin_across_owners(engine: Engine) -> None:
    films = [_queue(engine, "participant:flood", "video") for _ in range(4)]
    keyed = _queue(engine, "key:batch")  # posted after every film
    other = _queue(engine, "address:198.51.100.1", "simulation")
    claimed = []
    for _ in range(6):
        job = store.claim_job(engine, "replica", 30, ["batch", "video", "simulation"])
        assert job is not None
        claimed.append(str(job.id))
    assert claimed[:3] == [films[0], keyed, other]  # one each, not every film first
    assert claimed[3:] == films[1:]
    assert store.claim_job(engine, "replica", 30, ["batch", "video", "simulation"]) is None


def test_the_films_of_many_participants_from_one_address_take_one_turn(engine: Engine) -> None:
    settings = Settings(max_queued_jobs=CAP, participant_jobs_in_flight=100, address_jobs_in_flight=100)
    films = []
    for number in range(4):
        participant = participant_owner(f"p{number}", "203.0.113.5")
        films.append(_queue(engine, participant.id, "video", job_limits(participant, settings)))
    keyed = _queue(engine, key_owner(API_KEY))  # posted after every film
    first = store.claim_job(engine, "replica", 30, ["batch", "video"])
    second = store.claim_job(engine, "replica", 30, ["batch", "video"])
    assert first is not None and second is not None
    assert (str(first.id), str(second.id)) == (films[0], keyed)


def test_an_owner_with_a_job_running_waits_behind_one_without(engine: Engine) -> None:
    first = _queue(engine, "address:a")
    second = _queue(engine, "address:a")
    claimed = store.claim_job(engine, "replica", 30, ["batch"])
    assert claimed is not None and str(claimed.id) == first
    newcomer = _queue(engine, "address:b")
    nxt = store.claim_job(engine, "replica", 30, ["batch"])
    assert nxt is not None and str(nxt.id) == newcomer
    last = store.claim_job(engine, "replica", 30, ["batch"])
    assert last is not None and str(last.id) == second


def test_anonymous_work_takes_at_most_its_share_and_keys_find_room(engine: Engine) -> None:
    settings = Settings(max_queued_jobs=CAP, address_jobs_in_flight=100, participant_jobs_in_flight=100)
    for number in range(CAP // 2):
        participant = participant_owner(f"p{number}", "203.0.113.5")
        _queue(engine, participant.id, "video", job_limits(participant, settings))
    flooder = participant_owner("late", "203.0.113.6")
    with pytest.raises(TooManyJobsError, match="without a key"):
        _queue(engine, flooder.id, "video", job_limits(flooder, settings))
    with pytest.raises(TooManyJobsError):
        _queue(engine, address_owner("198.51.100.9").id, limits=job_limits(address_owner("198.51.100.9"), settings))
    keyed = key_owner(API_KEY)
    for _ in range(CAP - CAP // 2):  # the other half is the keys' and the research token's
        _queue(engine, keyed, limits=OwnerLimits(100, 10**9))
    with pytest.raises(TooManyJobsError):
        _queue(engine, "research", limits=None)


def test_films_are_capped_per_participant_and_per_address(engine: Engine) -> None:
    settings = Settings(max_queued_jobs=CAP, participant_jobs_in_flight=2, address_jobs_in_flight=3)
    one = participant_owner("one", "203.0.113.5")
    for _ in range(2):
        _queue(engine, one.id, "video", job_limits(one, settings))
    with pytest.raises(TooManyJobsInFlightError, match="You have 2 jobs"):
        _queue(engine, one.id, "video", job_limits(one, settings))
    two = participant_owner("two", "203.0.113.5")  # another participant from the same address
    _queue(engine, two.id, "video", job_limits(two, settings))
    with pytest.raises(TooManyJobsInFlightError, match="Your address has 3 jobs"):
        _queue(engine, two.id, "video", job_limits(two, settings))
    own = address_owner("203.0.113.5")  # the address's own API jobs count there too
    with pytest.raises(TooManyJobsInFlightError, match="Your address"):
        _queue(engine, own.id, limits=job_limits(own, settings))
    elsewhere = participant_owner("three", "198.51.100.3")
    _queue(engine, elsewhere.id, "video", job_limits(elsewhere, settings))


def test_a_foreign_jobs_404_reads_no_more_than_a_missing_ones(engine: Engine) -> None:
    big = store.create_job(engine, "batch", {"trials": "x" * 1_000_000}, 1, CAP, owner="key:owner").id
    statements: list[str] = []

    def record(_conn: object, _cursor: object, statement: str, *_: object) -> None:
        statements.append(statement)

    event.listen(engine, "before_cursor_execute", record)
    try:
        asked: dict[str, list[str]] = {}
        for name, job_id in (("foreign", big), ("missing", uuid.uuid4())):
            statements.clear()
            for ask in (store.get_job, store.get_job_file):
                with pytest.raises(JobNotFoundError):
                    ask(engine, job_id, owner="key:stranger")
            with pytest.raises(JobNotFoundError):
                store.cancel_job(engine, job_id, 60, owner="key:stranger")
            asked[name] = list(statements)
    finally:
        event.remove(engine, "before_cursor_execute", record)
    assert asked["foreign"] == asked["missing"]  # the same statements: the same cost
    assert not any("request" in statement for statement in asked["foreign"])  # never the big columns
    assert store.get_job(engine, big, owner="key:owner").request["trials"] == "x" * 1_000_000
