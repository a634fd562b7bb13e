"""Synthetic objects of any size for the solver's tests and its benchmark, built as ``Structure``s directly.

The two extremes of access: a *star* (every part on the base, side by side: the most
assembly states, 2 to the number of parts) and a *chain* (each part held by the one below:
the fewest, one more than the parts).
"""

from __future__ import annotations

from causalplan.troubleshoot.structure import NO_PART, Structure


def star(count: int, *, visible: bool) -> Structure:
    """Return a base with ``count`` parts, each on its own socket of the base, none blocking another.

    Every part is equally easy to reach: the setting of the classical ratio rule.
    """
    parts = ("base", *(f"p{index}" for index in range(1, count + 1)))
    body = sum(1 << index for index in range(1, count + 1))
    return Structure(
        object_id=f"star_{count}",
        parts=parts,
        base=0,
        body=body,
        tools=0,
        holder=(NO_PART, *(0 for _ in range(count))),
        blockers=tuple(0 for _ in parts),
        children=(body, *(0 for _ in range(count))),
        visible=body if visible else 0,
    )


def chain(count: int, *, visible: bool) -> Structure:
    """Return a base with ``count`` parts stacked, each held by the one below: the deepest is the hardest to reach."""
    parts = ("base", *(f"p{index}" for index in range(1, count + 1)))
    body = sum(1 << index for index in range(1, count + 1))
    return Structure(
        object_id=f"chain_{count}",
        parts=parts,
        base=0,
        body=body,
        tools=0,
        holder=(NO_PART, *range(count)),
        blockers=tuple(0 for _ in parts),
        children=(*(1 << (index + 1) for index in range(count)), 0),
        visible=body if visible else 0,
    )
