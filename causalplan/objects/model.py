"""The catalog's objects: parts with connectors, the fits between them, the true mechanism."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

PRIMITIVE_TEXTS: dict[str, str] = {
    "screw": "Screw the {moving} into the {fixed}.",
    "insert": "Insert the {moving} into the {fixed}.",
    "connect": "Connect the {moving} to the {fixed}.",
    "place": "Place the {moving} on the {fixed}.",
    "clip": "Clip the {moving} onto the {fixed}.",
    "plug": "Plug the {moving} into the {fixed}.",
    "ignite": "Light the {fixed} with the {moving}.",
}
"""The assembly primitives, each with the sentence that describes one step."""


Vector = tuple[float, float, float]
"""A point or direction in metres, in a part's own frame."""


@dataclass(frozen=True)
class Shape:
    """One solid primitive of a part's geometry, placed in the part's frame.

    ``size`` is the shape's own bounding box in metres: a box's lengths along x, y, z; a
    cylinder's diameter, diameter, length (its axis is z); a sphere's diameter three times.
    ``rotation`` is roll, pitch, yaw in radians; ``color`` is red, green, blue, alpha in 0..1
    (alpha below 1 draws the shape as glass).
    """

    kind: str
    size: Vector
    position: Vector = (0.0, 0.0, 0.0)
    rotation: Vector = (0.0, 0.0, 0.0)
    color: tuple[float, float, float, float] = (0.6, 0.6, 0.6, 1.0)


@dataclass(frozen=True)
class Geometry:
    """What a part looks like and weighs: its solid shapes, mass, and the light it gives.

    ``light`` shapes are drawn only when the object produces its goal (a lit bulb, a flame).
    """

    shapes: tuple[Shape, ...]
    mass: float
    light: tuple[Shape, ...] = ()


@dataclass(frozen=True)
class Connector:
    """A place on a part where another part attaches; parts fit when their specs match.

    ``position`` and ``axis`` (optional) give the connector's frame in the part's frame: the
    point that meets the other part's connector, and the outward direction a mating part
    comes from. Left out, the simulator puts the connector on a face of the part.
    """

    id: str
    kind: str
    spec: str
    position: Vector | None = None
    axis: Vector | None = None


@dataclass(frozen=True)
class Grasp:
    """Where the robot's gripper holds a part, in the part's frame.

    ``position`` is the point between the fingertips, ``approach`` the direction the gripper
    points (towards the part), ``fingers`` the direction the fingers close along, and
    ``width`` how far apart the fingers are when closed on the part (metres).
    """

    position: Vector
    approach: Vector = (0.0, 0.0, -1.0)
    fingers: Vector = (0.0, 1.0, 0.0)
    width: float | None = None


@dataclass(frozen=True)
class Part:
    """One part of an object; ``geometry`` is optional (the simulator then uses a plain cylinder).

    ``grasp`` is optional too: without it the robot holds the part from above, at its top.
    """

    id: str
    name: str
    connectors: tuple[Connector, ...]
    geometry: Geometry | None = None
    grasp: Grasp | None = None


@dataclass(frozen=True)
class Fit:
    """A way to attach ``moving`` (not yet assembled) to ``fixed`` (already assembled).

    Doing it uses both connectors, and also makes the ``blocks`` connectors unusable (a
    part that closes or covers them), which is how the catalog states order constraints.
    """

    id: str
    primitive: str
    moving_part: str
    moving_connector: str
    fixed_part: str
    fixed_connector: str
    probability: float
    blocks: tuple[tuple[str, str], ...] = ()
    text: str | None = None
    tolerance_mm: float | None = None
    """How far off its seat the moving connector may arrive and still engage (a thread's lead-in, a
    clip's chamfer); None: the simulator's alignment tolerance."""
    tolerance_deg: float | None = None
    """The same, as the angle between the connector axes."""

    def connectors(self) -> tuple[tuple[str, str], tuple[str, str]]:
        """Return the two (part, connector) pairs this fit joins."""
        return (self.moving_part, self.moving_connector), (self.fixed_part, self.fixed_connector)


