"""One participant's way through an experiment: which page they are on, what they may change, their work.

The participant record holds the stage and the position in it (which training or test
object), and ``work``: every draft as typed (step-1 labels per part, the rule box, step-3
choices), the tutorial's answers and, once step 2 is submitted, the frozen model. Pages that
are behind the participant (the training model, once step 3 has begun) cannot be changed.
"""

from __future__ import annotations

import copy
import uuid
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import Any, Protocol, Self

from causalplan.objects.catalog import Catalog
from causalplan.objects.model import AssemblyObject
from causalplan.studies.design import Design
from causalplan.studies.errors import StepLockedError
from causalplan.studies.recruitment import Recruitment
from causalplan.studies.steps import ParticipantModel, Stage, labels_from_text, rules_from_text


def as_utc(moment: datetime) -> datetime:
    """Return ``moment`` timezone-aware (SQLite gives back stored UTC times without their zone)."""
    return moment if moment.tzinfo is not None else moment.replace(tzinfo=UTC)


class StoredExperiment(Protocol):
    """What a journey reads of a stored experiment: its design and recruiting settings, as dicts."""

    @property
    def design(self) -> dict[str, Any]: ...

    @property
    def recruitment(self) -> dict[str, Any] | None: ...


class StoredParticipant(Protocol):
    """What a journey reads and writes of a stored participant (the service's record has all of it)."""

    stage: str
    position: int
    work: dict[str, Any]
    model_id: uuid.UUID | None
    started_at: datetime | None
    updated_at: datetime | None
    finished_at: datetime | None

    @property
    def training_order(self) -> list[str]: ...

    @property
    def test_order(self) -> list[str]: ...

    @property
    def experiment(self) -> StoredExperiment: ...


MAX_PLAN_REQUESTS_KEPT = 50
"""Each 'Show the robot's plan' is logged with the rules of that moment (for research), up to this many."""


