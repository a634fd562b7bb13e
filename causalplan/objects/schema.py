"""The schema of catalog object files (YAML/JSON), checked with pydantic, then cross-checked."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field, field_validator

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


class ConnectorSchema(_Strict):
    id: str = Field(pattern=IDENTIFIER_PATTERN, description="Unique within the part.")
    kind: str = Field(min_length=1, max_length=64, description="The physical feature, e.g. 'thread'.")
    spec: str = Field(min_length=1, max_length=64, description="The standard both sides must share, e.g. 'E27'.")


class PartSchema(_Strict):
    id: str = Field(pattern=IDENTIFIER_PATTERN)
    name: str = Field(min_length=1, max_length=80, description="Display name, e.g. 'light bulb'.")
    connectors: list[ConnectorSchema] = Field(default_factory=list)


class FitSchema(_Strict):
    id: str = Field(pattern=IDENTIFIER_PATTERN)
    primitive: str
    moving: str = Field(description="'part.connector' of the part being attached.")
    fixed: str = Field(description="'part.connector' of the part already in the assembly.")
    probability: float = Field(default=1.0, gt=0.0, le=1.0)
    blocks: list[str] = Field(default_factory=list, description="'part.connector's this fit covers.")
    text: str | None = Field(default=None, max_length=200, description="Sentence with {moving} and {fixed}.")

    @field_validator("primitive")
    @classmethod
    def _known_primitive(cls, value: str) -> str:
        if value not in PRIMITIVE_TEXTS:
            raise ValueError(f"unknown primitive '{value}'; use one of: {', '.join(PRIMITIVE_TEXTS)}")
        return value


class RequirementSchema(_Strict):
    any: list[str] = Field(min_length=1, description="Fit ids; any one of them satisfies the requirement.")
    says: str = Field(min_length=1, max_length=200, description="The requirement in words.")


class MechanismSchema(_Strict):
    explanation: str = Field(min_length=1, max_length=1000)
    requires: list[RequirementSchema] = Field(min_length=1)


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
