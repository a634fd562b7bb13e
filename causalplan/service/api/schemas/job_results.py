"""What a job that has succeeded answers in its ``result``, by kind (a simulation's and a film's: ``simulations``).

The service hands a result back as it was stored (``JobOut.result`` skips validation); these
models declare its shape for clients and for the schema tests that check real answers against it.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field

from causalplan.service.api.schemas.common import OutputModel


class BatchRowOut(OutputModel):
    """One trial of a batch, as a row of ``causalplan batch``'s CSV."""

    id: str
    verdict: Literal["transfers", "fails", "invalid", "undecided"]
    training_object: str | None
    test_object: str | None
    generalization: str | None
    decided_by: str
    reasons: str = Field(description="The reasons' codes, joined by ';'.")
    plan_length: int | str = Field(description="Steps of the plan; '' without a plan (a CSV row's empty cell).")
    seconds: float


class BatchResultOut(OutputModel):
    """A ``batch`` job's result: how many trials, the count of each verdict, and a row per trial."""

    trials: int
    verdicts: dict[str, int]
    repeated_ids: dict[str, int] = Field(
        default_factory=dict,
        description="Ids that several trials of a JSON Lines upload share, with how many (the first 100): their "
        "results are told apart by their place, the upload's order.",
    )
    results: list[BatchRowOut]


class ConsensusResultOut(OutputModel):
    """A ``consensus`` job's result: ``causalplan consensus``'s report.json."""

    training_object: str | None
    participants: int
    left_out: dict[str, str] = Field(description="Participants left out of the consensus, and why.")
    min_support: float
    consensus_valid: bool
    consensus_problems: list[str]
    rules: list[dict[str, Any]] = Field(description="Every rule of the crowd, its support and whether it entered.")
    clusters: list[dict[str, Any]] = Field(description="The function labels the crowd used, clustered.")
    mappings: dict[str, dict[str, Any]] = Field(description="By test object: the consensus mapping and its support.")
    individual_verdicts: list[dict[str, Any]]
    individual_transfer_rate: float | None
    individual_transfer_rates: dict[str, float | None]
    consensus_verdict: dict[str, dict[str, Any]] = Field(description="By test object: the consensus model's verdict.")


class FitEstimateOut(OutputModel):
    id: str
    trials: int
    successes: int
    probability: float
    interval: list[float] = Field(min_length=2, max_length=2, description="The 95% Wilson score interval.")
    failures: dict[str, int] = Field(description="Failed insertions by failure code.")


class NoiseOut(OutputModel):
    mm: float
    deg: float


class FitEstimationResultOut(OutputModel):
    """A ``fit_estimation`` job's result: ``causalplan estimate-fits --json``, and the catalog overlay."""

    object: str
    noise: NoiseOut
    seed: int
    fits: list[FitEstimateOut]
    overlay: dict[str, Any] = Field(description="The catalog overlay `causalplan estimate-fits --out` writes.")
