"""The near/far rule, the one place every part of causalplan takes it from."""

from __future__ import annotations

from causalplan.transfer.generalization import near_or_far


def test_a_test_object_of_a_trained_category_is_near() -> None:
    assert near_or_far(["electric"], "electric") == "near"
    assert near_or_far(["combustion", "electric"], "electric") == "near"


def test_a_test_object_of_no_trained_category_is_far() -> None:
    assert near_or_far(["electric"], "combustion") == "far"
    assert near_or_far([], "electric") == "far"
