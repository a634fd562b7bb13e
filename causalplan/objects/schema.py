"""The schema of catalog object files (YAML/JSON), checked with pydantic, then cross-checked."""

from __future__ import annotations

from typing import Annotated, Literal, Self

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from causalplan.causal.rules import keywords_in
from causalplan.objects.model import PRIMITIVE_TEXTS

IDENTIFIER_PATTERN = r"^[a-z][a-z0-9_]{0,63}$"
RESERVED_WORDS = frozenset(
    {
        "and",
        "or",
        "not",
        "imply",
        "exists",
        "forall",
        "when",
        "either",
        "object",
        "define",
        "domain",
        "problem",
        "at",
        "over",
        "start",
        "end",
        "all",
        "preference",
        "minimize",
        "maximize",
        "total_time",
    }
)


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


Coordinate = Annotated[float, Field(ge=-5.0, le=5.0)]
"""Metres in a part's frame (a part is at most a few metres across)."""
Length = Annotated[float, Field(ge=0.0001, le=5.0)]
"""Metres, from a tenth of a millimetre."""
Point = tuple[Coordinate, Coordinate, Coordinate]
Angle = Annotated[float, Field(ge=-720.0, le=720.0)]
"""Degrees. Bounds (as on every number here) also refuse NaN and infinity."""
Direction = tuple[Coordinate, Coordinate, Coordinate]

_SHAPE_FIELDS = {
    "box": ({"size"}, "size: [x, y, z]"),
    "cylinder": ({"radius", "length"}, "radius and length"),
    "sphere": ({"radius"}, "radius"),
    "tube": ({"radius", "length", "thickness"}, "radius, length and thickness (top_radius makes a cone)"),
}
_SIZE_FIELDS = ("size", "radius", "top_radius", "length", "thickness")


class ShapeSchema(_Strict):
    """One solid of a part, in metres in the part's frame; a tube is a hollow ring of boxes."""

    shape: Literal["box", "cylinder", "sphere", "tube"]
    size: tuple[Length, Length, Length] | None = Field(default=None, description="box: lengths along x, y, z.")
    radius: Length | None = Field(default=None, description="cylinder, sphere; tube: outer radius at the bottom.")
    top_radius: Length | None = Field(default=None, description="tube: outer radius at the top (default radius).")
    length: Length | None = Field(default=None, description="cylinder, tube: length along the shape's z axis.")
    thickness: Length | None = Field(default=None, description="tube: wall thickness.")
    segments: int = Field(default=12, ge=3, le=64, description="tube: number of boxes around.")
    at: Point = Field(default=(0.0, 0.0, 0.0), description="Centre of the shape in the part's frame.")
    turn: tuple[Angle, Angle, Angle] = Field(default=(0.0, 0.0, 0.0), description="Roll, pitch, yaw in degrees.")
    color: str = Field(default="#999999", pattern=r"^#[0-9a-fA-F]{6}([0-9a-fA-F]{2})?$", description="#rrggbb[aa]")

    @model_validator(mode="after")
    def _fields_for_the_shape(self) -> Self:
        needed, words = _SHAPE_FIELDS[self.shape]
        given = {name for name in _SIZE_FIELDS if getattr(self, name) is not None}
        allowed = needed | ({"top_radius"} if self.shape == "tube" else set())
        if needed - given:
            raise ValueError(f"a {self.shape} needs {words}, in metres")
        if given - allowed:
            raise ValueError(f"a {self.shape} does not use {', '.join(sorted(given - allowed))}")
        radius = min(self.radius or 0.0, self.top_radius or self.radius or 0.0)
        if self.thickness is not None and self.thickness >= radius:
            raise ValueError("a tube's thickness must be less than its radius")
        return self


class GeometrySchema(_Strict):
    """What a part looks like in the simulator: solids, mass, and the light it gives when it works."""

    mass: float = Field(default=0.1, gt=0.0, le=1000.0, description="Kilograms.")
    shapes: list[ShapeSchema] = Field(min_length=1, max_length=200)
    light: list[ShapeSchema] = Field(
        default_factory=list, max_length=50, description="Drawn only when the object produces its goal."
    )


class ConnectorSchema(_Strict):
    id: str = Field(pattern=IDENTIFIER_PATTERN, description="Unique within the part.")
    kind: str = Field(min_length=1, max_length=64, description="The physical feature, e.g. 'thread'.")
    spec: str = Field(min_length=1, max_length=64, description="The standard both sides must share, e.g. 'E27'.")
    at: Point | None = Field(default=None, description="Where the connector meets its mate, in the part's frame.")
    axis: Direction | None = Field(
        default=None, description="Outward direction a mating part comes from, in the part's frame."
    )

    @field_validator("axis")
    @classmethod
    def _axis_has_a_direction(cls, value: tuple[float, float, float] | None) -> tuple[float, float, float] | None:
        if value is not None and sum(component * component for component in value) < 1e-12:
            raise ValueError("the axis must not be [0, 0, 0]")
        return value


