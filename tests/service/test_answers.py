"""The service's caches: a repeat gets exactly the plain answer, other inputs never share one, and they stay bounded."""

from __future__ import annotations

import copy
import random
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from causalplan.causal.documents import SourceMap
from causalplan.inputs import mapping_from_data, model_from_data
from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import build_task
from causalplan.planners.pipeline import plan_task
from causalplan.service.work.calls import MAX_ANSWER_BYTES, ResultCache
from tests.service.fixtures import (
    AUTH,
    DESK_LAMP,
    FLASHLIGHT_MAPPING,
    example_document,
    running_client,
    services_of,
    settings_for,
    sqlite_url,
)

TIME_LIMIT = 20.0  # settings_for's default_time_limit
PER_REQUEST = {"cached", "model_id", "planner_requested", "warnings", "timing"}
"""Response fields that are not the planner's answer (``timing``: a repeat shows the first solve's)."""

EXAMPLE_REQUESTS = [
    ("paper/desk_lamp.yaml", None),
    ("paper/desk_lamp.yaml", "paper/flashlight_mapping.yaml"),
    ("paper/desk_lamp.yaml", "far/candle_mapping_for_paper_desk_lamp.yaml"),
    ("paper/failed_desk_lamp.yaml", None),
    ("paper/failed_desk_lamp.yaml", "paper/failed_flashlight_mapping.yaml"),
    ("far/abstract_desk_lamp.yaml", "far/candle_mapping.yaml"),
    ("near/candle.yaml", None),
    ("near/candle.yaml", "near/kerosene_lamp_mapping.yaml"),
    ("near/candle.yaml", "far/flashlight_mapping_for_candle.yaml"),
]


def plain_answer(catalog: Catalog, body: dict[str, Any]) -> dict[str, Any]:
    """Return what the plain path (``causalplan plan --json``, in this process) answers to a plan request."""
    loaded = model_from_data(body["model"], SourceMap(), catalog)
    assert loaded.model is not None and loaded.is_valid, loaded.report.as_dict()
    mapping = None
    if body.get("mapping") is not None:
        read = mapping_from_data(body["mapping"], SourceMap(), catalog)
        assert read.is_valid, read.report.as_dict()
        mapping = read.mapping
    target = catalog.get((mapping or loaded.model.labelling).object_id)
    task = build_task(loaded.model, target, mapping)
    planner, time_limit, val = (
        body.get("planner", "auto"),
        body.get("time_limit", TIME_LIMIT),
        body.get("validate", True),
    )
    return plan_task(task, planner, time_limit, include_pddl=True, val=val).as_dict()


def answer_of(response: dict[str, Any]) -> dict[str, Any]:
    """Return the planner's answer in a response (without the fields that differ per request)."""
    return {name: value for name, value in response.items() if name not in PER_REQUEST and name != "pddl"}


def plain_fields(plain: dict[str, Any]) -> dict[str, Any]:
    return {name: value for name, value in plain.items() if name not in {"timing", "pddl"}}


def post_plan(client: TestClient, body: dict[str, Any], headers: dict[str, str] | None = None) -> dict[str, Any]:
    response = client.post("/v1/plans", json=body, headers=headers)
    assert response.status_code == 200, response.text
    data: dict[str, Any] = response.json()
    return data


def stored_models(client: TestClient) -> dict[str, dict[str, Any]]:
    """Return every stored model by id, as the export shows it."""
    export = client.get("/v1/export", headers=AUTH).json()
    return {model["id"]: model for model in export["models"]}


def stored_fields(stored: dict[str, Any]) -> dict[str, Any]:
    return {name: value for name, value in stored.items() if name not in {"id", "created_at"}}


@pytest.fixture(scope="module")
def plain_client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    """An app with no caches at all (``cache_size`` 0): every request is read, planned and stored anew."""
    url = sqlite_url(tmp_path_factory.mktemp("db"))
    with running_client(settings_for(url, cache_size=0, planning_workers=1)) as client:
        yield client


