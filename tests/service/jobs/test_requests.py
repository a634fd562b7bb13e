"""The stored requests of jobs: the keys rows have always had, read back as the kind's model."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from causalplan.service.jobs.requests import BatchRequest, FitsFilmRequest, PlanFilmRequest, read_video_request


def test_a_plan_film_is_stored_with_the_apis_validate_key_and_read_back() -> None:
    request = PlanFilmRequest(model_id="m", mapping=None, planner="fd", time_limit=5.0, validate=True, video="mp4")
    stored = request.stored()
    assert stored["validate"] is True and "validate_plan" not in stored
    assert read_video_request(stored) == request and request.units() == 1


def test_a_participants_film_is_told_from_the_apis_by_its_fields() -> None:
    stored = FitsFilmRequest(object="flashlight", fits=["a", "b"], video="mp4", film="0" * 32).stored()
    assert isinstance(read_video_request(stored), FitsFilmRequest)


def test_a_counted_request_starts_with_its_count_and_refuses_unknown_keys() -> None:
    batch = BatchRequest(trials="{}", count=3, planner="fd", time_limit=1.0, simulate=False)
    assert batch.units() == 3
    with pytest.raises(ValidationError):
        BatchRequest.model_validate({**batch.stored(), "extra": 1})
