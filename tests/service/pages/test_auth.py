"""Research sign-in cookies: signed, lapsing, and revoked on the server when signing out."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from sqlalchemy.orm import Session

from causalplan.service.pages.auth import COOKIE_NAME, cookie_session, session_cookie
from causalplan.service.storage.records import RevokedResearchSessionRecord
from causalplan.service.storage.revocations import forget_lapsed_revocations
from tests.service.fixtures import RESEARCH_TOKEN, migrated_engine, running_client, settings_for


def signed_in_cookie(client: TestClient) -> str:
    response = client.post(
        "/research/login", data={"token": RESEARCH_TOKEN, "next": "/research"}, follow_redirects=False
    )
    assert response.status_code == 303
    cookie = response.cookies.get(COOKIE_NAME)
    assert cookie is not None
    return cookie


def opens_research(client: TestClient, cookie: str) -> bool:
    client.cookies.clear()
    client.cookies.set(COOKIE_NAME, cookie, path="/research")
    return client.get("/research", follow_redirects=False).status_code == 200


def test_a_cookie_names_its_session_and_is_signed() -> None:
    cookie = session_cookie("secret", now=1000.0)
    found = cookie_session(cookie, "secret", now=2000.0)
    assert found is not None and found[1] == 1000 + 12 * 3600 and len(found[0]) == 32
    assert cookie_session(cookie, "another token", now=2000.0) is None
    expires, _, signature = cookie.split(".")
    assert cookie_session(f"{expires}.{'0' * 32}.{signature}", "secret", now=2000.0) is None  # another session
    assert session_cookie("secret", now=1000.0) != cookie  # each sign-in is its own session


@pytest.mark.slow
def test_signing_out_revokes_the_old_cookie_in_every_server_process(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path}/auth.sqlite3"
    with (
        running_client(settings_for(url, planning_workers=1)) as first,
        running_client(settings_for(url, planning_workers=1)) as second,
    ):
        cookie = signed_in_cookie(first)
        other = signed_in_cookie(first)
        assert opens_research(first, cookie) and opens_research(second, cookie)
        first.cookies.set(COOKIE_NAME, cookie, path="/research")
        assert first.post("/research/logout", follow_redirects=False).status_code == 303
        assert not opens_research(first, cookie)
        assert not opens_research(second, cookie)  # the other process reads the revocation from the database
        assert opens_research(second, other)  # other sessions stay signed in


def test_lapsed_revocations_are_forgotten(tmp_path: Path) -> None:
    # A database of its own, with no service running: the service's upkeep forgets lapsed
    # revocations too, and would race this call for the same row.
    engine = migrated_engine(tmp_path)
    try:
        now = datetime.now(UTC)
        with Session(engine) as session:
            session.add_all(
                [
                    RevokedResearchSessionRecord(id="a" * 32, expires_at=now - timedelta(minutes=1)),
                    RevokedResearchSessionRecord(id="b" * 32, expires_at=now + timedelta(hours=1)),
                ]
            )
            session.commit()
            assert forget_lapsed_revocations(session, now) == 1
            assert [r.id for r in session.query(RevokedResearchSessionRecord)] == ["b" * 32]
    finally:
        engine.dispose()
