"""The crowd curve: known populations with known answers."""

from __future__ import annotations

from pathlib import Path

from causalplan.consensus.curve import crowd_curve, plot_curve
from causalplan.consensus.population import ERROR_KINDS
from causalplan.objects.catalog import Catalog

NONE = dict.fromkeys(ERROR_KINDS, 0.0)


def test_a_crowd_without_errors_transfers_like_each_of_its_members(catalog: Catalog) -> None:
    points = crowd_curve("desk_lamp", catalog, sizes=(1, 3), draws=2, rates=NONE, tests=("flashlight",), simulate=False)
    assert [(p.size, p.consensus_rate, p.individual_rate) for p in points] == [(1, 1.0, 1.0), (3, 1.0, 1.0)]


def test_a_crowd_where_everyone_uses_the_objects_own_words_fails_far_like_its_members(catalog: Catalog) -> None:
    rates = NONE | {"object_specific": 1.0}
    points = crowd_curve(
        "desk_lamp", catalog, sizes=(3,), draws=2, rates=rates, tests=("flashlight", "candle"), simulate=False
    )
    assert [(p.test_object, p.generalization, p.consensus_rate, p.individual_rate) for p in points] == [
        ("flashlight", "near", 1.0, 1.0),
        ("candle", "far", 0.0, 0.0),
    ]


def test_a_minority_error_hurts_individuals_but_not_the_consensus_of_ten(catalog: Catalog, tmp_path: Path) -> None:
    rates = NONE | {"effect_as_cause": 0.3}
    points = crowd_curve(
        "desk_lamp", catalog, sizes=(1, 10), draws=3, seed=5, rates=rates, tests=("candle",), simulate=False
    )
    ten = points[-1]
    assert ten.consensus_rate == 1.0
    assert ten.individual_rate < 1.0  # the shade's "diffuse light" has no part on a candle
    assert ten.consensus_low < ten.consensus_rate <= ten.consensus_high
    plot_curve(points, tmp_path / "curve.png", "test")
    assert (tmp_path / "curve.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
