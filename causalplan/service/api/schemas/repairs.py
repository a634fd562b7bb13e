"""The repairs a transfer's answer carries when asked (``repair: true``): edits that make it transfer."""

from __future__ import annotations

from typing import Any

from pydantic import Field

from causalplan.service.api.schemas.common import OutputModel


class EditOut(OutputModel):
    kind: str
    label: str
    part: str | None
    rule: int | None
    effect: str | None
    says: str


class RepairOut(OutputModel):
    size: int
    edits: list[EditOut]
    says: str
    verdict: str
    decided_by: str
    plan: list[dict[str, Any]] | None


class RepairsOut(OutputModel):
    """The smallest sets of edits that make a failed transfer work, each re-checked by a full verdict."""

    found: int
    by_size: dict[int, int]
    checked: int
    max_edits: int
    complete: bool = Field(
        default=True,
        description="False when the search stopped at its time budget (CAUSALPLAN_SEARCH_SECONDS) before checking "
        "every edit set: the repairs are those found until then.",
    )
    repairs: list[RepairOut]
