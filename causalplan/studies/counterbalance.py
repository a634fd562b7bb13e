"""Counterbalancing the order of objects across participants with balanced Latin squares.

Participant number k of a condition (0, 1, 2, ...) gets row ``k`` of the training objects'
square and, once those rows have all been used, the next row of the test objects' square:
the two orders are crossed, so every pair of orders comes up equally often.
"""

from __future__ import annotations

from collections.abc import Sequence


def latin_square(size: int) -> list[tuple[int, ...]]:
    """Return the rows of a balanced Latin square (Williams design) of ``size`` items.

    Every row is an order of ``0 .. size-1``. Over the rows, each item stands in each position
    equally often, and each item directly follows every other item equally often; for an odd
    size that needs the mirrored rows as well, so there are ``2 * size`` rows (``size`` when even).
    """
    if size < 1:
        raise ValueError(f"a Latin square needs at least one item, not {size}")
    if size == 1:
        return [(0,)]
    first = [0]
    low, high = 1, size - 1
    while len(first) < size:  # 0, 1, n-1, 2, n-2, ...: every difference between neighbours once
        if len(first) % 2:
            first.append(low)
            low += 1
        else:
            first.append(high)
            high -= 1
    rows = [tuple((item + shift) % size for item in first) for shift in range(size)]
    if size % 2:
        rows += [tuple(reversed(row)) for row in rows]
    return rows


def ordered(items: Sequence[str], row: Sequence[int]) -> list[str]:
    """Return ``items`` in the order of one row of a Latin square."""
    return [items[index] for index in row]


def object_orders(
    ordinal: int,
    training: Sequence[str],
    tests: Sequence[str],
    counterbalance_training: bool,
    counterbalance_tests: bool,
) -> tuple[list[str], list[str]]:
    """Return the training and test objects in the order participant number ``ordinal`` of a condition meets them."""
    if ordinal < 0:
        raise ValueError(f"participant numbers start at 0, not {ordinal}")
    training_rows = latin_square(len(training)) if counterbalance_training else [tuple(range(len(training)))]
    test_rows = latin_square(len(tests)) if counterbalance_tests else [tuple(range(len(tests)))]
    training_row = training_rows[ordinal % len(training_rows)]
    test_row = test_rows[(ordinal // len(training_rows)) % len(test_rows)]
    return ordered(training, training_row), ordered(tests, test_row)
