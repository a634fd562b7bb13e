"""The anonymous demo: a few starts a minute per client, and its participants purged after the retention age."""

from __future__ import annotations

from dataclasses import replace
from datetime import timedelta
from pathlib import Path

import pytest
from sqlalchemy import func, select
from sqlalchemy.orm import Session

from causalplan.service.errors import TooManyDemoStartsError
from causalplan.service.pages.upkeep import purge_interval
from causalplan.service.storage.demo import WINDOW_SECONDS, DemoStarts, purge_demo_participants
from causalplan.service.storage.records import ModelRecord, ParticipantRecord, TrialRecord, utc_now
from tests.service.fixtures import migrated_engine, running_client, services_of, settings_for, wait_until
from tests.service.pages.flows import FLASHLIGHT_CHOICES, complete, experiment, links


class Clock:
    def __init__(self, now: float) -> None:
        self.now = now

    def __call__(self) -> float:
        return self.now


def test_each_client_has_its_own_starts_per_window(tmp_path: Path) -> None:
    clock = Clock(10 * WINDOW_SECONDS + 15)
    starts = DemoStarts(migrated_engine(tmp_path), 2, clock)
    starts.admit("a")
    starts.admit("a")
    starts.admit("b")
    with pytest.raises(TooManyDemoStartsError) as refused:
        starts.admit("a")
    assert refused.value.retry_after == 45  # until the window ends
    clock.now += 45
    starts.admit("a")  # a new window


def test_no_limit_when_the_setting_is_zero(tmp_path: Path) -> None:
    engine, clock = migrated_engine(tmp_path), Clock(10 * WINDOW_SECONDS + 15)
    unlimited = DemoStarts(engine, 0, clock)
    for _ in range(100):
        unlimited.admit("a")
    limited = DemoStarts(engine, 2, clock)  # the same database: the unlimited starts were never counted
    limited.admit("a")
    limited.admit("a")
    with pytest.raises(TooManyDemoStartsError):
        limited.admit("a")


@pytest.mark.slow
def test_try_refuses_a_client_past_its_starts_this_minute(tmp_path: Path) -> None:
    settings = settings_for(f"sqlite:///{tmp_path}/try.sqlite3", planning_workers=1, demo_starts_per_minute=3)
    with running_client(settings) as client:
        assert [client.post("/try", follow_redirects=False).status_code for _ in range(3)] == [303, 303, 303]
        refused = client.post("/try", follow_redirects=False)
        assert refused.status_code == 429
        assert 1 <= int(refused.headers["retry-after"]) <= WINDOW_SECONDS
        assert "started the demo 3 times" in refused.text
        with Session(services_of(client).engine) as session:
            assert session.scalar(select(func.count()).select_from(ParticipantRecord)) == 3


def counts(session: Session) -> tuple[int, int, int]:
    return (
        int(session.scalar(select(func.count()).select_from(ParticipantRecord)) or 0),
        int(session.scalar(select(func.count()).select_from(TrialRecord)) or 0),
        int(session.scalar(select(func.count()).select_from(ModelRecord)) or 0),
    )


@pytest.mark.slow
def test_the_purge_takes_old_demo_participants_with_their_work_and_nothing_else(tmp_path: Path) -> None:
    with running_client(settings_for(f"sqlite:///{tmp_path}/purge.sqlite3", planning_workers=1)) as client:
        (study,) = links(client, experiment(client)["id"])
        complete(client, study["code"])
        demo_code = str(client.post("/try", follow_redirects=False).headers["location"]).removeprefix("/p/")
        engine = services_of(client).engine
        with Session(engine) as session:
            demo = session.scalars(select(ParticipantRecord).where(ParticipantRecord.code == demo_code)).one()
            # The demo participant did the study's steps too (a model and a trial of their own).
            demo.stage, demo.training_order, demo.test_order = "step1", ["desk_lamp"], ["flashlight"]
            session.commit()
        complete(client, demo_code, FLASHLIGHT_CHOICES)
        with Session(engine) as session:
            assert counts(session) == (2, 2, 2)
            assert purge_demo_participants(session, utc_now() - timedelta(hours=1)) == 0  # still fresh
            assert purge_demo_participants(session, utc_now() + timedelta(seconds=1)) == 1
            assert counts(session) == (1, 1, 1)
            (kept,) = session.scalars(select(ParticipantRecord))
            assert kept.code == study["code"]
        assert client.get(f"/p/{demo_code}", follow_redirects=False).status_code == 404


@pytest.mark.slow
def test_the_purge_runs_when_the_service_starts(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path}/start.sqlite3"
    with running_client(settings_for(url, planning_workers=1)) as client:
        client.post("/try")
    with running_client(settings_for(url, planning_workers=1, demo_retention_hours=1e-9)) as client:
        wait_until(lambda: client.app.state.upkeep.purges >= 1)  # type: ignore[attr-defined]
        with Session(services_of(client).engine) as session:
            assert counts(session)[0] == 0


@pytest.mark.slow
def test_the_purge_runs_four_times_per_retention_period_and_at_least_hourly(tmp_path: Path) -> None:
    with running_client(settings_for(f"sqlite:///{tmp_path}/every.sqlite3", planning_workers=1)) as client:
        services = services_of(client)
        assert purge_interval(services) == 3600.0  # a day's retention: hourly
        short = services.settings.model_copy(update={"demo_retention_hours": 1.0})
        assert purge_interval(replace(services, settings=short)) == 900.0
