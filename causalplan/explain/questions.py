"""The questions a person can ask of a plan, read from a small grammar, checked against the object.

Grammar (case-insensitive; a leading "why not" and a trailing "?" are allowed; PART is a
part's id or name, ``light_bulb`` or ``light bulb``; FIT a fit's id; N a step number)::

    attach PART            why not attach this part (that the plan leaves out)?
    leave out PART         why not do without this part?
    leave out step N       why not skip this step?
    PART before PART       why not attach the first before the second?
    use FIT                why not attach its part through this fit instead?

Every question becomes ``PlanConstraints`` of catalog ids only: what a person typed is
matched against the object's parts and fits and never reaches the PDDL itself.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from enum import StrEnum

from causalplan.causal.labels import closest
from causalplan.errors import CausalPlanError
from causalplan.objects.model import AssemblyObject
from causalplan.pddl.constraints import PlanConstraints
from causalplan.planners.result import PlanStep

MAX_QUESTION_LENGTH = 200
GRAMMAR = 'attach PART | leave out PART | leave out step N | PART before PART | use FIT (e.g. "attach shade")'


class QuestionError(CausalPlanError):
    """A question that does not follow the grammar."""

    code = "invalid_question"


class UnknownPartError(QuestionError):
    """A question names a part the object does not have."""

    code = "unknown_part"


class UnknownFitError(QuestionError):
    """A question names a fit the object does not have."""

    code = "unknown_fit"


class UnknownStepError(QuestionError):
    """A question names a step the plan does not have."""

    code = "unknown_step"


class Kind(StrEnum):
    """What a question asks for."""

    ATTACH = "attach"
    LEAVE_OUT = "leave_out"
    ORDER = "order"
    USE_FIT = "use_fit"


@dataclass(frozen=True)
class Question:
    """A contrastive question in catalog ids: ``parts`` (one, or first and then for an order), or a ``fit``."""

    kind: Kind
    parts: tuple[str, ...]
    fit: str | None = None

    def constraints(self, obj: AssemblyObject) -> PlanConstraints:
        """Return what the alternative plan must do."""
        if self.kind is Kind.ATTACH:
            return PlanConstraints(required_parts=frozenset(self.parts))
        if self.kind is Kind.LEAVE_OUT:
            return PlanConstraints(forbidden_fits=frozenset(f.id for f in obj.fits if f.moving_part in self.parts))
        if self.kind is Kind.ORDER:
            return PlanConstraints(orderings=frozenset({(self.parts[0], self.parts[1])}))
        assert self.fit is not None
        chosen = obj.fit(self.fit)
        others = frozenset(f.id for f in obj.fits if f.moving_part == chosen.moving_part and f.id != chosen.id)
        return PlanConstraints(required_parts=frozenset({chosen.moving_part}), forbidden_fits=others)

    def text(self, obj: AssemblyObject) -> str:
        """Return the question in words, with the parts' names."""
        names = [obj.part(part).name for part in self.parts]
        if self.kind is Kind.ATTACH:
            return f"Why not attach the {names[0]}?"
        if self.kind is Kind.LEAVE_OUT:
            return f"Why not leave out the {names[0]}?"
        if self.kind is Kind.ORDER:
            return f"Why not attach the {names[0]} before the {names[1]}?"
        assert self.fit is not None
        return f"Why not {obj.step_text(obj.fit(self.fit)).rstrip('.').lower()} instead?"

    def as_dict(self) -> dict[str, object]:
        """Return the question as a JSON-ready dict."""
        return {"kind": self.kind.value, "parts": list(self.parts), "fit": self.fit}


_PREFIX = re.compile(r"^\s*why\s+not\s+", re.IGNORECASE)
_STEP = re.compile(r"^step\s+(\d+)$")


def _key(text: str) -> str:
    return re.sub(r"[\s_-]+", "_", text.strip().lower()).strip("_")


def resolve_part(obj: AssemblyObject, text: str) -> str:
    """Return the id of the part ``text`` names (its id or its name); raise ``UnknownPartError``."""
    wanted = _key(text.removeprefix("the ").removeprefix("The "))
    for part in obj.parts:
        if wanted in (_key(part.id), _key(part.name)):
            return part.id
    guess = closest(wanted, list(obj.part_ids))
    hint = f" Did you mean '{guess}'?" if guess else ""
    raise UnknownPartError(
        f"The {obj.name} has no part '{text.strip()}'; its parts are {', '.join(obj.part_ids)}.{hint}",
        details={"part": text.strip()[:MAX_QUESTION_LENGTH], "parts": list(obj.part_ids)},
    )


def _moving_part(obj: AssemblyObject, text: str) -> str:
    part = resolve_part(obj, text)
    if part == obj.base:
        raise QuestionError(
            f"The {obj.part(part).name} is where the assembly starts: no step attaches it.",
            details={"part": part},
        )
    return part


def resolve_step(steps: tuple[PlanStep, ...], number: int) -> PlanStep:
    """Return step ``number`` (from 1) of ``steps``; raise ``UnknownStepError``."""
    if not 1 <= number <= len(steps):
        raise UnknownStepError(
            f"The plan has {len(steps)} step(s); there is no step {number}.",
            details={"step": number, "steps": len(steps)},
        )
    return steps[number - 1]


def parse_question(text: str, obj: AssemblyObject, steps: tuple[PlanStep, ...]) -> Question:
    """Return the question ``text`` asks of the plan ``steps`` on ``obj``; raise a ``QuestionError`` if none."""
    if len(text) > MAX_QUESTION_LENGTH:
        raise QuestionError(f"A question has at most {MAX_QUESTION_LENGTH} characters; this one has {len(text)}.")
    body = " ".join(_PREFIX.sub("", text).strip().rstrip("?").split())
    lowered = body.lower()
    if lowered.startswith("attach "):
        return Question(Kind.ATTACH, (_moving_part(obj, body[7:]),))
    if lowered.startswith("leave out "):
        rest = lowered[10:].strip()
        step = _STEP.match(rest)
        if step:
            return Question(Kind.LEAVE_OUT, (resolve_step(steps, int(step.group(1))).args[0],))
        return Question(Kind.LEAVE_OUT, (_moving_part(obj, body[10:]),))
    if lowered.startswith("use "):
        name = body[4:].strip()
        name = name[4:] if name.lower().startswith("fit ") else name
        fits = {fit.id: fit for fit in obj.fits}
        if name not in fits:
            guess = closest(name, list(fits))
            hint = f" Did you mean '{guess}'?" if guess else ""
            raise UnknownFitError(
                f"The {obj.name} has no fit '{name}'; its fits are {', '.join(fits)}.{hint}",
                details={"fit": name[:MAX_QUESTION_LENGTH], "fits": list(fits)},
            )
        return Question(Kind.USE_FIT, (fits[name].moving_part,), name)
    halves = re.split(r"\s+before\s+", body, flags=re.IGNORECASE)
    if len(halves) == 2:
        first, then = _moving_part(obj, halves[0]), _moving_part(obj, halves[1])
        if first == then:
            raise QuestionError(f"'{body}' names the same part twice.", details={"part": first})
        return Question(Kind.ORDER, (first, then))
    raise QuestionError(
        f"Cannot read the question '{body[:MAX_QUESTION_LENGTH]}'; ask one of: {GRAMMAR}.",
        details={"grammar": GRAMMAR},
    )
