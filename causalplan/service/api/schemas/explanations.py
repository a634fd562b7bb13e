"""Requests and answers of POST /v1/explanations."""

from __future__ import annotations

import uuid
from typing import Any

from pydantic import Field

from causalplan.service.api.schemas.common import OutputModel
from causalplan.service.api.schemas.plans import PlanIn, PlanResultOut


class ExplanationIn(PlanIn):
    """POST /v1/explanations: plan a model and explain the plan (why a step; why not another)."""

    why: str | None = Field(
        default=None,
        max_length=64,
        description="A step number, the part a step attaches, or 'all'; every step when neither question is asked.",
    )
    why_not: str | None = Field(
        default=None,
        max_length=200,
        description="A contrastive question: 'attach PART', 'leave out PART', 'leave out step N', "
        "'PART before PART' or 'use FIT' (PART a part's id or name, FIT a fit's id).",
    )
    simulate: bool = Field(default=False, description="When an order cannot be done, also try it in the simulator.")


class LinkOut(OutputModel):
    rule: int
    rule_text: str
    cause: str
    effect: str


class ChainOut(OutputModel):
    function: str
    rules: list[LinkOut]


class WhyOut(OutputModel):
    """Why one step is in the plan: the causal chain of each function its part carries."""

    step: int
    text: str
    part: str
    chains: list[ChainOut]
    unused_functions: list[str]
    reached_by: list[int]
    message: str


class WhyNotOut(OutputModel):
    """The answer to a why-not question: a code, the words, what decides it, and the alternative plan."""

    question: str
    asked: dict[str, Any]
    code: str = Field(
        description="already_does, not_needed, also_works, longer, shorter, goal_unreachable, "
        "blocked, no_assembly_sequence, violates_true_mechanism or undecided."
    )
    message: str
    decided_by: dict[str, Any]
    alternative: PlanResultOut = Field(description="The alternative plan, replayed and checked like any plan.")
    simulation_failure: str | None


class ExplanationOut(OutputModel):
    """``causalplan explain --json``, and the model stored."""

    plan: PlanResultOut
    why: list[WhyOut]
    why_not: WhyNotOut | None
    model_id: uuid.UUID
