"""What the experiment API and the pages' small JSON endpoints send and receive (``*In`` / ``*Out``)."""

from __future__ import annotations

import uuid
from typing import Annotated, Any, Literal

from pydantic import ConfigDict, Field, StrictBool

from causalplan.service.api.schemas.common import DiagnosticOut, InputModel, OutputModel, UtcDatetime
from causalplan.studies.recruitment import DEFAULT_PLACES_PER_CLIENT

ObjectId = Annotated[str, Field(min_length=1, max_length=200)]
MAX_RULES_TEXT = 200_000
MAX_PART_TEXT = 10_000


# -- experiments (researchers, bearer token) --------------------------------------------------------


class StrictInputModel(InputModel):
    """A research route's body: JSON types as declared (no 0 for a boolean, no "5" for a number)."""

    model_config = ConfigDict(extra="forbid", strict=True)


class ConditionIn(StrictInputModel):
    name: str = Field(min_length=1, max_length=100, description="e.g. 'near' or 'far'.", examples=["near"])
    training: list[ObjectId] = Field(
        min_length=1, max_length=2, description="Catalog ids of the training objects: one, or two one model explains."
    )
    tests: list[ObjectId] = Field(min_length=1, max_length=8, description="Catalog ids of the test objects (new ones).")


class ExperimentIn(StrictInputModel):
    """POST /v1/experiments: a new experiment."""

    name: str = Field(min_length=1, max_length=200)
    description: str = Field(default="", max_length=2000)
    conditions: list[ConditionIn] = Field(default_factory=list, max_length=8)
    template: Literal["far_generalization"] | None = Field(
        default=None,
        description="'far_generalization': the paper's far-generalization experiment, made from the catalog; "
        "given conditions are checked against the paper's design instead.",
    )
    counterbalance_training: bool = Field(default=True, description="Order the training objects by a Latin square.")
    counterbalance_tests: bool = Field(default=True, description="Order the test objects by a Latin square.")
    show_verdict: bool = Field(default=True, description="Show participants whether their model transferred.")
    tutorial: bool = Field(default=True, description="Begin with the toy-car tutorial.")
    robot_verdict: bool = Field(
        default=False,
        description="A transfer also needs the robot (Franka Panda) to carry out the plan; a plan it cannot "
        "carry out fails with robot_cannot_execute.",
    )

    model_config = ConfigDict(
        extra="forbid",
        strict=True,
        json_schema_extra={
            "examples": [
                {
                    "name": "Near and far generalization",
                    "conditions": [
                        {"name": "near", "training": ["desk_lamp", "flashlight"], "tests": ["candle"]},
                        {"name": "far", "training": ["desk_lamp", "candle"], "tests": ["flashlight"]},
                    ],
                }
            ]
        },
    )


class RecruitmentIn(StrictInputModel):
    """PUT /v1/experiments/{id}/recruitment: how the public link recruits (every field optional)."""

    consent_text: str = Field(
        default="", max_length=10_000, description="Shown before anything is stored; '' : the default text."
    )
    completion_code: str = Field(default="", max_length=32, description="Prolific completion code of those who finish.")
    screened_out_code: str = Field(default="", max_length=32, description="Code of those screened out (or '').")
    no_consent_code: str = Field(default="", max_length=32, description="Code of those who decline consent (or '').")
    comprehension_tries: int | None = Field(
        default=None, description="Screen out who has not answered all tutorial questions right within this many tries."
    )
    too_fast_seconds: int | None = Field(default=None, description="Flag as excluded who finishes faster than this.")
    demographics: list[str] = Field(default=[], max_length=10, description="Ids of the demographic questions to ask.")
    require_platform_id: StrictBool = Field(
        default=False,
        description="Refuse arrivals without a crowd platform's ids (Prolific's PID and session, MTurk's worker).",
    )
    places_per_client: int | None = Field(
        default=DEFAULT_PLACES_PER_CLIENT,
        description="Places one client address may hold admitted but not started (null: no limit); "
        "more consents from it are asked to try again later.",
    )
    quotas: dict[str, int | None] = Field(
        default={}, description="Condition name -> most participants on the public link (null: no limit)."
    )


