"""Arrivals on the public link (SQLite and PostgreSQL): balanced assignment, quotas that hold in a race."""

from __future__ import annotations

import threading
import uuid
from collections import Counter
from collections.abc import Iterator

import pytest
from sqlalchemy import Engine, func, select, update
from sqlalchemy.orm import Session

from causalplan.service.errors import ClientHoldsPlacesError
from causalplan.service.storage import arrivals
from causalplan.service.storage import experiments as store
from causalplan.service.storage.migrate import upgrade
from causalplan.service.storage.records import ExperimentRecord, ParticipantRecord, utc_now
from causalplan.service.storage.session import create_database_engine
from causalplan.studies.assignment import Place, choose
from causalplan.studies.design import Condition, Design
from causalplan.studies.recruitment import PlatformVisit
from causalplan.studies.steps import Stage

TWO_CONDITIONS = Design(
    (
        Condition("near", ("desk_lamp", "flashlight"), ("candle",)),
        Condition("far", ("desk_lamp", "candle"), ("flashlight",)),
    )
)
ONE_CONDITION = Design((Condition("near", ("desk_lamp",), ("flashlight",)),))


@pytest.fixture
def engine(database_url: str) -> Iterator[Engine]:
    made = create_database_engine(database_url)
    upgrade(made)
    yield made
    made.dispose()


def new_experiment(engine: Engine, design: Design) -> uuid.UUID:
    with Session(engine, expire_on_commit=False) as session:
        return store.create_experiment(session, "public link", "", design).id


def direct_visit() -> PlatformVisit:
    return PlatformVisit("direct")


def admit_one(engine: Engine, experiment_id: uuid.UUID, visit: PlatformVisit) -> ParticipantRecord | None:
    with Session(engine, expire_on_commit=False) as session:
        experiment = store.get_experiment(session, experiment_id)
        return arrivals.admit(session, experiment, arrivals.arrive(session, experiment, visit))


def test_the_open_place_with_fewest_taken_is_chosen_ties_to_the_first_condition() -> None:
    assert choose([Place("near", 2, None), Place("far", 1, None)]) == Place("far", 1, None)
    assert choose([Place("near", 1, None), Place("far", 1, None)]) == Place("near", 1, None)
    assert choose([Place("near", 0, 0), Place("far", 5, None)]) == Place("far", 5, None)  # near is full
    assert choose([Place("near", 3, 3)]) is None


def test_arrivals_are_balanced_over_conditions_and_object_orders_as_they_come(engine: Engine) -> None:
    experiment_id = new_experiment(engine, TWO_CONDITIONS)
    admitted = [admit_one(engine, experiment_id, direct_visit()) for _ in range(8)]
    assert all(participant is not None for participant in admitted)
    placed = [(p.condition, p.ordinal) for p in admitted if p is not None]
    assert placed == [
        ("near", 0),
        ("far", 0),
        ("near", 1),
        ("far", 1),
        ("near", 2),
        ("far", 2),
        ("near", 3),
        ("far", 3),
    ]
    near_orders = Counter(tuple(p.training_order) for p in admitted if p is not None and p.condition == "near")
    assert near_orders == {("desk_lamp", "flashlight"): 2, ("flashlight", "desk_lamp"): 2}


def test_links_made_before_the_public_link_count_as_taken_places(engine: Engine) -> None:
    experiment_id = new_experiment(engine, TWO_CONDITIONS)
    with Session(engine, expire_on_commit=False) as session:
        store.add_participants(session, store.get_experiment(session, experiment_id), 2, "near")
    participant = admit_one(engine, experiment_id, direct_visit())
    assert participant is not None and (participant.condition, participant.ordinal) == ("far", 0)


def test_of_two_arrivals_that_saw_the_last_place_only_one_takes_it(engine: Engine) -> None:
    experiment_id = new_experiment(engine, ONE_CONDITION)
    with Session(engine) as first, Session(engine) as second:
        experiment = store.get_experiment(first, experiment_id)
        arrivals.set_quotas(first, experiment, {"near": 1})
        seen_by_first = choose(arrivals.places(first, experiment))
        seen_by_second = choose(arrivals.places(second, store.get_experiment(second, experiment_id)))
        assert seen_by_first == seen_by_second == Place("near", 0, 1, admitted=0)
        assert seen_by_first is not None and seen_by_second is not None
        assert arrivals.take_place(first, experiment_id, seen_by_first)
        first.commit()
        assert not arrivals.take_place(second, experiment_id, seen_by_second)
        second.rollback()
        # The number was taken (no participant stored here, so the place itself is not held).
        assert arrivals.places(second, store.get_experiment(second, experiment_id))[0].admitted == 1


