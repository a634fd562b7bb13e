"""The public study link through the app: platforms, consent, screening, the way back, the export and its analysis."""

from __future__ import annotations

import json
import re
import uuid
from collections.abc import Iterator
from datetime import timedelta
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner
from fastapi.testclient import TestClient
from sqlalchemy import func, select, update
from sqlalchemy.orm import Session

from causalplan.cli import app
from causalplan.service.pages.upkeep import purge
from causalplan.service.storage.records import ArrivalRecord, ParticipantRecord, TrialRecord, utc_now
from tests.service.fixtures import AUTH, RESEARCH_TOKEN, running_client, services_of, settings_for, sqlite_url
from tests.service.pages.flows import TUTORIAL_ANSWERS, TUTORIAL_RULES, complete, experiment, links, post, sent_back

WRONG_ANSWERS = {**TUTORIAL_ANSWERS, "answer:diffuse": "yes"}
ARRIVALS_PER_MINUTE = 3


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    """The module's app with no limit on arrivals (the tests arrive many times from one address)."""
    with running_client(settings_for(sqlite_url(tmp_path_factory.mktemp("db")), arrivals_per_minute=0)) as running:
        yield running


@pytest.fixture(scope="module")
def throttled(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    """An app that lets one client arrive ``ARRIVALS_PER_MINUTE`` times a minute."""
    url = sqlite_url(tmp_path_factory.mktemp("db"))
    with running_client(settings_for(url, arrivals_per_minute=ARRIVALS_PER_MINUTE, planning_workers=1)) as running:
        yield running


def recruiting(client: TestClient, experiment_id: str, **settings: Any) -> dict[str, Any]:
    response = client.put(f"/v1/experiments/{experiment_id}/recruitment", json=settings, headers=AUTH)
    assert response.status_code == 200, response.text
    body: dict[str, Any] = response.json()
    return body


def prolific(pid: str) -> dict[str, str]:
    return {"PROLIFIC_PID": pid, "STUDY_ID": "study1", "SESSION_ID": f"session-{pid}"}


def consent_code(page: str) -> str:
    found = re.search(r'name="arrival" value="([A-Za-z0-9]+)"', page)
    assert found, page
    return found.group(1)


def join(client: TestClient, experiment_id: str, params: dict[str, str]) -> str:
    """Arrive with ``params``, agree to take part; return the participant's code."""
    arrival = client.get(f"/s/{experiment_id}", params=params)
    assert arrival.status_code == 200, arrival.text
    agreed = post(client, f"/s/{experiment_id}/consent", {"arrival": consent_code(arrival.text), "decision": "agree"})
    location: str = agreed.headers["location"]
    assert location.startswith("/p/")
    return location.removeprefix("/p/")


def counts(client: TestClient, experiment_id: str) -> tuple[int, int]:
    """Return the experiment's stored arrivals and participants."""
    experiment = uuid.UUID(experiment_id)
    with Session(services_of(client).engine) as session:
        arrivals = session.scalar(
            select(func.count()).select_from(ArrivalRecord).where(ArrivalRecord.experiment_id == experiment)
        )
        participants = session.scalar(
            select(func.count()).select_from(ParticipantRecord).where(ParticipantRecord.experiment_id == experiment)
        )
    return int(arrivals or 0), int(participants or 0)


def age_participants(client: TestClient, experiment_id: str, minutes: float) -> None:
    """Move the experiment's participants ``minutes`` into the past, as if that long had gone by."""
    earlier = utc_now() - timedelta(minutes=minutes)
    with Session(services_of(client).engine) as session:
        session.execute(
            update(ParticipantRecord)
            .where(ParticipantRecord.experiment_id == uuid.UUID(experiment_id))
            .values(created_at=earlier, started_at=earlier)
        )
        session.commit()


def exported(client: TestClient, experiment_id: str, platform_ids: str = "plain") -> dict[str, Any]:
    response = client.get(
        f"/v1/experiments/{experiment_id}/export", params={"platform_ids": platform_ids}, headers=AUTH
    )
    assert response.status_code == 200
    data: dict[str, Any] = response.json()
    return data


def test_failing_the_comprehension_check_twice_screens_out_with_the_other_code(client: TestClient) -> None:
    created = experiment(client, tutorial=True)
    recruiting(client, created["id"], completion_code="DONE1", screened_out_code="OUT1", comprehension_tries=2)
    code = join(client, created["id"], prolific("pid-screened"))
    first = sent_back(client, f"/p/{code}/tutorial", {**WRONG_ANSWERS, "rules": TUTORIAL_RULES})
    assert "You have 1 try left" in first.text
    post(client, f"/p/{code}/tutorial", {**WRONG_ANSWERS, "rules": TUTORIAL_RULES})
    screened = client.get(f"/p/{code}")
    assert screened.url.path == f"/p/{code}/screened"
    assert 'href="https://app.prolific.com/submissions/complete?cc=OUT1"' in screened.text
    again = client.get(f"/s/{created['id']}", params=prolific("pid-screened"))  # no second chance
    assert again.url.path == f"/p/{code}/screened"
    (participant,) = exported(client, created["id"])["participants"]
    assert participant["excluded"] and participant["exclusion_reason"] == "comprehension"
    assert participant["comprehension_tries"] == 2 and participant["comprehension_passed_on_try"] is None
    assert participant["exclusions"][0]["detail"] == "not every comprehension question right within 2 tries"


def test_declining_stores_only_the_arrival_and_gives_the_no_consent_code(client: TestClient) -> None:
    created = experiment(client)
    recruiting(client, created["id"], no_consent_code="NOPE1", consent_text="Our own consent text.")
    arrival = client.get(f"/s/{created['id']}", params=prolific("pid-declines"))
    assert "Our own consent text." in arrival.text
    assert counts(client, created["id"]) == (1, 0)
    declined = client.post(
        f"/s/{created['id']}/consent", data={"arrival": consent_code(arrival.text), "decision": "decline"}
    )
    assert declined.status_code == 200 and "You chose not to take part" in declined.text
    assert 'href="https://app.prolific.com/submissions/complete?cc=NOPE1"' in declined.text
    assert counts(client, created["id"]) == (1, 0)
    back = client.get(f"/s/{created['id']}", params=prolific("pid-declines"))
    assert "You chose not to take part" in back.text and counts(client, created["id"]) == (1, 0)


def test_a_full_study_says_so_and_stores_nothing(client: TestClient) -> None:
    created = experiment(client)
    recruiting(client, created["id"], quotas={"near": 1})
    join(client, created["id"], prolific("pid-first"))
    full = client.get(f"/s/{created['id']}", params=prolific("pid-second"))
    assert full.status_code == 200 and "This study is full" in full.text
    assert counts(client, created["id"]) == (1, 1)


def test_an_mturk_preview_stores_nothing_and_a_worker_submits_to_mturk(client: TestClient) -> None:
    created = experiment(client)
    preview = client.get(f"/s/{created['id']}", params={"assignmentId": "ASSIGNMENT_ID_NOT_AVAILABLE", "hitId": "H1"})
    assert "This is a preview" in preview.text and 'name="arrival"' not in preview.text
    assert counts(client, created["id"]) == (0, 0)
    worker = {"workerId": "W1", "hitId": "H1", "assignmentId": "A1", "turkSubmitTo": "https://workersandbox.mturk.com"}
    code = join(client, created["id"], worker)
    step1 = client.get(f"/p/{code}/step1/1")
    assert "frame-ancestors https://worker.mturk.com" in step1.headers["content-security-policy"]
    complete(client, code)
    done = client.get(f"/p/{code}/done")
    assert 'action="https://workersandbox.mturk.com/mturk/externalSubmit"' in done.text
    assert 'name="assignmentId" value="A1"' in done.text
    assert "form-action 'self' https://workersandbox.mturk.com;" in done.headers["content-security-policy"]


def test_a_hostile_parameter_is_refused_and_never_shown(client: TestClient) -> None:
    created = experiment(client)
    refused = client.get(f"/s/{created['id']}", params={**prolific("x"), "PROLIFIC_PID": '"><script>alert(1)</script>'})
    assert refused.status_code == 422 and "PROLIFIC_PID" in refused.text
    assert "<script>alert" not in refused.text and "alert(1)" not in refused.text
    elsewhere = {"workerId": "W1", "hitId": "H1", "assignmentId": "A1", "turkSubmitTo": "https://evil.example"}
    assert client.get(f"/s/{created['id']}", params=elsewhere).status_code == 422
    assert counts(client, created["id"]) == (0, 0)


def test_a_too_fast_finish_is_flagged_and_the_export_hides_or_hashes_platform_ids(client: TestClient) -> None:
    created = experiment(client)
    recruiting(client, created["id"], completion_code="DONE1", too_fast_seconds=3600, demographics=["age"])
    code = join(client, created["id"], prolific("pid-fast"))
    complete(client, code)
    post(client, f"/p/{code}/about", {"age": "29"})
    done = client.get(f"/p/{code}/done")
    assert 'href="https://app.prolific.com/submissions/complete?cc=DONE1"' in done.text
    assert (
        '<meta http-equiv="refresh" content="5;url=https://app.prolific.com/submissions/complete?cc=DONE1">'
        in done.text
    )
    (participant,) = exported(client, created["id"])["participants"]
    assert participant["excluded"] and participant["exclusion_reason"] == "too_fast"
    assert participant["platform"] == "prolific" and participant["platform_participant_id"] == "pid-fast"
    assert participant["demographics"] == {"age": "29"}
    assert [step["step"] for step in participant["step_seconds"]] == ["step1/1", "step2", "step3/1", "about"]
    assert participant["seconds_taken"] is not None and participant["seconds_taken"] < 3600
    (hashed,) = exported(client, created["id"], "hashed")["participants"]
    assert len(hashed["platform_participant_id"]) == 64 and "pid-fast" not in json.dumps(hashed)
    (omitted,) = exported(client, created["id"], "omit")["participants"]
    assert omitted["platform_participant_id"] is None and omitted["platform_session_id"] is None


@pytest.mark.slow
def test_the_analyze_command_reads_the_export_of_a_real_run_and_skips_the_excluded(
    client: TestClient, tmp_path: Path
) -> None:
    created = experiment(client, tutorial=True)
    recruiting(client, created["id"], comprehension_tries=1)
    for pid in ("pid-a", "pid-b"):
        code = join(client, created["id"], prolific(pid))
        post(client, f"/p/{code}/tutorial", {**TUTORIAL_ANSWERS, "rules": TUTORIAL_RULES})
        complete(client, code)
    screened = join(client, created["id"], prolific("pid-c"))
    post(client, f"/p/{screened}/tutorial", {**WRONG_ANSWERS, "rules": TUTORIAL_RULES})
    path = tmp_path / "export.json"
    path.write_text(json.dumps(exported(client, created["id"])), encoding="utf-8")
    result = CliRunner().invoke(app, ["analyze", str(path), "--out", str(tmp_path / "out"), "--json"])
    assert result.exit_code == 0, result.output
    analysis = json.loads(result.output)
    assert analysis["trials"] == analysis["analysed_trials"] == 2  # the screened-out one never reached step 3
    assert analysis["rates"][0]["transfers"] == 2 and analysis["rates"][0]["test_object"] == "flashlight"
    written = sorted(item.name for item in (tmp_path / "out").iterdir())
    assert written == ["analysis.json", "codebook.csv", "rates.png", "rates.svg", "trials.csv"]
    page = client.get(f"/research/experiments/{created['id']}", headers=AUTH)
    # The screened-out participant is named, with no trial lost: they never reached step 3.
    left_out = "2 of 2 trials analysed; left out: 0 trials of 1 participant excluded by screening (comprehension 1)."
    assert analysis["left_out"] == left_out and left_out in page.text
    assert client.get(f"/research/experiments/{created['id']}/rates.svg", headers=AUTH).text.count("<svg") == 1
    assert 'id="consensus-graph"' in page.text and "One causal model from the participants' models" in page.text
    graph = client.get(f"/research/experiments/{created['id']}/consensus.svg", headers=AUTH)
    assert graph.status_code == 200, graph.text
    assert graph.headers["content-type"].startswith("image/svg+xml")
    assert graph.text.count("<svg") == 1


def _table_rows(page: str, table_id: str) -> list[list[str]]:
    """Return the text of each body row's cells of the page's table ``table_id``."""
    table = page.split(f'id="{table_id}"', 1)[1].split("</table>", 1)[0]
    body = table.split("<tbody>", 1)[1]
    return [
        [re.sub(r"<[^>]+>", "", cell).strip() for cell in re.findall(r"<td>(.*?)</td>", row, re.S)]
        for row in body.split("</tr>")
        if "<td>" in row
    ]


def _chart_texts(svg: str) -> list[str]:
    # matplotlib writes each text of the chart (ticks, labels, counts, title) as a comment beside its glyphs.
    return re.findall(r"<!-- (.*?) -->", svg, re.S)


@pytest.mark.slow
def test_the_page_the_api_and_analyze_show_one_rates_table_that_leaves_out_the_same_trials(
    client: TestClient, tmp_path: Path
) -> None:
    created = experiment(client, tutorial=True)
    recruiting(client, created["id"], comprehension_tries=1, too_fast_seconds=3600)
    kept = {}
    for pid in ("pid-works", "pid-fails", "pid-undecided"):
        kept[pid] = join(client, created["id"], prolific(pid))
        post(client, f"/p/{kept[pid]}/tutorial", {**TUTORIAL_ANSWERS, "rules": TUTORIAL_RULES})
    age_participants(client, created["id"], minutes=120)  # these three took two hours: not too fast
    complete(client, kept["pid-works"])
    complete(client, kept["pid-fails"], {"chosen:batteries": "provide electricity"})
    complete(client, kept["pid-undecided"])
    too_fast = join(client, created["id"], prolific("pid-fast"))
    post(client, f"/p/{too_fast}/tutorial", {**TUTORIAL_ANSWERS, "rules": TUTORIAL_RULES})
    complete(client, too_fast)  # transferred, but excluded: finished within the hour
    screened = join(client, created["id"], prolific("pid-screened"))
    post(client, f"/p/{screened}/tutorial", {**WRONG_ANSWERS, "rules": TUTORIAL_RULES})  # no trial at all
    export = exported(client, created["id"])
    (timed_out,) = [trial for trial in export["trials"] if trial["participant_code"] == kept["pid-undecided"]]
    with Session(services_of(client).engine) as session:  # as the service stores a planner that ran out of time
        session.execute(
            update(TrialRecord).where(TrialRecord.id == uuid.UUID(timed_out["trial_id"])).values(verdict="undecided")
        )
        session.commit()
    path = tmp_path / "export.json"
    path.write_text(json.dumps(exported(client, created["id"])), encoding="utf-8")
    result = CliRunner().invoke(app, ["analyze", str(path), "--out", str(tmp_path / "out"), "--json"])
    assert result.exit_code == 0, result.output
    analysis = json.loads(result.output)
    left_out = (
        "2 of 4 trials analysed; left out: 1 trial of 2 participants excluded by screening (comprehension 1, "
        "too_fast 1); 1 undecided trial (the planner could not decide in time)."
    )
    assert analysis["left_out"] == left_out
    (rate,) = analysis["rates"]
    assert {name: rate[name] for name in ("trials", "transfers", "fails", "undecided", "excluded", "rate")} == {
        "trials": 2,
        "transfers": 1,
        "fails": 1,
        "undecided": 1,
        "excluded": 1,
        "rate": 0.5,
    }

    results = client.get(f"/v1/experiments/{created['id']}/results", headers=AUTH).json()
    assert results["rates"] == analysis["rates"]
    page = client.get(f"/research/experiments/{created['id']}", headers=AUTH).text
    assert left_out in page
    low, high = rate["interval"]
    assert _table_rows(page, "rates") == [
        ["near", "one category", "flashlight", "near", "1/2", "1", "50%", f"{low:.0%}\u2013{high:.0%}", "1", "1"]
    ]
    rates_and_analysis = page.split('id="results"', 1)[1].split('id="consensus"', 1)[0]  # the crowd's graph follows
    charts = re.findall(r'<img class="plot" id="([^"]+)" src="([^"]+)"', rates_and_analysis)
    assert charts == [("rates-chart", f"/research/experiments/{created['id']}/rates.svg")]
    drawn = client.get(charts[0][1], headers=AUTH)
    assert drawn.headers["content-type"] == "image/svg+xml"
    written = (tmp_path / "out" / "rates.svg").read_text(encoding="utf-8")
    assert _chart_texts(drawn.text) == _chart_texts(written) and "1/2" in _chart_texts(written)
    for gone in ("chart.svg", "analysis.svg"):  # the two charts drawn before, each counting differently
        assert client.get(f"/research/experiments/{created['id']}/{gone}", headers=AUTH).status_code == 404


def test_the_crowds_model_waits_for_two_models(client: TestClient) -> None:
    created = experiment(client)
    page = client.get(f"/research/experiments/{created['id']}", headers=AUTH)
    assert "appears once two participants have written a model" in page.text
    refused = client.get(f"/research/experiments/{created['id']}/consensus.svg", headers=AUTH)
    assert refused.status_code == 422 and "There is no consensus to draw" in refused.text


def test_a_bot_that_agrees_and_leaves_lets_its_place_go(client: TestClient) -> None:
    created = experiment(client)
    recruiting(client, created["id"], quotas={"near": 2})
    for bot in range(2):
        join(client, created["id"], prolific(f"bot-{bot}"))  # agrees, then never starts the work
    assert "This study is full" in client.get(f"/s/{created['id']}", params=prolific("pid-real")).text
    age_participants(client, created["id"], minutes=16)
    code = join(client, created["id"], prolific("pid-real"))
    assert client.get(f"/p/{code}").status_code == 200
    places = recruiting(client, created["id"], quotas={"near": 2})["places"]
    assert [(place["taken"], place["admitted"]) for place in places] == [(1, 3)]


def test_completions_count_against_the_quota_with_a_bounded_over_admission(client: TestClient) -> None:
    created = experiment(client)
    recruiting(client, created["id"], quotas={"near": 10}, places_per_client=None)  # all from one test client
    codes = [join(client, created["id"], prolific(f"pid-over-{n}")) for n in range(11)]  # 10 and 10 % more
    assert "This study is full" in client.get(f"/s/{created['id']}", params=prolific("pid-over-11")).text
    complete(client, codes[0])
    age_participants(client, created["id"], minutes=16)  # the ten others never started
    for n in range(11, 21):  # one finished and ten at work
        join(client, created["id"], prolific(f"pid-over-{n}"))
    assert "This study is full" in client.get(f"/s/{created['id']}", params=prolific("pid-over-21")).text
    places = recruiting(client, created["id"], quotas={"near": 10})["places"]
    assert [(place["taken"], place["finished"], place["extra"]) for place in places] == [(11, 1, 1)]


def test_one_client_arriving_too_often_is_told_to_wait(throttled: TestClient) -> None:
    created = experiment(throttled)
    for n in range(ARRIVALS_PER_MINUTE):
        assert throttled.get(f"/s/{created['id']}", params=prolific(f"pid-fast-{n}")).status_code == 200
    refused = throttled.get(f"/s/{created['id']}", params=prolific("pid-fast-again"))
    assert refused.status_code == 429 and int(refused.headers["retry-after"]) >= 1
    assert "too many" in refused.text.lower()
    assert counts(throttled, created["id"]) == (ARRIVALS_PER_MINUTE, 0)


def test_a_study_that_requires_a_platform_id_refuses_anonymous_arrivals(client: TestClient) -> None:
    created = experiment(client)
    settings = recruiting(client, created["id"], require_platform_id=True)
    assert settings["require_platform_id"] is True
    anonymous = client.get(f"/s/{created['id']}")
    assert anonymous.status_code == 403 and "Prolific" in anonymous.text
    assert counts(client, created["id"]) == (0, 0)
    join(client, created["id"], prolific("pid-required"))
    assert counts(client, created["id"]) == (1, 1)


def test_the_research_form_sets_and_shows_the_platform_id_requirement(client: TestClient) -> None:
    created = experiment(client)
    post(client, "/research/login", {"token": RESEARCH_TOKEN, "next": "/research"})
    form = {"consent_text": "", "quota:0": "", "require_platform_id": "yes"}
    saved = post(client, f"/research/experiments/{created['id']}/recruitment", form)
    assert saved.headers["location"].endswith("#recruiting")
    assert client.get(f"/v1/experiments/{created['id']}/recruitment", headers=AUTH).json()["require_platform_id"]
    page = client.get(f"/research/experiments/{created['id']}")
    assert 'name="require_platform_id" value="yes" checked' in page.text
    client.cookies.clear()


def test_undecided_arrivals_are_purged_after_the_stated_time(client: TestClient) -> None:
    created = experiment(client)
    client.get(f"/s/{created['id']}", params=prolific("pid-undecided"))
    client.get(f"/s/{created['id']}", params=prolific("pid-declined-old"))
    declined = client.get(f"/s/{created['id']}", params=prolific("pid-declined-old"))
    post(client, f"/s/{created['id']}/consent", {"arrival": consent_code(declined.text), "decision": "decline"}, 200)
    join(client, created["id"], prolific("pid-admitted-old"))
    services = services_of(client)
    hours = services.settings.undecided_arrival_hours
    with Session(services.engine) as session:
        session.execute(
            update(ArrivalRecord)
            .where(ArrivalRecord.experiment_id == uuid.UUID(created["id"]))
            .values(created_at=utc_now() - timedelta(hours=hours, minutes=1))
        )
        session.commit()
    client.get(f"/s/{created['id']}", params=prolific("pid-undecided-new"))
    purge(services)
    stored = recruiting(client, created["id"])["arrivals"]
    assert stored == {"arrived": 3, "consented": 1, "declined": 1, "undecided": 1}  # the old undecided one went


def test_a_bot_with_a_victims_platform_id_neither_declines_for_them_nor_takes_their_record(
    client: TestClient,
) -> None:
    created = experiment(client)
    victim = prolific("pid-victim")
    first_bot = client.get(f"/s/{created['id']}", params={**victim, "SESSION_ID": "bot-guess-1"})
    post(client, f"/s/{created['id']}/consent", {"arrival": consent_code(first_bot.text), "decision": "decline"}, 200)
    arriving = client.get(f"/s/{created['id']}", params=victim)
    assert "You chose not to take part" not in arriving.text and 'name="arrival"' in arriving.text
    bot_code = join(client, created["id"], {**victim, "SESSION_ID": "bot-guess-2"})
    victim_code = join(client, created["id"], victim)
    assert victim_code != bot_code
    back = client.get(f"/s/{created['id']}", params=victim, follow_redirects=False)
    assert back.status_code == 303 and back.headers["location"] == f"/p/{victim_code}"
    copied = client.get(f"/s/{created['id']}", params={**victim, "SESSION_ID": "bot-guess-3"}, follow_redirects=False)
    assert copied.status_code == 200 and f"/p/{victim_code}" not in copied.text and f"/p/{bot_code}" not in copied.text


def test_a_bot_looping_from_one_address_gets_two_places_and_a_real_visitor_still_gets_in(client: TestClient) -> None:
    created = experiment(client)
    assert recruiting(client, created["id"], quotas={"near": 5})["places_per_client"] == 2  # the default
    for bot in range(2):
        join(client, created["id"], prolific(f"loop-{bot}"))
    for bot in range(2, 6):  # it goes on consenting, from the same address
        arrival = client.get(f"/s/{created['id']}", params=prolific(f"loop-{bot}"))
        refused = post(
            client, f"/s/{created['id']}/consent", {"arrival": consent_code(arrival.text), "decision": "agree"}, 429
        )
        assert "Please try again later" in refused.text and int(refused.headers["retry-after"]) > 0
    assert counts(client, created["id"]) == (6, 2)
    visitor = TestClient(client.app, client=("198.51.100.7", 50000))  # the running app, another address
    code = join(visitor, created["id"], prolific("real-visitor"))
    assert visitor.get(f"/p/{code}").status_code == 200


def test_a_transfer_resting_on_an_electric_function_given_to_the_match_is_shown_and_set_aside(
    client: TestClient, tmp_path: Path
) -> None:
    conditions = [{"name": "far", "training": ["desk_lamp"], "tests": ["candle"]}]
    created = experiment(client, conditions=conditions)
    (participant,) = links(client, created["id"])
    electric = {
        "chosen:wax": "provide electricity",
        "chosen:wick": "turn electricity into light",
        "chosen:match": "close the circuit",
    }
    complete(client, participant["code"], electric)
    data = exported(client, created["id"])
    assert [trial["verdict"] for trial in data["trials"]] == ["transfers"]  # the planner alone lets it through
    post(client, "/research/login", {"token": RESEARCH_TOKEN, "next": "/research"})
    page = client.get(f"/research/experiments/{created['id']}").text
    client.cookies.clear()
    assert "1 of 1 analysed transfers rest on an implausible mapping" in page
    assert 'id="implausible-transfers"' in page and "match: close the circuit" in page
    path = tmp_path / "export.json"
    path.write_text(json.dumps(data), encoding="utf-8")
    result = CliRunner().invoke(app, ["analyze", str(path), "--out", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    assert "with every transfer, 0/0 without the implausible ones" in " ".join(result.output.split())
