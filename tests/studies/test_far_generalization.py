"""The paper's far-generalization design: the template, its refusals, and a synthetic run through analyze."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from causalplan.cli import app
from causalplan.consensus.paper_study import synthetic_export
from causalplan.consensus.population import paper_population
from causalplan.objects.catalog import Catalog, load_catalog
from causalplan.studies.analysis import analyse
from causalplan.studies.far_generalization import (
    BOTH_CATEGORIES,
    ONE_CATEGORY,
    DesignError,
    PaperCondition,
    check_conditions,
    describe,
    far_generalization_conditions,
    relation_shares,
    template_conditions,
)
from causalplan.studies.trials import Study, trial_rows
from tests.service.fixtures import AUTH, error_of, running_client, settings_for, sqlite_url

CATALOG = load_catalog()
PREDICTED = {ONE_CATEGORY: {"abstract": 0.2, "slip": 0.1}, BOTH_CATEGORIES: {"abstract": 0.2, "slip": 0.1}}
OPPOSITE = {ONE_CATEGORY: {"abstract": 1.0, "slip": 0.05}, BOTH_CATEGORIES: {"abstract": 0.0, "slip": 0.7}}
PREDICTION_1 = "trained on one category: near vs far test objects"
PREDICTION_2 = "trained on both categories vs on one category, test objects of an untrained category for the latter"


def test_the_template_makes_near_and_far_conditions_with_two_novel_test_objects() -> None:
    conditions = far_generalization_conditions(CATALOG)
    assert [c.name for c in conditions] == [
        "near electric A",
        "near combustion A",
        "far A",
        "near electric B",
        "near combustion B",
        "far B",
    ]
    for condition in conditions:
        assert len(condition.training) == 2 and not set(condition.training) & set(condition.tests)
        assert sorted(CATALOG.get(test).category for test in condition.tests) == ["combustion", "electric"]
    # Each set tests every condition on the same two objects; the two sets rotate which objects are shown.
    assert conditions[0].tests == conditions[1].tests == conditions[2].tests != conditions[3].tests
    trained = {o for c in conditions if c.name.startswith("near") for o in c.training}
    assert trained == {o.id for o in CATALOG.objects.values() if o.goal == "light"}
    relations = describe(conditions, CATALOG)
    assert relations["near electric A"] == {"headlamp": "near", "kerosene_lamp": "far"}
    assert relations["far A"] == {"headlamp": "near", "kerosene_lamp": "near"}  # the relation, not the name


def test_a_test_object_the_condition_trains_on_is_refused_with_the_reason() -> None:
    bad = [PaperCondition("near electric", ("desk_lamp", "headlamp"), ("headlamp", "candle"))]
    with pytest.raises(DesignError) as caught:
        check_conditions(bad, CATALOG)
    assert caught.value.code == "invalid_design"
    assert caught.value.details["errors"] == [
        "Condition 'near electric' trains on headlamp and tests on it too: the paper's test objects are novel, "
        "since it asks whether a model explains an object the participant did not model; pick another electric "
        "object to test on."
    ]
    with pytest.raises(DesignError, match="one novel object of each category"):
        check_conditions([PaperCondition("far", ("desk_lamp", "candle"), ("headlamp", "solar_lantern"))], CATALOG)
    given = [{"name": "far", "training": ["desk_lamp", "candle"], "tests": ["headlamp", "oil_lamp"]}]
    assert template_conditions("far_generalization", CATALOG, given) == given


def test_a_catalog_without_three_objects_per_category_cannot_hold_the_design() -> None:
    paper = Catalog(
        {k: v for k, v in CATALOG.objects.items() if k in ("desk_lamp", "flashlight", "candle", "oil_lamp")}
    )
    with pytest.raises(DesignError) as caught:
        far_generalization_conditions(paper)
    assert "needs at least 3 electric objects" in caught.value.message
    assert "the catalog has 2: desk_lamp, flashlight" in caught.value.message
    with pytest.raises(DesignError, match="1 to 4 sets"):
        far_generalization_conditions(CATALOG, sets=5)


def _analysed(knobs: dict[str, dict[str, float]], seed: int) -> tuple[dict[str, object], dict[str, object]]:
    lines = paper_population(far_generalization_conditions(CATALOG), CATALOG, 20, seed, knobs)
    rows = trial_rows(synthetic_export(lines, CATALOG), CATALOG)
    shares = {f"{span}, {kind}": share for (span, kind), share in relation_shares(rows, CATALOG).items()}
    comparisons = {c.name: c for c in analyse(Study(tuple(rows)), CATALOG).comparisons}
    return shares, comparisons  # type: ignore[return-value]


def test_a_synthetic_run_shows_the_predicted_pattern_with_intervals() -> None:
    shares, comparisons = _analysed(PREDICTED, seed=1)
    far_trained, near_trained_far = shares["both categories, near"], shares["one category, far"]
    assert far_trained.low > near_trained_far.high  # type: ignore[attr-defined]
    assert "both categories, far" not in shares  # trained on both, every test is near
    for name in (PREDICTION_1, PREDICTION_2):
        assert comparisons[name].p_holm < 0.05 and comparisons[name].odds_ratio > 1  # type: ignore[attr-defined]


def test_the_opposite_pattern_is_detected_when_the_population_is_built_that_way() -> None:
    shares, comparisons = _analysed(OPPOSITE, seed=1)
    assert shares["both categories, near"].high < shares["one category, far"].low  # type: ignore[attr-defined]
    second = comparisons[PREDICTION_2]
    assert second.p_holm > 0.05 and second.odds_ratio_interval[1] < 1  # type: ignore[attr-defined]


def test_the_api_and_the_research_form_create_the_papers_design(tmp_path: Path) -> None:
    with running_client(settings_for(sqlite_url(tmp_path))) as client:
        made = client.post("/v1/experiments", headers=AUTH, json={"name": "paper", "template": "far_generalization"})
        assert made.status_code == 201, made.text
        body = made.json()
        assert [c["name"] for c in body["conditions"]] == [c.name for c in far_generalization_conditions(CATALOG)]
        assert body["counterbalance_training"] and body["counterbalance_tests"]
        refused = client.post(
            "/v1/experiments",
            headers=AUTH,
            json={
                "name": "bad",
                "template": "far_generalization",
                "conditions": [
                    {"name": "near", "training": ["desk_lamp", "headlamp"], "tests": ["headlamp", "candle"]}
                ],
            },
        )
        error = error_of(refused, 422)
        assert error["code"] == "invalid_experiment"
        assert "trains on headlamp and tests on it too" in error["details"]["errors"][0]
        form = client.post(
            "/research/experiments",
            headers={**AUTH, "Origin": "http://testserver"},
            data={"name": "paper form", "template": "far_generalization", "counterbalance_tests": "1"},
            follow_redirects=False,
        )
        assert form.status_code == 303, form.text
        page = client.get(form.headers["location"], headers=AUTH)
        assert "near combustion B" in page.text
        new_form = client.get("/research/experiments/new", headers=AUTH).text
        assert "far-generalization experiment: near and far conditions" in new_form


def test_the_commands_run_the_synthetic_study_and_analyse_it(tmp_path: Path) -> None:
    runner = CliRunner(env={"FORCE_COLOR": None, "NO_COLOR": "1", "COLUMNS": "400"})
    export = tmp_path / "study.json"
    made = runner.invoke(
        app, ["synthetic-study", "--n", "10", "--abstract", "1", "0", "--slip", "0.05", "0.7", "--out", str(export)]
    )
    assert made.exit_code == 0, made.output
    assert "120 trials of 60 participants" in made.output
    analysed = runner.invoke(app, ["analyze", str(export), "--out", str(tmp_path / "analysis")])
    assert analysed.exit_code == 0, analysed.output
    assert f"{PREDICTION_2}: " in analysed.output
    assert "the opposite of the prediction" in analysed.output


def test_without_slips_general_words_transfer_everywhere_and_a_categorys_words_only_near() -> None:
    conditions = far_generalization_conditions(CATALOG)
    general = {span: {"abstract": 1.0, "slip": 0.0} for span in (ONE_CATEGORY, BOTH_CATEGORIES)}
    trials = synthetic_export(paper_population(conditions, CATALOG, 2, 0, general), CATALOG)["trials"]
    assert {trial["verdict"] for trial in trials} == {"transfers"}  # the roles cover every true mechanism
    specific = {span: {"abstract": 0.0, "slip": 0.0} for span in (ONE_CATEGORY, BOTH_CATEGORIES)}
    rows = trial_rows(synthetic_export(paper_population(conditions, CATALOG, 2, 0, specific), CATALOG), CATALOG)
    assert {(row.generalization, row.verdict) for row in rows} == {("near", "transfers"), ("far", "fails")}
    assert {code for row in rows if row.verdict == "fails" for code in row.reason_codes} == {"missing_function"}