class RecruitmentOut(OutputModel):
    """An experiment's recruiting settings, its public link, and the places per condition."""

    consent_text: str
    completion_code: str
    screened_out_code: str
    no_consent_code: str
    comprehension_tries: int | None
    too_fast_seconds: int | None
    demographics: list[str]
    require_platform_id: bool
    places_per_client: int | None
    public_link: str
    places: list[dict[str, Any]] = Field(
        description="Per condition: places held (taken), completions (finished), the quota, how many more than "
        "the quota may be at work at once (extra), and admissions so far (admitted)."
    )
    arrivals: dict[str, int] = Field(description="Arrived on the public link: in all, consented, declined, undecided.")


class ConditionOut(OutputModel):
    name: str
    training: list[str]
    tests: list[str]


class ExperimentLinks(OutputModel):
    page: str
    results: str
    participants: str
    export_json: str
    export_csv: str


class ExperimentOut(OutputModel):
    """A stored experiment."""

    id: uuid.UUID
    created_at: UtcDatetime
    name: str
    description: str
    conditions: list[ConditionOut]
    counterbalance_training: bool
    counterbalance_tests: bool
    show_verdict: bool
    tutorial: bool
    robot_verdict: bool
    is_demo: bool
    participants: int
    links: ExperimentLinks


class LinksIn(StrictInputModel):
    """POST /v1/experiments/{id}/participants: make participant links."""

    count: int = Field(ge=1, le=500, description="How many links to make.")
    condition: str | None = Field(
        default=None, max_length=100, description="Put them all in this condition; left out, spread them evenly."
    )


class ParticipantOut(OutputModel):
    """One participant link and how far its participant got."""

    id: uuid.UUID
    code: str
    url: str
    condition: str
    ordinal: int = Field(description="Number within the condition; picks the Latin-square rows.")
    training_order: list[str]
    test_order: list[str]
    stage: Literal["tutorial", "step1", "step2", "step3", "about", "done", "screened"]
    progress: str
    created_at: UtcDatetime
    started_at: UtcDatetime | None
    updated_at: UtcDatetime | None
    finished_at: UtcDatetime | None
    platform: str | None = Field(
        description="prolific, mturk or direct for arrivals on the public link; null for made links."
    )
    exclusion_reason: str | None = Field(
        description="Why the participant is excluded (comprehension, too_fast); null: included."
    )


class ParticipantsOut(OutputModel):
    data: list[ParticipantOut]


class RateOut(OutputModel):
    """One condition on one test object, counted as ``causalplan analyze`` counts: the analysed trials."""

    condition: str
    training_span: str | None = Field(description="'one category' or 'both categories' (null: an object is lost).")
    test_object: str
    generalization: str | None
    trials: int = Field(description="Analysed trials: decided, of participants screening kept.")
    transfers: int
    fails: int = Field(description="Analysed trials whose model did not transfer (fails or invalid).")
    undecided: int = Field(description="Left out: trials the planner could not decide in time.")
    excluded: int = Field(description="Left out: trials of participants excluded by screening.")
    rate: float | None = Field(description="transfers / trials (null without trials).")
    interval: list[float | None] = Field(description="The rate's 95% Wilson interval (nulls without trials).")


class TrialRowOut(OutputModel):
    """One step-3 trial: the participant's model, mapping, verdict and reasons."""

    model_config = ConfigDict(extra="allow")

    trial_id: uuid.UUID
    participant_id: uuid.UUID
    condition: str
    test_object: str
    position: int
    generalization: str | None
    verdict: str
    decided_by: str
    reasons: list[dict[str, Any]]
    plan: list[str | None]
    model: dict[str, Any] | None
    mapping: dict[str, Any]


class ResultsOut(OutputModel):
    """An experiment's results: participants, transfer rates, and every trial."""

    experiment: ExperimentOut
    participants: list[ParticipantOut]
    rates: list[RateOut]
    rates_problem: str | None = Field(description="Why the rates cannot be computed (null: they are).")
    trials: list[TrialRowOut]


class ExperimentExportOut(OutputModel):
    """An experiment's raw data as JSON (what ``causalplan analyze`` reads): every record as stored."""

    exported_at: UtcDatetime
    experiment: dict[str, Any] = Field(description="The experiment's record, its design included.")
    rates: list[RateOut]
    participants: list[dict[str, Any]] = Field(description="Every participant, with all saved work and exclusions.")
    trials: list[dict[str, Any]] = Field(description="Every trial, with its full result.")


# -- the participant pages' endpoints -----------------------------------------------------------------