@dataclass(frozen=True)
class Requirement:
    """One condition of the true mechanism: at least one of ``any_of`` fits has been made.

    ``function`` is what the part making it does, in an expert's words (None: not given).
    ``after`` is the order a real object imposes: fits that must have been made at an earlier
    step than this requirement's fit (a wick burns only if the fuel was there when it was lit).
    """

    any_of: tuple[str, ...]
    says: str
    function: str | None = None
    after: tuple[str, ...] = ()

    def is_met_by(self, made: Sequence[str]) -> bool:
        """Return whether the fits ``made`` (in the order made) meet this requirement, its order included."""
        steps = {fit_id: number for number, fit_id in enumerate(made)}
        return any(
            fit_id in steps and all(steps.get(earlier, len(made)) < steps[fit_id] for earlier in self.after)
            for fit_id in self.any_of
        )


@dataclass(frozen=True)
class Fault:
    """One way the assembled object can fail: ``part`` is broken (one fault at a time).

    ``probability`` is the prior of this part being the broken one (an object's faults sum to
    1); ``looks`` says what the fault is like; ``visible`` says whether inspecting the part
    shows it (a burnt-out filament does; flat batteries do not).
    """

    part: str
    probability: float
    looks: str
    visible: bool


@dataclass(frozen=True)
class AssemblyObject:
    """An assemblable object: its parts, fits, base part, category and true mechanism."""

    id: str
    name: str
    category: str
    goal: str
    description: str
    base: str
    parts: tuple[Part, ...]
    fits: tuple[Fit, ...]
    mechanism: tuple[Requirement, ...]
    mechanism_explanation: str
    faults: tuple[Fault, ...] = ()
    """The parts whose failure stops the goal, with priors; empty when the file gives none."""
    fault_priors: str | None = None
    """Where the faults' priors come from ("illustrative" or "measured"); None without faults."""

    @property
    def part_ids(self) -> tuple[str, ...]:
        return tuple(part.id for part in self.parts)

    def part(self, part_id: str) -> Part:
        """Return the part with this id (KeyError when there is none)."""
        for part in self.parts:
            if part.id == part_id:
                return part
        raise KeyError(part_id)

    def fit(self, fit_id: str) -> Fit:
        """Return the fit with this id (KeyError when there is none)."""
        for fit in self.fits:
            if fit.id == fit_id:
                return fit
        raise KeyError(fit_id)

    def step_text(self, fit: Fit) -> str:
        """Return the sentence describing the step that makes ``fit``."""
        template = fit.text or PRIMITIVE_TEXTS[fit.primitive]
        return template.format(moving=self.part(fit.moving_part).name, fixed=self.part(fit.fixed_part).name)

    def requirement_of(self, fit_id: str) -> Requirement | None:
        """Return the first requirement of the true mechanism that ``fit_id`` can meet (None: no requirement)."""
        return next((requirement for requirement in self.mechanism if fit_id in requirement.any_of), None)

    def order_words(self, requirement: Requirement) -> str:
        """Return a requirement in words with the order it needs, e.g. 'the wick has been lit after the ...'."""
        if not requirement.after:
            return requirement.says
        earlier = []
        for fit_id in requirement.after:
            needed = self.requirement_of(fit_id)
            earlier.append(needed.says if needed is not None else self.step_text(self.fit(fit_id)).rstrip("."))
        return f"{requirement.says} after {' and '.join(earlier)}"

    def is_needed(self, part_id: str) -> bool:
        """Return whether the true mechanism fails when ``part_id`` does nothing (a fault there stops the goal).

        A requirement then holds only through a fit that does not involve the part; a part
        that every fit of some requirement involves (as the moving or the fixed side) is needed.
        """
        return any(
            all(part_id in (self.fit(fit_id).moving_part, self.fit(fit_id).fixed_part) for fit_id in requirement.any_of)
            for requirement in self.mechanism
        )

    def excluded_fits(self, fit: Fit) -> tuple[str, ...]:
        """Return the fits (itself included) that can no longer be made once ``fit`` is made."""
        taken = set(fit.connectors()) | set(fit.blocks)
        return tuple(other.id for other in self.fits if other.id == fit.id or taken & set(other.connectors()))