@dataclass
class Journey:
    """A participant record with its experiment's design and objects (in the participant's order)."""

    participant: StoredParticipant
    design: Design
    training: tuple[AssemblyObject, ...]
    tests: tuple[AssemblyObject, ...]
    recruitment: Recruitment = field(default_factory=Recruitment)

    @classmethod
    def of(cls, participant: StoredParticipant, catalog: Catalog) -> Self:
        """Return the journey of a stored participant (UnknownObjectError if the catalog lost an object)."""
        design = Design.from_dict(participant.experiment.design)
        return cls(
            participant,
            design,
            tuple(catalog.get(object_id) for object_id in participant.training_order),
            tuple(catalog.get(object_id) for object_id in participant.test_order),
            Recruitment.from_dict(participant.experiment.recruitment),
        )

    # -- where they are ---------------------------------------------------------------------------

    @property
    def stage(self) -> Stage:
        return Stage(self.participant.stage)

    @property
    def position(self) -> int:
        return self.participant.position

    @property
    def goal(self) -> str:
        return self.training[0].goal

    def current_page(self) -> str:
        """Return the path (after ``/p/<code>/``) of the page the participant should be on."""
        if self.stage in (Stage.STEP1, Stage.STEP3):
            return f"{self.stage.value}/{self.position + 1}"
        return self.stage.value

    def may_open(self, stage: Stage, index: int = 0) -> bool:
        """Return whether the page of ``stage`` (object ``index``) is open to the participant now."""
        if stage is Stage.STEP1:
            # Going back to step 1 from step 2 is allowed; once step 3 begins the model is fixed.
            in_range = 0 <= index < len(self.training)
            return in_range and ((self.stage is Stage.STEP1 and index <= self.position) or self.stage is Stage.STEP2)
        if stage is Stage.STEP3:
            return self.stage is Stage.STEP3 and index == self.position
        return self.stage is stage

    def require_open(self, stage: Stage, index: int = 0) -> None:
        """Raise StepLockedError unless the page of ``stage`` (object ``index``) is open."""
        if not self.may_open(stage, index):
            raise StepLockedError(
                "This part of the study is closed: it is finished (the training model cannot change once "
                "step 3 has begun) or not reached yet.",
                details={"stage": self.stage.value, "position": self.position},
            )

    def progress(self) -> str:
        """Return where the participant is, in words (for the researcher)."""
        if self.stage is Stage.STEP1:
            return f"step 1, object {self.position + 1} of {len(self.training)}"
        if self.stage is Stage.STEP3:
            return f"step 3, object {self.position + 1} of {len(self.tests)}"
        return {
            Stage.TUTORIAL: "tutorial",
            Stage.STEP2: "step 2",
            Stage.ABOUT: "demographic questions",
            Stage.DONE: "finished",
            Stage.SCREENED: "screened out",
        }[self.stage]

    # -- their work ---------------------------------------------------------------------------------

    def _saved(self) -> dict[str, Any]:
        """Return the saved work to read (never changed in place: see ``_work``)."""
        return self.participant.work or {}

    def _work(self) -> dict[str, Any]:
        """Return a copy of the saved work to change and ``_save``."""
        return copy.deepcopy(self._saved())

    def _save(self, work: dict[str, Any]) -> None:
        # A new dict, so SQLAlchemy sees the JSON column change.
        self.participant.work = work
        self._touch()

    def _touch(self) -> None:
        now = datetime.now(UTC)
        self.participant.updated_at = now
        if self.participant.started_at is None:
            self.participant.started_at = now

    def tutorial_work(self) -> dict[str, Any]:
        tutorial: dict[str, Any] = self._saved().get("tutorial", {})
        return tutorial

    def save_tutorial(self, rules: str | None = None, answers: dict[str, str] | None = None) -> None:
        work = self._work()
        tutorial = work.setdefault("tutorial", {})
        if rules is not None:
            tutorial["rules"] = rules
        if answers is not None:
            tutorial["answers"] = answers
        self._save(work)

    def record_tutorial_try(self, answers: dict[str, str], all_correct: bool) -> int:
        """Store one try of the comprehension check (answers, all right or not); return the number of tries."""
        work = self._work()
        tutorial = work.setdefault("tutorial", {})
        tries = tutorial.setdefault("tries", [])
        tries.append({"at": datetime.now(UTC).isoformat(), "answers": answers, "all_correct": all_correct})
        if all_correct:
            tutorial.setdefault("passed_on_try", len(tries))
        self._save(work)
        return len(tries)

    def has_passed_comprehension(self) -> bool:
        return "passed_on_try" in self.tutorial_work()

    def step_seconds(self) -> list[dict[str, Any]]:
        """Return the time spent on each page left so far: ``[{"step": "step1/1", "seconds": 41.2}, ...]``."""
        times: list[dict[str, Any]] = self._saved().get("step_seconds", [])
        return times

    def seconds_taken(self) -> float | None:
        """Return the seconds from the start to the end of the study (None before both)."""
        start, end = self.participant.started_at, self.participant.finished_at
        return (as_utc(end) - as_utc(start)).total_seconds() if start is not None and end is not None else None

    def function_texts(self, object_id: str) -> dict[str, str]:
        """Return the step-1 boxes of a training object as typed (part id -> text)."""
        texts: dict[str, str] = self._saved().get("functions", {}).get(object_id, {})
        return texts

    def save_functions(self, object_id: str, texts: dict[str, str]) -> None:
        work = self._work()
        work.setdefault("functions", {})[object_id] = texts
        self._save(work)

    def rules_text(self) -> str:
        return str(self._saved().get("rules", ""))

    def save_rules(self, text: str) -> None:
        work = self._work()
        work["rules"] = text
        self._save(work)

    def draft_model(self, rules_text: str | None = None) -> ParticipantModel:
        """Return the model as it stands in the step-1 boxes and ``rules_text`` (default: the step-2 box)."""
        functions = {
            obj.id: {
                part: labels
                for part, text in self.function_texts(obj.id).items()
                if part in obj.part_ids and (labels := labels_from_text(text))
            }
            for obj in self.training
        }
        rules, _ = rules_from_text(self.rules_text() if rules_text is None else rules_text)
        return ParticipantModel(self.goal, functions, tuple(rules))

    def submitted_model(self) -> ParticipantModel | None:
        """Return the model submitted in step 2 (None before)."""
        data = self._saved().get("model")
        return ParticipantModel.from_dict(data) if data else None

    def mapping_entries(self, object_id: str) -> dict[str, dict[str, Any]]:
        """Return the step-3 choices for a test object as saved (part id -> chosen labels and new lines)."""
        entries: dict[str, dict[str, Any]] = self._saved().get("mappings", {}).get(object_id, {})
        return entries

    def save_mapping(self, object_id: str, entries: dict[str, dict[str, Any]]) -> None:
        work = self._work()
        work.setdefault("mappings", {})[object_id] = entries
        self._save(work)

    def log_plan_request(self, at: datetime, rules: tuple[str, ...] | None = None) -> None:
        """Remember that the participant asked for the robot's plan, with the rules planned (default: the draft's)."""
        work = self._work()
        log = work.setdefault("plan_requests", [])
        log.append({"at": at.isoformat(), "rules": list(self.draft_model().rules if rules is None else rules)})
        work["plan_requests"] = log[-MAX_PLAN_REQUESTS_KEPT:]
        self._save(work)

    def draft_revision(self, key: str) -> int:
        """Return the revision of the draft ``key`` last saved (0: none saved with one).

        A page stamps each save of one box or group of boxes (``step1:desk_lamp``, ``step2:rules``)
        with a revision that only grows; a save older than the one stored (a request overtaken
        by a newer one, an old form posted again) must not overwrite newer text.
        """
        revisions: dict[str, int] = self._saved().get("revisions", {})
        return int(revisions.get(key, 0))

    def accept_revision(self, key: str, revision: int | None) -> bool:
        """Return whether a save of draft ``key`` stamped ``revision`` is the newest, and keep its revision.

        ``None`` (a form posted without the page's script) is always accepted and keeps the stored
        revision, so a later save of the script still counts as newer.
        """
        if revision is None:
            return True
        if revision < self.draft_revision(key):
            return False
        work = self._work()
        work.setdefault("revisions", {})[key] = revision
        self._save(work)
        return True

    # -- moving on ----------------------------------------------------------------------------------

    def finish_tutorial(self) -> None:
        self.require_open(Stage.TUTORIAL)
        self._move(Stage.STEP1, 0)

    def finish_functions(self, index: int) -> None:
        """Move on from step 1 of training object ``index``: to the next object, or to step 2."""
        self.require_open(Stage.STEP1, index)
        if self.stage is Stage.STEP2:
            return  # they came back to change labels; step 2 is where they go next
        if index + 1 < len(self.training):
            self._move(Stage.STEP1, max(self.position, index + 1))
        else:
            self._move(Stage.STEP2, 0)

    def finish_model(self, model: ParticipantModel, model_id: uuid.UUID) -> None:
        """Freeze the model submitted in step 2 and begin step 3."""
        self.require_open(Stage.STEP2)
        work = self._work()
        work["model"] = model.as_dict()
        self._save(work)
        self.participant.model_id = model_id
        self._move(Stage.STEP3, 0)

    def finish_test(self, index: int) -> None:
        """Move on from step 3 of test object ``index``: to the next test object, or to the end."""
        self.require_open(Stage.STEP3, index)
        if index + 1 < len(self.tests):
            self._move(Stage.STEP3, index + 1)
        elif self.recruitment.questions():
            self._move(Stage.ABOUT, 0)
        else:
            self._finish(Stage.DONE)

    def finish_demographics(self, answers: dict[str, str]) -> None:
        """Store the answers to the demographic questions (empty ones left out) and end the study."""
        self.require_open(Stage.ABOUT)
        work = self._work()
        work["demographics"] = {name: answer for name, answer in answers.items() if answer}
        self._save(work)
        self._finish(Stage.DONE)

    def screen_out(self) -> None:
        """End the study here: the participant failed the comprehension check."""
        self._finish(Stage.SCREENED)

    def _finish(self, stage: Stage) -> None:
        self._move(stage, 0)
        self.participant.finished_at = self.participant.updated_at

    def _move(self, stage: Stage, position: int) -> None:
        # The time on the page being left is kept with the work (the export's step_seconds).
        now = datetime.now(UTC)
        work = self._work()
        entered = work.get("entered_at")
        since = as_utc(datetime.fromisoformat(entered) if entered else self.participant.started_at or now)
        work.setdefault("step_seconds", []).append(
            {"step": self.current_page(), "seconds": round(max(0.0, (now - since).total_seconds()), 1)}
        )
        work["entered_at"] = now.isoformat()
        self.participant.work = work
        self.participant.stage = stage.value
        self.participant.position = position
        self._touch()