@pytest.mark.parametrize(("model", "mapping"), EXAMPLE_REQUESTS)
def test_every_example_repeated_gets_exactly_the_plain_answer(
    client: TestClient, plain_client: TestClient, catalog: Catalog, model: str, mapping: str | None
) -> None:
    body: dict[str, Any] = {"model": example_document(model), "include_pddl": True}
    if mapping is not None:
        body["mapping"] = example_document(mapping)
    plain = plain_answer(catalog, body)
    uncached = post_plan(plain_client, body)
    first, repeat = post_plan(client, body), post_plan(client, body)
    assert repeat["cached"] is True and uncached["cached"] is False
    # The repeat is the first answer, timing included (it is that solve's), under a new model id.
    assert {**repeat, "cached": False, "model_id": first["model_id"]} == first
    for response in (uncached, first, repeat):
        assert answer_of(response) == plain_fields(plain)
        assert response["pddl"] == plain["pddl"]
    # What is stored for the repeat is what the plain path stores.
    stored = stored_models(client)
    assert stored_fields(stored[repeat["model_id"]]) == stored_fields(stored[first["model_id"]])
    assert stored_fields(stored[repeat["model_id"]]) == stored_fields(stored_models(plain_client)[uncached["model_id"]])


def random_requests(catalog: Catalog, count: int, seed: int) -> list[dict[str, Any]]:
    """Return ``count`` valid plan requests with random functions, rules and mappings (seeded)."""
    rng = random.Random(seed)
    labels = ["provide energy", "hold fuel", "make a flame", "let light out", "close the circuit", "guide"]
    requests: list[dict[str, Any]] = []
    while len(requests) < count:
        obj = catalog.get(rng.choice(sorted(catalog.objects)))
        functions = {part: rng.sample(labels, rng.randint(1, 2)) for part in rng.sample(obj.part_ids, 2)}
        used = sorted({label for part_labels in functions.values() for label in part_labels})
        middle = f"step {rng.randint(0, 999)}"
        causes = rng.sample(used, min(len(used), rng.randint(1, 2)))
        rules = [" AND ".join(causes) + f" CAUSES {middle}", f"{middle} AND {used[-1]} CAUSES {obj.goal}"]
        body: dict[str, Any] = {"model": {"object": obj.id, "goal": obj.goal, "functions": functions, "rules": rules}}
        body["planner"] = rng.choice(["auto", "fd", "fd-opt", "mdp"])
        other = catalog.get(rng.choice(sorted(catalog.objects)))
        if rng.random() < 0.5:
            body["mapping"] = {"object": other.id, "functions": {rng.choice(other.part_ids): used}}
        loaded = model_from_data(body["model"], SourceMap(), catalog)
        if loaded.is_valid and not loaded.report.warnings:
            requests.append(body)
    return requests


def test_random_requests_repeated_get_exactly_the_plain_answer(client: TestClient, catalog: Catalog) -> None:
    for body in random_requests(catalog, 12, seed=8):
        first, repeat = post_plan(client, body), post_plan(client, body)
        assert repeat["cached"] is True, body
        assert {**repeat, "cached": first["cached"], "model_id": first["model_id"]} == first, body
        assert answer_of(first) == plain_fields(plain_answer(catalog, body)), body


def test_a_repeat_is_stored_with_its_own_client_ids_and_key_order(client: TestClient) -> None:
    model = {**DESK_LAMP, "rules": [rule.replace("electricity flows", "current 1") for rule in DESK_LAMP["rules"]]}
    reordered = {key: model[key] for key in reversed(list(model))}
    first = post_plan(client, {"model": model}, {"X-Participant-Id": "p1", "X-Session-Id": "s1"})
    repeat = post_plan(client, {"model": model}, {"X-Participant-Id": "p2"})
    other_order = post_plan(client, {"model": reordered})
    assert (first["cached"], repeat["cached"], other_order["cached"]) == (False, True, True)
    stored = stored_models(client)
    assert (stored[first["model_id"]]["participant_id"], stored[first["model_id"]]["session_id"]) == ("p1", "s1")
    assert (stored[repeat["model_id"]]["participant_id"], stored[repeat["model_id"]]["session_id"]) == ("p2", None)
    assert list(stored[other_order["model_id"]]["document"]) == list(reordered)  # as sent, not as first seen
    assert len({first["model_id"], repeat["model_id"], other_order["model_id"]}) == 3


def test_a_repeated_invalid_model_or_mapping_gets_the_same_422_and_is_stored_each_time(client: TestClient) -> None:
    invalid_model = {**DESK_LAMP, "object": "lamp"}
    invalid_mapping = {"object": "flashlight", "functions": {"bateries": ["provide electricity"]}}
    for body in ({"model": invalid_model}, {"model": DESK_LAMP, "mapping": invalid_mapping}):
        first, repeat = (client.post("/v1/plans", json=body) for _ in range(2))
        assert first.status_code == repeat.status_code == 422
        first_error, repeat_error = first.json()["error"], repeat.json()["error"]
        assert first_error["details"].pop("model_id") != repeat_error["details"].pop("model_id")
        assert first_error == repeat_error
    stored = stored_models(client)
    assert sum(1 for model in stored.values() if model["document"] == invalid_model) == 2


