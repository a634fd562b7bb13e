"""The screening rules on a participant held in memory: the comprehension check's tries and the too-fast flag."""

from __future__ import annotations

import uuid
from datetime import timedelta

from causalplan.objects.catalog import Catalog
from causalplan.service.storage.records import ParticipantRecord, utc_now
from causalplan.studies.design import Condition, Design
from causalplan.studies.journey import Journey
from causalplan.studies.recruitment import Recruitment
from causalplan.studies.screening import comprehension_try, too_fast
from causalplan.studies.steps import Stage

DESIGN = Design((Condition("near", ("desk_lamp",), ("flashlight",)),))
RIGHT = {"sticker": "no", "diffuse": "no", "and": "and"}
WRONG = {**RIGHT, "diffuse": "yes"}


def journey_with(catalog: Catalog, recruitment: Recruitment, stage: Stage = Stage.TUTORIAL) -> Journey:
    participant = ParticipantRecord(
        id=uuid.uuid4(),
        code="c" * 22,
        experiment_id=uuid.uuid4(),
        condition="near",
        ordinal=0,
        training_order=["desk_lamp"],
        test_order=["flashlight"],
        stage=stage.value,
        position=0,
        work={},
        started_at=utc_now(),
    )
    return Journey(participant, DESIGN, (catalog.get("desk_lamp"),), (catalog.get("flashlight"),), recruitment)


def test_two_wrong_tries_screen_out_under_a_two_try_rule(catalog: Catalog) -> None:
    journey = journey_with(catalog, Recruitment(comprehension_tries=2))
    assert comprehension_try(journey, WRONG, all_correct=False) is None
    excluded = comprehension_try(journey, WRONG, all_correct=False)
    assert excluded is not None and excluded.reason == "comprehension"
    assert excluded.detail == "not every comprehension question right within 2 tries"
    assert journey.stage is Stage.SCREENED and journey.participant.finished_at is not None
    assert [item["all_correct"] for item in journey.tutorial_work()["tries"]] == [False, False]


def test_right_on_the_second_try_passes_and_later_tries_no_longer_count(catalog: Catalog) -> None:
    journey = journey_with(catalog, Recruitment(comprehension_tries=2))
    assert comprehension_try(journey, WRONG, all_correct=False) is None
    assert comprehension_try(journey, RIGHT, all_correct=True) is None
    assert comprehension_try(journey, WRONG, all_correct=False) is None  # passed already
    assert journey.tutorial_work()["passed_on_try"] == 2 and journey.stage is Stage.TUTORIAL


def test_without_a_rule_nobody_is_screened_out(catalog: Catalog) -> None:
    journey = journey_with(catalog, Recruitment())
    for _ in range(5):
        assert comprehension_try(journey, WRONG, all_correct=False) is None
    assert journey.stage is Stage.TUTORIAL


def test_a_finish_under_the_threshold_is_flagged_and_one_over_it_is_not(catalog: Catalog) -> None:
    quick = journey_with(catalog, Recruitment(too_fast_seconds=300), Stage.DONE)
    quick.participant.finished_at = quick.participant.started_at + timedelta(seconds=120)  # type: ignore[operator]
    flagged = too_fast(quick)
    assert flagged is not None and flagged.reason == "too_fast"
    assert flagged.detail == "finished in 120 s; the threshold is 300 s"
    slow = journey_with(catalog, Recruitment(too_fast_seconds=300), Stage.DONE)
    slow.participant.finished_at = slow.participant.started_at + timedelta(seconds=301)  # type: ignore[operator]
    assert too_fast(slow) is None
    assert too_fast(journey_with(catalog, Recruitment(), Stage.DONE)) is None  # no threshold set


def test_time_on_each_page_is_kept_as_the_participant_moves_on(catalog: Catalog) -> None:
    journey = journey_with(catalog, Recruitment(), Stage.STEP1)
    journey.finish_functions(0)
    assert journey.stage is Stage.STEP2
    (entry,) = journey.step_seconds()
    assert entry["step"] == "step1/1" and entry["seconds"] >= 0
