"""Balanced Latin squares and the object orders they give participants."""

from __future__ import annotations

from collections import Counter
from itertools import pairwise

import pytest

from causalplan.studies.counterbalance import latin_square, object_orders


@pytest.mark.parametrize("size", [1, 2, 3, 4, 5, 6, 7, 8])
def test_every_row_is_an_order_and_every_item_takes_every_position_equally_often(size: int) -> None:
    rows = latin_square(size)
    assert len(rows) == (size if size % 2 == 0 or size == 1 else 2 * size)
    for row in rows:
        assert sorted(row) == list(range(size))
    for position in range(size):
        counts = Counter(row[position] for row in rows)
        assert set(counts) == set(range(size)) and len(set(counts.values())) == 1


@pytest.mark.parametrize("size", [2, 3, 4, 5, 6])
def test_each_item_follows_every_other_item_equally_often(size: int) -> None:
    rows = latin_square(size)
    followers = Counter(pair for row in rows for pair in pairwise(row))
    assert len(followers) == size * (size - 1)  # every ordered pair of different items
    assert len(set(followers.values())) == 1


def test_the_squares_of_two_three_and_four_items() -> None:
    assert latin_square(2) == [(0, 1), (1, 0)]
    assert latin_square(3)[:3] == [(0, 1, 2), (1, 2, 0), (2, 0, 1)]
    assert latin_square(4) == [(0, 1, 3, 2), (1, 2, 0, 3), (2, 3, 1, 0), (3, 0, 2, 1)]


def test_a_square_needs_an_item() -> None:
    with pytest.raises(ValueError, match="at least one item"):
        latin_square(0)


def test_participants_cycle_through_the_training_orders_then_the_test_orders() -> None:
    training, tests = ["desk_lamp", "flashlight"], ["candle", "kerosene_lamp"]
    orders = [object_orders(number, training, tests, True, True) for number in range(5)]
    assert orders == [
        (["desk_lamp", "flashlight"], ["candle", "kerosene_lamp"]),
        (["flashlight", "desk_lamp"], ["candle", "kerosene_lamp"]),
        (["desk_lamp", "flashlight"], ["kerosene_lamp", "candle"]),
        (["flashlight", "desk_lamp"], ["kerosene_lamp", "candle"]),
        (["desk_lamp", "flashlight"], ["candle", "kerosene_lamp"]),  # every pairing once, then again
    ]


def test_without_counterbalancing_the_order_is_as_listed() -> None:
    for number in range(4):
        assert object_orders(number, ["a", "b"], ["c", "d", "e"], False, False) == (["a", "b"], ["c", "d", "e"])
    assert object_orders(1, ["a", "b"], ["c", "d"], False, True) == (["a", "b"], ["d", "c"])
    with pytest.raises(ValueError, match="start at 0"):
        object_orders(-1, ["a"], ["b"], True, True)
