"""The object as a troubleshooter sees it: which part holds which, which blocks which, what shows.

Parts are numbered in the catalog's order and sets of parts are bit masks (bit ``i`` is part
``i``), because the solver keeps millions of them. The *body* parts are the ones attached to
the assembly (each by the one fit that moves it); the base stays where it is; *tools* are the
parts used only to light the object (a match), which the test itself uses. A part is held by
the fixed side of its fit; a fit's ``blocks`` covers a connector, and so blocks that
connector's part and every part attached at it (the desk lamp's shade blocks the bulb).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

from causalplan.objects.model import AssemblyObject
from causalplan.troubleshoot.errors import NotTroubleshootableError

NO_PART = -1


def bits(mask: int) -> Iterator[int]:
    """Yield the indices of the set bits of ``mask``, lowest first."""
    index = 0
    while mask:
        if mask & 1:
            yield index
        mask >>= 1
        index += 1


@dataclass(frozen=True)
class Structure:
    """The parts of one object, how they hold and block each other, and which faults inspection shows."""

    object_id: str
    parts: tuple[str, ...]
    base: int
    body: int
    """The parts attached in the assembled object (all but the base and the tools)."""
    tools: int
    holder: tuple[int, ...]
    """Each body part's holder (the fixed side of its fit); ``NO_PART`` for the base and the tools."""
    blockers: tuple[int, ...]
    """Each part's blockers: the body parts whose fits cover one of its connectors or its own fit's seat."""
    children: tuple[int, ...]
    """Each part's children: the body parts it holds."""
    visible: int
    """The parts whose fault inspection shows."""

    @property
    def size(self) -> int:
        return len(self.parts)

    @property
    def all_parts(self) -> int:
        return (1 << self.size) - 1

    def index(self, part: str) -> int:
        """Return the number of ``part`` (ValueError when the object has no such part)."""
        return self.parts.index(part)

    def names(self, mask: int) -> list[str]:
        """Return the part ids in ``mask``, in the catalog's order."""
        return [self.parts[index] for index in bits(mask)]

    def is_reachable(self, part: int, attached: int) -> bool:
        """Return whether nothing that blocks ``part`` or is held by it is attached."""
        return not attached & (self.blockers[part] | self.children[part])

    def is_assembled(self, attached: int) -> bool:
        return attached == self.body

    def can_detach(self, part: int, attached: int) -> bool:
        return bool(attached >> part & 1) and self.is_reachable(part, attached)

    def can_attach(self, part: int, attached: int) -> bool:
        holder = self.holder[part]
        holder_in_place = holder == self.base or bool(attached >> holder & 1)
        return (
            bool(self.body >> part & 1)
            and not attached >> part & 1
            and holder_in_place
            and not attached & self.blockers[part]
        )

    def can_replace(self, part: int, attached: int) -> bool:
        """Return whether ``part`` can be swapped for a spare: off the object (the base: everything off)."""
        if self.tools >> part & 1:
            return True
        if part == self.base:
            return attached == 0
        return not attached >> part & 1

    def can_inspect(self, part: int, attached: int) -> bool:
        """Return whether inspecting ``part`` can show its fault now: a visible fault on a reachable part."""
        return bool(self.visible >> part & 1) and (bool(self.tools >> part & 1) or self.is_reachable(part, attached))


def _fit_of_each_part(obj: AssemblyObject) -> dict[str, str]:
    """Return the fit that attaches each body part; refuse parts attached two ways or not at all."""
    moving: dict[str, list[str]] = {}
    lit_by: set[str] = set()
    for fit in obj.fits:
        if fit.primitive == "ignite":
            lit_by.add(fit.moving_part)
        else:
            moving.setdefault(fit.moving_part, []).append(fit.id)
    two_ways = sorted(part for part, fits in moving.items() if len(fits) > 1)
    if two_ways:
        raise NotTroubleshootableError(
            f"The {obj.name} has parts that attach in more than one way ({', '.join(two_ways)}); troubleshooting "
            "needs one assembled object, each part in one place.",
            details={"object": obj.id, "parts": two_ways},
        )
    loose = [part for part in obj.part_ids if part != obj.base and part not in moving and part not in lit_by]
    if loose:
        raise NotTroubleshootableError(
            f"No fit attaches {', '.join(loose)} to the {obj.name}.", details={"object": obj.id, "parts": loose}
        )
    return {part: fits[0] for part, fits in moving.items() if part != obj.base}


def structure_of(obj: AssemblyObject) -> Structure:
    """Return how ``obj``'s parts hold and block each other (NotTroubleshootableError when they cannot)."""
    parts = obj.part_ids
    number = {part: index for index, part in enumerate(parts)}
    fit_of = _fit_of_each_part(obj)
    body = sum(1 << number[part] for part in fit_of)
    tools = sum(1 << number[part] for part in parts if part != obj.base and part not in fit_of)
    holder = [NO_PART] * len(parts)
    children = [0] * len(parts)
    for part, fit_id in fit_of.items():
        fixed = number[obj.fit(fit_id).fixed_part]
        holder[number[part]] = fixed
        children[fixed] |= 1 << number[part]
    seat_of = {(obj.fit(fit_id).fixed_part, obj.fit(fit_id).fixed_connector): part for part, fit_id in fit_of.items()}
    blockers = [0] * len(parts)
    for part, fit_id in fit_of.items():
        for covered_part, connector in obj.fit(fit_id).blocks:
            for blocked in (covered_part, seat_of.get((covered_part, connector))):
                if blocked is not None and blocked != part:
                    blockers[number[blocked]] |= 1 << number[part]
    visible = sum(1 << number[fault.part] for fault in obj.faults if fault.visible)
    return Structure(
        object_id=obj.id,
        parts=parts,
        base=number[obj.base],
        body=body,
        tools=tools,
        holder=tuple(holder),
        blockers=tuple(blockers),
        children=tuple(children),
        visible=visible,
    )