def test_simultaneous_arrivals_never_exceed_the_quota(engine: Engine) -> None:
    experiment_id = new_experiment(engine, TWO_CONDITIONS)
    with Session(engine) as session:
        arrivals.set_quotas(session, store.get_experiment(session, experiment_id), {"near": 2, "far": 1})
    start = threading.Barrier(8)
    admitted: list[ParticipantRecord | None] = []

    def arrive() -> None:
        start.wait()
        admitted.append(admit_one(engine, experiment_id, direct_visit()))

    threads = [threading.Thread(target=arrive) for _ in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(60)
    assert len(admitted) == 8
    placed = sorted((p.condition, p.ordinal) for p in admitted if p is not None)
    assert placed == [("far", 0), ("near", 0), ("near", 1)]  # each place once, none over the quota
    with Session(engine) as session:
        stored = session.scalar(
            select(func.count()).select_from(ParticipantRecord).where(ParticipantRecord.experiment_id == experiment_id)
        )
        assert stored == 3
        assert [(p.taken, p.quota) for p in arrivals.places(session, store.get_experiment(session, experiment_id))] == [
            (2, 2),
            (1, 1),
        ]


def test_the_same_platform_session_arrives_once_and_is_admitted_once(engine: Engine) -> None:
    experiment_id = new_experiment(engine, ONE_CONDITION)
    visit = PlatformVisit("prolific", "5f1e2d3c4b5a697887766554", "study-1", "sess_9")
    first = admit_one(engine, experiment_id, visit)
    again = admit_one(engine, experiment_id, visit)
    assert first is not None and again is not None and first.id == again.id
    with Session(engine) as session:
        experiment = session.get(ExperimentRecord, experiment_id)
        assert experiment is not None
        assert [place.taken for place in arrivals.places(session, experiment)] == [1]


def test_a_copied_platform_id_with_another_session_is_another_arrival(engine: Engine) -> None:
    experiment_id = new_experiment(engine, ONE_CONDITION)
    victim = PlatformVisit("prolific", "5f1e2d3c4b5a697887766554", "study-1", "sess_victim")
    squatter = admit_one(engine, experiment_id, PlatformVisit("prolific", victim.participant, "study-1", "guess"))
    own = admit_one(engine, experiment_id, victim)
    assert squatter is not None and own is not None and squatter.id != own.id


def admit_from(
    engine: Engine, experiment_id: uuid.UUID, client: str, places_per_client: int | None = 2
) -> ParticipantRecord | None:
    """Admit a new direct arrival from ``client`` under the places-per-client limit."""
    with Session(engine, expire_on_commit=False) as session:
        experiment = store.get_experiment(session, experiment_id)
        arrival = arrivals.arrive(session, experiment, direct_visit(), client)
        return arrivals.admit(session, experiment, arrival, arrivals.DEFAULT_RULES, places_per_client)


def test_one_client_address_holds_at_most_its_places_even_when_it_consents_at_once(engine: Engine) -> None:
    experiment_id = new_experiment(engine, TWO_CONDITIONS)
    start = threading.Barrier(6)
    admitted: list[ParticipantRecord] = []
    refused: list[ClientHoldsPlacesError] = []

    def consent() -> None:
        start.wait()
        try:
            participant = admit_from(engine, experiment_id, "203.0.113.9")
        except ClientHoldsPlacesError as exc:
            refused.append(exc)
            return
        assert participant is not None
        admitted.append(participant)

    threads = [threading.Thread(target=consent) for _ in range(6)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(60)
    assert (len(admitted), len(refused)) == (2, 4)
    assert refused[0].headers["Retry-After"] == str(15 * 60)
    assert admit_from(engine, experiment_id, "198.51.100.20") is not None  # someone else still gets in
    with Session(engine) as session:
        experiment = store.get_experiment(session, experiment_id)
        assert sum(place.taken for place in arrivals.places(session, experiment)) == 3  # refusals took nothing


def test_a_client_whose_participants_started_may_bring_more(engine: Engine) -> None:
    experiment_id = new_experiment(engine, ONE_CONDITION)
    first = admit_from(engine, experiment_id, "203.0.113.10", places_per_client=1)
    with pytest.raises(ClientHoldsPlacesError):
        admit_from(engine, experiment_id, "203.0.113.10", places_per_client=1)
    assert first is not None
    with Session(engine) as session:
        session.execute(update(ParticipantRecord).where(ParticipantRecord.id == first.id).values(updated_at=utc_now()))
        session.commit()
    assert admit_from(engine, experiment_id, "203.0.113.10", places_per_client=1) is not None
    assert admit_from(engine, experiment_id, "203.0.113.10", places_per_client=None) is not None  # no limit


def test_excluded_completions_neither_fill_the_quota_nor_hold_a_place(engine: Engine) -> None:
    experiment_id = new_experiment(engine, ONE_CONDITION)
    with Session(engine) as session:
        arrivals.set_quotas(session, store.get_experiment(session, experiment_id), {"near": 1})
    bot = admit_one(engine, experiment_id, direct_visit())
    assert bot is not None
    with Session(engine) as session:  # it raced through and was flagged at the end, as the pages flag it
        record = session.get(ParticipantRecord, bot.id)
        assert record is not None
        record.stage, record.finished_at, record.updated_at = Stage.DONE.value, utc_now(), utc_now()
        session.add_all([record, arrivals.exclusion(record, "too_fast", "finished in 1 s")])
        session.commit()
        (place,) = arrivals.places(session, store.get_experiment(session, experiment_id))
        assert (place.taken, place.finished) == (0, 0)
    assert admit_one(engine, experiment_id, direct_visit()) is not None  # the study is not full


def test_a_condition_whose_twin_met_its_quota_stays_within_one_of_it() -> None:
    near = Place("near", 104, 100, finished=100, extra=10)  # met: closed, four still at work
    far = Place("far", 104, 100, finished=97, extra=10)
    assert choose([near, far]) == far  # one more: 105 against 104
    assert choose([near, Place("far", 105, 100, finished=97, extra=10)]) is None  # not two ahead
    assert choose([near, Place("far", 105, 200, finished=97, extra=10)]) is not None  # another quota: its own
