"""The statistics the analysis prints: an estimate that cannot be made is said in words, never as nan."""

from __future__ import annotations

from causalplan.studies.statistics import clustered_logistic


def test_a_model_too_small_for_its_estimates_reports_a_problem_not_nan() -> None:
    # Two participants, each with one predictor value: the robust errors cannot be estimated.
    fitted = clustered_logistic([1, 0, 1, 0], {"other_category_test": [0, 0, 1, 1]}, ["a", "a", "b", "b"])
    assert fitted.effects == ()
    assert fitted.problem == "its estimates are not finite: too few participants for it"