def variants() -> dict[str, dict[str, Any]]:
    """Return plan requests that each differ from 'base' in one input the answer depends on."""
    base: dict[str, Any] = {"model": copy.deepcopy(DESK_LAMP), "planner": "fd", "time_limit": 20}
    renamed = {**DESK_LAMP, "rules": [rule.replace("electricity flows", "current") for rule in DESK_LAMP["rules"]]}
    flashlight_model = {
        "object": "flashlight",
        "goal": "light",
        "functions": {"batteries": ["provide electricity"], "head": ["turn electricity into light"]},
        "rules": ["provide electricity AND turn electricity into light CAUSES light"],
    }
    fewer_parts = {"object": "flashlight", "functions": {"batteries": ["provide electricity"]}}
    capital_goal = {
        **DESK_LAMP,
        "goal": "Light",
        "rules": [rule.replace("light", "Light") for rule in DESK_LAMP["rules"]],
    }
    return {
        "base": base,
        "model text": {**base, "model": renamed},
        "goal case": {**base, "model": capital_goal},
        "object": {**base, "model": flashlight_model},
        "mapping": {**base, "mapping": FLASHLIGHT_MAPPING},
        "other mapping": {**base, "mapping": fewer_parts},
        "planner": {**base, "planner": "fd-opt"},
        "auto planner": {**base, "planner": "auto"},
        "time limit": {**base, "time_limit": 5},
    }


def test_changed_inputs_never_get_another_requests_answer(tmp_path: Path, catalog: Catalog) -> None:
    url = sqlite_url(tmp_path)
    with running_client(settings_for(url, planning_workers=1)) as client:
        answers = {}
        for name, body in variants().items():
            response = post_plan(client, body)
            assert response["cached"] is False, f"{name} was answered from another request's cache entry"
            assert answer_of(response) == plain_fields(plain_answer(catalog, body)), name
            answers[name] = response
        for name, body in variants().items():  # now every one is cached, each under its own key
            again = post_plan(client, body)
            assert again["cached"] is True, name
            assert answer_of(again) == answer_of(answers[name]), name
    assert answers["mapping"]["object"] == "flashlight" and answers["base"]["object"] == "desk_lamp"
    assert answers["other mapping"]["status"] == "unsolvable" and answers["mapping"]["status"] == "solved"


def test_the_caches_stay_bounded(tmp_path: Path) -> None:
    url = sqlite_url(tmp_path)
    with running_client(settings_for(url, cache_size=2, planning_workers=1)) as client:
        services = services_of(client)
        bodies = [
            {"model": {**DESK_LAMP, "rules": [r.replace("electricity flows", f"flow {i}") for r in DESK_LAMP["rules"]]}}
            for i in range(4)
        ]
        first = [post_plan(client, body) for body in bodies]
        assert len(services.caches.answers) == 2
        again = post_plan(client, bodies[0])  # dropped from the cache: planned again
        assert again["cached"] is False and answer_of(again) == answer_of(first[0])
        assert post_plan(client, bodies[0])["cached"] is True
        assert len(services.caches.answers) == 2


def test_answers_come_out_as_copies_and_the_cache_keeps_the_recently_used() -> None:
    cache = ResultCache(2)
    answer: dict[str, Any] = {"plan": [{"action": "screw", "args": ["a", "b"]}], "status": "solved"}
    cache.put("k", answer)
    answer["plan"][0]["args"].append("changed")  # the caller's dict is not the stored one
    out = cache.get("k")
    assert out == {"plan": [{"action": "screw", "args": ["a", "b"]}], "status": "solved"}
    assert out is not None
    out["plan"].clear()
    assert cache.get("k") == {"plan": [{"action": "screw", "args": ["a", "b"]}], "status": "solved"}
    cache.put("l", {})
    assert cache.get("k") is not None  # now the most recently used
    cache.put("m", {})
    assert cache.get("l") is None and len(cache) == 2
    cache.put("huge", {"text": "x" * (MAX_ANSWER_BYTES + 1)})  # larger than an answer may be: not kept
    assert cache.get("huge") is None and cache.get("k") is not None
    off = ResultCache(0)
    off.put("x", {})
    assert off.get("x") is None and len(off) == 0