class GraspSchema(_Strict):
    """Where the robot's gripper holds the part, in the part's frame (metres)."""

    at: Point = Field(description="The point between the fingertips.")
    approach: Direction = Field(default=(0.0, 0.0, -1.0), description="The direction the gripper points.")
    fingers: Direction = Field(default=(0.0, 1.0, 0.0), description="The direction the fingers close along.")
    width: float | None = Field(default=None, ge=0.0, le=0.08, description="Finger gap when closed (metres).")

    @model_validator(mode="after")
    def _directions(self) -> Self:
        for name in ("approach", "fingers"):
            if sum(component * component for component in getattr(self, name)) < 1e-12:
                raise ValueError(f"the grasp's {name} must not be [0, 0, 0]")
        a, f = self.approach, self.fingers
        cosine = (
            abs(sum(x * y for x, y in zip(a, f, strict=True))) / (sum(x * x for x in a) * sum(y * y for y in f)) ** 0.5
        )
        if cosine > 0.01:
            raise ValueError("the grasp's fingers must close at right angles to its approach")
        return self


class PartSchema(_Strict):
    id: str = Field(pattern=IDENTIFIER_PATTERN)
    name: str = Field(min_length=1, max_length=80, description="Display name, e.g. 'light bulb'.")
    connectors: list[ConnectorSchema] = Field(default_factory=list)
    geometry: GeometrySchema | None = Field(default=None, description="Optional; without it, a 5 cm cylinder.")
    grasp: GraspSchema | None = Field(default=None, description="Optional; without it, held from above at the top.")


class FitSchema(_Strict):
    id: str = Field(pattern=IDENTIFIER_PATTERN)
    primitive: str
    moving: str = Field(description="'part.connector' of the part being attached.")
    fixed: str = Field(description="'part.connector' of the part already in the assembly.")
    probability: float = Field(default=1.0, gt=0.0, le=1.0)
    blocks: list[str] = Field(default_factory=list, description="'part.connector's this fit covers.")
    text: str | None = Field(default=None, max_length=200, description="Sentence with {moving} and {fixed}.")
    tolerance_mm: float | None = Field(
        default=None, gt=0.0, le=50.0, description="How far off the seat the part may arrive and still engage (mm)."
    )
    tolerance_deg: float | None = Field(
        default=None, gt=0.0, le=45.0, description="How tilted it may arrive and still engage (degrees)."
    )

    @field_validator("primitive")
    @classmethod
    def _known_primitive(cls, value: str) -> str:
        if value not in PRIMITIVE_TEXTS:
            raise ValueError(f"unknown primitive '{value}'; use one of: {', '.join(PRIMITIVE_TEXTS)}")
        return value


class RequirementSchema(_Strict):
    any: list[str] = Field(min_length=1, description="Fit ids; any one of them satisfies the requirement.")
    says: str = Field(min_length=1, max_length=200, description="The requirement in words.")
    function: str | None = Field(
        default=None,
        min_length=1,
        max_length=80,
        description="What the part making it does, as an expert labels it (the reference model's function).",
    )
    after: list[str] = Field(
        default_factory=list,
        description="Fit ids that must have been made at an earlier step than this requirement's fit: the order "
        "a real object imposes (the fuel is there before the wick is lit).",
    )

    @field_validator("function")
    @classmethod
    def _no_rule_keywords(cls, value: str | None) -> str | None:
        if value is not None and keywords_in(value):
            raise ValueError("a function label cannot hold the rule keywords AND or CAUSES as words")
        return value


class MechanismSchema(_Strict):
    explanation: str = Field(min_length=1, max_length=1000)
    requires: list[RequirementSchema] = Field(min_length=1)


class FaultSchema(_Strict):
    part: str = Field(pattern=IDENTIFIER_PATTERN, description="The part that is broken.")
    probability: float = Field(gt=0.0, le=1.0, description="Prior that this part is the broken one.")
    looks: str = Field(min_length=1, max_length=200, description="What the fault is, e.g. 'a burnt-out filament'.")
    visible: bool = Field(description="Whether inspecting the part shows the fault.")


class FaultsSchema(_Strict):
    """The parts whose failure stops the goal (one fault at a time), with prior probabilities."""

    priors: Literal["illustrative", "measured"] = Field(
        description="Where the probabilities come from: 'illustrative' (made up to show the idea) or 'measured'."
    )
    parts: list[FaultSchema] = Field(min_length=1, max_length=100)


class ObjectSchema(_Strict):
    id: str = Field(pattern=IDENTIFIER_PATTERN)
    name: str = Field(min_length=1, max_length=80)
    category: str = Field(pattern=IDENTIFIER_PATTERN, description="e.g. 'electric' or 'combustion'.")
    goal: str = Field(min_length=1, max_length=80)
    description: str = Field(default="", max_length=1000)
    base: str = Field(description="The part the assembly starts from.")
    parts: list[PartSchema] = Field(min_length=1)
    fits: list[FitSchema] = Field(default_factory=list)
    mechanism: MechanismSchema
    faults: FaultsSchema | None = Field(default=None, description="Optional; without it, no troubleshooting.")
