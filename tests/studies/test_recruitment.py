"""Reading what crowd platforms put in a study link, the recruiting settings, and the way back to the platform."""

from __future__ import annotations

import pytest

from causalplan.studies.errors import InvalidRecruitmentError
from causalplan.studies.recruitment import (
    DEFAULT_CONSENT,
    Recruitment,
    finish,
    mturk_host,
    platform_id_view,
    read_quotas,
    read_recruitment,
    read_visit,
)

PROLIFIC = {"PROLIFIC_PID": "5f1e2d3c4b5a697887766554", "STUDY_ID": "study-1", "SESSION_ID": "sess_9"}
MTURK = {
    "workerId": "A1B2C3D4E5",
    "hitId": "3XYZHIT",
    "assignmentId": "3ASSIGN",
    "turkSubmitTo": "https://workersandbox.mturk.com",
}


def test_a_prolific_link_gives_the_three_ids() -> None:
    visit = read_visit(PROLIFIC)
    assert (visit.platform, visit.participant, visit.study, visit.session) == (
        "prolific",
        "5f1e2d3c4b5a697887766554",
        "study-1",
        "sess_9",
    )
    assert not visit.is_preview and visit.submit_to is None


def test_an_mturk_link_gives_worker_hit_assignment_and_the_submit_host() -> None:
    visit = read_visit(MTURK)
    assert (visit.platform, visit.participant, visit.study, visit.session, visit.submit_to) == (
        "mturk",
        "A1B2C3D4E5",
        "3XYZHIT",
        "3ASSIGN",
        "https://workersandbox.mturk.com",
    )


def test_mturk_preview_is_recognised_and_carries_no_ids() -> None:
    visit = read_visit({"assignmentId": "ASSIGNMENT_ID_NOT_AVAILABLE", "hitId": "3XYZHIT"})
    assert visit.is_preview and visit.participant is None


def test_a_link_without_platform_ids_is_a_direct_arrival() -> None:
    assert read_visit({}).platform == "direct"


@pytest.mark.parametrize(
    ("parameters", "named"),
    [
        ({**PROLIFIC, "PROLIFIC_PID": "<script>alert(1)</script>"}, "PROLIFIC_PID"),
        ({**PROLIFIC, "STUDY_ID": "x" * 65}, "STUDY_ID"),
        ({"PROLIFIC_PID": "abc"}, "STUDY_ID"),  # one Prolific id means all three are needed
        ({**MTURK, "workerId": "A1 B2"}, "workerId"),
    ],
)
def test_a_bad_id_is_refused_naming_the_parameter_never_its_value(parameters: dict[str, str], named: str) -> None:
    with pytest.raises(InvalidRecruitmentError) as raised:
        read_visit(parameters)
    assert raised.value.details == {"parameter": named}
    assert "<script>" not in raised.value.message and "x" * 65 not in raised.value.message


@pytest.mark.parametrize(
    "host",
    [
        "https://evil.example",
        "http://www.mturk.com",
        "https://www.mturk.com.evil.example",
        "https://user@www.mturk.com",
        "https://www.mturk.com:444",
        "https://www.mturk.com/elsewhere",
        "https://www.mturk.com/?next=https://evil.example",
        "javascript:alert(1)",
    ],
)
def test_turk_submit_to_must_be_one_of_mturks_two_hosts(host: str) -> None:
    with pytest.raises(InvalidRecruitmentError):
        read_visit({**MTURK, "turkSubmitTo": host})


def test_mturks_two_hosts_are_accepted_with_or_without_the_slash() -> None:
    assert mturk_host("https://www.mturk.com/") == "https://www.mturk.com"
    assert mturk_host("https://workersandbox.mturk.com") == "https://workersandbox.mturk.com"


def test_the_way_back_is_prolifics_completion_url_or_a_post_to_mturk() -> None:
    prolific = finish("prolific", "sess_9", None, "C0DE42", "completed")
    assert prolific is not None and prolific.url == "https://app.prolific.com/submissions/complete?cc=C0DE42"
    assert prolific.fields == ()
    assert finish("prolific", "sess_9", None, "", "screened_out") is None  # no code: no redirect
    mturk = finish("mturk", "3ASSIGN", "https://www.mturk.com", "", "completed")
    assert mturk is not None and mturk.url == "https://www.mturk.com/mturk/externalSubmit"
    assert (
        mturk.fields == (("assignmentId", "3ASSIGN"), ("outcome", "completed"))
        and mturk.origin == "https://www.mturk.com"
    )
    assert finish("direct", None, None, "C0DE42", "completed") is None


def test_recruiting_settings_are_checked_and_round_trip() -> None:
    settings = read_recruitment(
        {"completion_code": "ABC123", "comprehension_tries": 2, "too_fast_seconds": 120, "demographics": ["age", "age"]}
    )
    assert settings.consent_text == DEFAULT_CONSENT  # empty: the default text
    assert settings.demographics == ("age",)
    assert Recruitment.from_dict(settings.as_dict()) == settings
    assert Recruitment.from_dict(None) == Recruitment()


def test_every_problem_of_recruiting_settings_is_listed() -> None:
    with pytest.raises(InvalidRecruitmentError) as raised:
        read_recruitment(
            {"completion_code": "not a code!", "comprehension_tries": 0, "too_fast_seconds": -5, "demographics": ["iq"]}
        )
    errors = raised.value.details["errors"]
    assert isinstance(errors, list) and len(errors) == 4
    assert "completion code" in errors[0] and "iq" in errors[3]


def test_quotas_name_known_conditions_and_default_to_no_limit() -> None:
    assert read_quotas({"near": 10}, ["near", "far"]) == {"near": 10, "far": None}
    with pytest.raises(InvalidRecruitmentError):
        read_quotas({"nera": 10}, ["near", "far"])
    with pytest.raises(InvalidRecruitmentError):
        read_quotas({"near": -1}, ["near"])


def test_platform_ids_are_exported_plain_hashed_or_omitted() -> None:
    assert platform_id_view("A1B2", "exp-1", "plain") == "A1B2"
    hashed = platform_id_view("A1B2", "exp-1", "hashed")
    assert hashed is not None and len(hashed) == 64 and "A1B2" not in hashed
    assert hashed == platform_id_view("A1B2", "exp-1", "hashed") != platform_id_view("A1B2", "exp-2", "hashed")
    assert platform_id_view("A1B2", "exp-1", "omit") is None
