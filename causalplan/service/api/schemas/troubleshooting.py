"""Request and answer of POST /v1/troubleshooting: repair a broken object with a model as the prior."""

from __future__ import annotations

import uuid
from typing import Literal

from pydantic import Field, model_validator

from causalplan.service.api.schemas.common import DiagnosticOut, InputModel, MappingDocument, ModelDocument, OutputModel


class TroubleshootingIn(InputModel):
    """POST /v1/troubleshooting: the strategies' table on a broken object, and one episode if ``fault`` is given."""

    model: ModelDocument | None = Field(default=None, description="The model inline (or give model_id).")
    model_id: uuid.UUID | None = Field(default=None, description="A model stored by POST /v1/models.")
    mapping: MappingDocument | None = Field(default=None, description="A step-3 mapping: troubleshoot that object.")
    object: str | None = Field(
        default=None,
        min_length=1,
        max_length=64,
        description="The broken object (default: the mapping's, else the model's).",
    )
    fault: str | None = Field(
        default=None, min_length=1, max_length=64, description="The broken part: also run one episode ('episode')."
    )
    strategy: Literal["model", "uniform", "oracle"] = Field(
        default="model", description="Whose policy runs the episode."
    )

    @model_validator(mode="after")
    def _one_model(self) -> TroubleshootingIn:
        if (self.model is None) == (self.model_id is None):
            raise ValueError("give exactly one of 'model' (the model inline) and 'model_id' (a stored model)")
        return self


class FaultResultOut(OutputModel):
    part: str
    probability: float = Field(description="The catalog's prior of this fault.")
    actions: int = Field(description="The actions this strategy takes when this part is broken.")
    fewest_actions: int = Field(description="The fewest actions of a robot that knows this part is broken.")
    reward_share: float = Field(description="(bonus - actions) / (bonus - fewest_actions).")


class StrategyOut(OutputModel):
    expected_actions: float = Field(description="Expected actions to the repair, under the catalog's priors.")
    worst_actions: int = Field(description="The most actions over the fault locations.")
    reward_share: float = Field(description="The reward as a share of the maximum, averaged over fault locations.")
    own_expected_actions: float = Field(description="Expected actions under the strategy's own prior.")
    faults: dict[str, FaultResultOut]


class StepOut(OutputModel):
    action: Literal["test", "inspect", "detach", "attach", "replace"]
    part: str | None = Field(description="The part acted on (null for a test).")
    observed: Literal["goal", "no goal", "broken", "works"] | None = Field(
        description="What a test or an inspection showed (null for the other actions)."
    )


class StrategyActionsOut(OutputModel):
    actions: int


class EpisodeOut(OutputModel):
    fault: str
    strategy: Literal["model", "uniform", "oracle"]
    actions: int
    steps: list[StepOut]
    strategies: dict[str, StrategyActionsOut] = Field(description="Each strategy's actions on the same fault.")


class TroubleshootingOut(OutputModel):
    """The same JSON as `causalplan troubleshoot --all-faults --json`, with the episode when a fault was given."""

    status: Literal["solved"]
    object: str
    fault_priors: str | None = Field(description="Where the catalog's priors come from: 'illustrative' or 'measured'.")
    repair_bonus: float = Field(description="The reward for the repair; each action costs 1.")
    faults: dict[str, float] = Field(description="The catalog's fault priors, by part.")
    strategies: dict[str, StrategyOut] = Field(description="model (with a model), uniform and oracle.")
    episode: EpisodeOut | None = None
    model_id: uuid.UUID
    warnings: list[DiagnosticOut]