class TutorialDraftIn(InputModel):
    step: Literal["tutorial"]
    revision: int | None = Field(
        default=None, ge=0, le=2**53, description="The page's stamp of this save; an older one than stored is ignored."
    )
    answers: dict[Annotated[str, Field(max_length=40)], Annotated[str, Field(max_length=40)]] = Field(max_length=10)


class FunctionsDraftIn(InputModel):
    step: Literal["step1"]
    revision: int | None = Field(
        default=None, ge=0, le=2**53, description="The page's stamp of this save; an older one than stored is ignored."
    )
    object: ObjectId
    functions: dict[Annotated[str, Field(max_length=200)], Annotated[str, Field(max_length=MAX_PART_TEXT)]] = Field(
        max_length=64
    )


class MappingEntryIn(InputModel):
    chosen: list[Annotated[str, Field(max_length=200)]] = Field(default_factory=list, max_length=64)
    added: str = Field(default="", max_length=MAX_PART_TEXT)


class MappingDraftIn(InputModel):
    step: Literal["step3"]
    revision: int | None = Field(
        default=None, ge=0, le=2**53, description="The page's stamp of this save; an older one than stored is ignored."
    )
    object: ObjectId
    mapping: dict[Annotated[str, Field(max_length=200)], MappingEntryIn] = Field(max_length=64)


DraftIn = Annotated[TutorialDraftIn | FunctionsDraftIn | MappingDraftIn, Field(discriminator="step")]


class SavedOut(OutputModel):
    saved: bool
    saved_at: UtcDatetime
    revision: int = Field(default=0, description="The revision stored (newer than the one sent if not applied).")
    applied: bool = Field(default=True, description="False: a newer save was already stored; this one changed nothing.")


class CheckIn(InputModel):
    """The rule box as typed: checked like `causalplan check` and saved."""

    rules: str = Field(max_length=MAX_RULES_TEXT)
    practice: bool = Field(default=False, description="The tutorial's practice box (the toy car).")
    revision: int | None = Field(
        default=None, ge=0, le=2**53, description="The page's stamp of this save; an older one than stored is ignored."
    )


class PlanIn(InputModel):
    """The rule box as typed: saved, then planned on each training object."""

    rules: str = Field(max_length=MAX_RULES_TEXT)
    revision: int | None = Field(
        default=None, ge=0, le=2**53, description="The page's stamp of this save; an older one than stored is ignored."
    )


class LineDiagnosticOut(DiagnosticOut):
    line: int | None = Field(description="The line of the rule box it is about (null: the whole model).")


class CheckOut(OutputModel):
    valid: bool
    errors: list[LineDiagnosticOut]
    warnings: list[LineDiagnosticOut]
    graph_url: str | None
    saved_at: UtcDatetime
    revision: int = Field(default=0, description="The revision of the rule box stored.")
    applied: bool = Field(default=True, description="False: newer rules were already stored; these were checked only.")


class PlanForObjectOut(OutputModel):
    object: str
    name: str
    status: str
    steps: list[str]
    message: str
    works: bool = Field(description="Whether the plan makes the real object produce its goal (replayed).")
    picture_url: str | None
    fits: list[str] = Field(description="The fits the plan makes, in order (what 'Watch the robot' films).")
    questions: list[str] = Field(
        default_factory=list, description="Example questions to ask the robot about this plan, in the object's words."
    )


class PlansOut(OutputModel):
    plans: list[PlanForObjectOut]


class FilmIn(InputModel):
    """'Watch the robot': film the robot making these fits of one of the participant's training objects."""

    object: str = Field(max_length=200)
    fits: list[str] = Field(min_length=1, max_length=64)


class FilmOut(OutputModel):
    """A film of the robot being made, or made: what the page shows while it waits, then plays."""

    key: str
    state: Literal["filming", "ready", "failed"]
    frames: int = Field(description="Frames drawn so far.")
    expected_frames: int | None = Field(description="Frames the film has while the robot moves (null: not known yet).")
    seconds: float = Field(description="Seconds since filming began (or that it took).")
    status_url: str
    video_url: str | None = Field(description="Where the film is, once ready.")
    content_type: str
    bytes: int = Field(description="The film's size, once ready (0 before).")
    robot: dict[str, Any] | None = Field(description="Whether the robot carried out the plan, and why not.")
    error: dict[str, str] | None
