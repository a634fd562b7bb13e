"""The research page's defects, each fixed: a confirmation on saving, the crowd's model counted and named
as drawn, and the experiment's internal name never shown to participants."""

from __future__ import annotations

import re

from fastapi.testclient import TestClient

from tests.service.fixtures import AUTH, RESEARCH_TOKEN
from tests.service.pages.flows import LAMP_RULES, experiment, links, post, through_step2

FLASHLIGHT_FUNCTIONS = {
    "part:batteries": "provide electricity",
    "part:head": "turn electricity into light\nclose the circuit",
}


def test_saving_the_recruiting_settings_says_they_are_saved(client: TestClient) -> None:
    created = experiment(client)
    post(client, "/research/login", {"token": RESEARCH_TOKEN, "next": "/research"})
    try:
        before = client.get(f"/research/experiments/{created['id']}")
        assert "recruitment-saved" not in before.text
        saved = post(client, f"/research/experiments/{created['id']}/recruitment", {"consent_text": "", "quota:0": "5"})
        page = client.get(saved.headers["location"])
        assert 'id="recruitment-saved"' in page.text and "The recruiting settings are saved" in page.text
    finally:
        client.cookies.clear()


def test_the_consent_page_never_shows_the_experiments_internal_name(client: TestClient) -> None:
    created = experiment(client, name="PILOT 3 far-vs-near (do not tell)")
    page = client.get(f"/s/{created['id']}", params={"PROLIFIC_PID": "pid-x", "STUDY_ID": "s", "SESSION_ID": "x"})
    assert page.status_code == 200, page.text
    assert "PILOT 3" not in page.text and "A study of how things work" in page.text


def test_the_crowds_model_counts_and_names_the_models_it_draws(client: TestClient) -> None:
    conditions = [
        {"name": "near", "training": ["desk_lamp"], "tests": ["flashlight"]},
        {"name": "other", "training": ["flashlight"], "tests": ["desk_lamp"]},
    ]
    created = experiment(client, conditions=conditions)
    lamp = links(client, created["id"], count=2, condition="near")
    (torch,) = links(client, created["id"], condition="other")
    for participant in lamp:
        through_step2(client, participant["code"])
    post(client, f"/p/{torch['code']}/step1/1", FLASHLIGHT_FUNCTIONS)
    post(client, f"/p/{torch['code']}/step2", {"rules": LAMP_RULES})
    page = client.get(f"/research/experiments/{created['id']}", headers=AUTH)
    assert 'id="consensus-graph"' in page.text and "3 participants' models" not in page.text
    graph = client.get(f"/research/experiments/{created['id']}/consensus.svg", headers=AUTH)
    assert graph.status_code == 200, graph.text
    assert "Consensus of 2 participants' models" in graph.text and "1 left out" in graph.text
    titles = re.findall(r">(participant \d+)</text>", graph.text)
    assert titles == ["participant 1", "participant 2"]  # the two models drawn, as many as the title says
    for participant in (*lamp, torch):  # titled by their place, never by their secret link code
        assert participant["code"] not in graph.text
