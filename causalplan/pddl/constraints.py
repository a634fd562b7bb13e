"""Constraints a question adds to a planning task: parts required, fits forbidden, an order of parts.

A contrastive question ("why not attach the shade?", "why not the shade before the bulb?")
is answered by planning again with its constraint compiled into the problem file, so the
domain (and its derived predicates) stays as the person's rules made it:

* a required part is one more goal conjunct, ``(in-assembly part)``;
* a forbidden fit is never ``(available fit)`` in the initial state;
* "first before then" adds ``(excludes fit-of-then fit-of-first)`` facts, so once ``then`` is
  in the assembly ``first`` can no longer be attached (and both are required parts).

Only part and fit ids of the catalog's object are written, which the PDDL already uses;
``check`` refuses anything else, so no text a person typed reaches the PDDL.
"""

from __future__ import annotations

from dataclasses import dataclass

from causalplan.errors import CausalPlanError
from causalplan.objects.model import AssemblyObject, Fit


class InvalidConstraintError(CausalPlanError):
    """A constraint names a part or fit the object does not have."""

    code = "invalid_constraint"


@dataclass(frozen=True)
class PlanConstraints:
    """What a plan must also do: attach ``required_parts``, never make ``forbidden_fits``, respect ``orderings``.

    An ordering ``(first, then)`` means: ``first`` is attached before ``then``.
    """

    required_parts: frozenset[str] = frozenset()
    forbidden_fits: frozenset[str] = frozenset()
    orderings: frozenset[tuple[str, str]] = frozenset()

    @property
    def is_empty(self) -> bool:
        return not (self.required_parts or self.forbidden_fits or self.orderings)

    def all_required(self) -> frozenset[str]:
        """Return the parts the plan must attach (those of an ordering included)."""
        return self.required_parts | {part for pair in self.orderings for part in pair}

    def check(self, obj: AssemblyObject) -> None:
        """Raise ``InvalidConstraintError`` unless every part and fit named is one of ``obj``'s."""
        parts, fits = set(obj.part_ids), {fit.id for fit in obj.fits}
        unknown_parts = sorted(self.all_required() - parts)
        unknown_fits = sorted(self.forbidden_fits - fits)
        if unknown_parts or unknown_fits:
            raise InvalidConstraintError(
                f"The {obj.name} has no part {', '.join(unknown_parts)} / fit {', '.join(unknown_fits)}.",
                details={"parts": unknown_parts, "fits": unknown_fits},
            )

    def is_available(self, fit: Fit) -> bool:
        """Return whether ``fit`` may be made at all."""
        return fit.id not in self.forbidden_fits

    def excluded_after(self, obj: AssemblyObject, fit: Fit) -> tuple[str, ...]:
        """Return the fits that making ``fit`` rules out because an ordering puts their part first."""
        earlier = {first for first, then in self.orderings if then == fit.moving_part}
        if not earlier:  # no ordering (every plan's case): no pass over the object's fits per step
            return ()
        return tuple(other.id for other in obj.fits if other.moving_part in earlier)

    def goal_facts(self) -> list[str]:
        """Return the goal conjuncts the constraints add, one ``(in-assembly part)`` per required part."""
        return [f"(in-assembly {part})" for part in sorted(self.all_required())]

    def violations(self, obj: AssemblyObject, made: list[str]) -> list[str]:
        """Return, in words, what the made fits (in order) do against the constraints."""
        moved = [obj.fit(fit_id).moving_part for fit_id in made]
        problems = [f"it makes the forbidden fit {fit_id}" for fit_id in made if fit_id in self.forbidden_fits]
        problems += [
            f"it does not attach the {obj.part(part).name}"
            for part in sorted(self.all_required())
            if part not in moved and part != obj.base
        ]
        problems += [
            f"it attaches the {obj.part(then).name} before the {obj.part(first).name}"
            for first, then in sorted(self.orderings)
            if first in moved and then in moved and moved.index(then) < moved.index(first)
        ]
        return problems


NO_CONSTRAINTS = PlanConstraints()
