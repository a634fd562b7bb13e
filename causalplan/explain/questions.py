"""The questions a person can ask of a plan, read from a small grammar or plain words, checked against the object.

Grammar (case-insensitive; a leading "why not" and a trailing "?" are allowed; PART is a
part's id or name, ``light_bulb`` or ``light bulb``; FIT a fit's id; N a step number)::

    attach PART            why not attach this part (that the plan leaves out)?
    leave out PART         why not do without this part?
    leave out step N       why not skip this step?
    PART before PART       why not attach the first before the second?
    use FIT                why not attach its part through this fit instead?

Plain questions are read too: the parts they name (by display name, id, or a word of the name
no other part has, such as "the base" or "the bulb") and their question words: "why not put
the shade on first?", "why not leave out the base?", "what if the bulb went in last?". A
question read neither way is refused with the closest questions that can be answered
(``details["suggestions"]``), in the object's own words.

Every question becomes ``PlanConstraints`` of catalog ids only: what a person typed is
matched against the object's parts and fits and never reaches the PDDL itself.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Sequence
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
    mentioned = mentioned_parts(obj, text)
    if len(mentioned) == 1:
        return mentioned[0]
    names = [part.name for part in obj.parts]
    guess = closest(text.strip().lower().removeprefix("the "), names)
    hint = f" Did you mean the {guess}?" if guess else ""
    raise UnknownPartError(
        f"The {obj.name} has no part '{text.strip()}'; its parts are the {', the '.join(names)}.{hint}",
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
    """Return the question ``text`` asks of the plan ``steps`` on ``obj``; raise a ``QuestionError`` if none.

    Every refusal carries ``details["suggestions"]``: the closest questions that can be answered.
    """
    try:
        return _read_question(text, obj, steps)
    except QuestionError as exc:
        if "suggestions" not in exc.details:  # an unreadable question's refusal has found them already
            exc.details["suggestions"] = suggested_questions(obj, steps, text[:MAX_QUESTION_LENGTH])
        raise


def _read_question(text: str, obj: AssemblyObject, steps: tuple[PlanStep, ...]) -> Question:
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
        return Question(Kind.LEAVE_OUT, (resolve_part(obj, body[10:]),))
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
    plain = _plain_question(body, obj, steps)
    if plain is not None:
        return plain
    suggestions = suggested_questions(obj, steps, text)
    raise QuestionError(
        f"The robot did not understand '{body[:MAX_QUESTION_LENGTH]}'. "
        + (f"It can answer, for example: {' '.join(suggestions)}" if suggestions else f"Ask one of: {GRAMMAR}."),
        details={"grammar": GRAMMAR, "suggestions": suggestions},
    )


# -- plain questions ------------------------------------------------------------------------------------

_STOP_WORDS = frozenset({"a", "an", "the", "and", "of", "with", "to", "in", "on", "for", "its", "it"})
_LEAVE_OUT = re.compile(
    r"\b(leave|leaving|left|without|skip|skipping|omit|omitting|remove|removing|drop|dropping|no|not use|"
    r"don'?t use|do without)\b"
)
_FIRST = re.compile(r"\b(first|start|beginning|begin with|earlier)\b")
_LAST = re.compile(r"\b(last|end|finally|later)\b")
_ATTACH = re.compile(
    r"\b(put|putting|attach|attaching|add|adding|fit|fitting|screw|screwing|insert|inserting|mount|place|clip|"
    r"use|using|go|goes|went|going|install|include|connect|on|in|into|onto)\b"
)
_PLAIN_STEP = re.compile(r"\bstep\s+(\d+)\b")
_PLAIN_PREFIX = re.compile(
    r"^\s*(why\s+not|what\s+if|why\s+don'?t\s+(you|we|it|the\s+robot)|how\s+about|could\s+(you|it|the\s+robot)"
    r"|can\s+(you|it|the\s+robot)|why)\s+",
    re.IGNORECASE,
)


def _words(text: str) -> list[str]:
    return re.findall(r"[a-z0-9']+", text.lower().replace("_", " "))


def _forms(phrase: str) -> set[str]:
    """Return a phrase with its last word singular and plural (batteries/battery, shade/shades)."""
    words = phrase.split()
    if not words:
        return set()
    *head, last = words
    forms = {last, last + "s"}
    if last.endswith("ies"):
        forms.add(last[:-3] + "y")
    elif last.endswith("s"):
        forms.add(last[:-1])
    if last.endswith("y"):
        forms.add(last[:-1] + "ies")
    return {" ".join([*head, form]) for form in forms}


def part_aliases(obj: AssemblyObject) -> dict[str, str]:
    """Return every phrase that names a part of ``obj`` (lower case) and the part's id.

    A part is named by its display name, its id written as words, and each word of its name
    that no other part's name has ("base" for the base with cables), each singular or plural.
    The object's goal ("light") names no part.
    """
    aliases: dict[str, str] = {}
    owners: dict[str, set[str]] = {}
    for part in obj.parts:
        for phrase in (part.name.lower(), part.id.replace("_", " ").lower()):
            for form in _forms(" ".join(_words(phrase))):
                aliases[form] = part.id
        for word in _words(part.name):
            if word not in _STOP_WORDS and word != obj.goal.lower():
                owners.setdefault(word, set()).add(part.id)
    for word, parts in owners.items():
        if len(parts) == 1:
            for form in _forms(word):
                aliases.setdefault(form, next(iter(parts)))
    return aliases


def mentioned_parts(obj: AssemblyObject, text: str) -> list[str]:
    """Return the parts ``text`` names, in the order it names them (longest phrases first, no repeats)."""
    aliases = part_aliases(obj)
    longest = max((len(alias.split()) for alias in aliases), default=1)
    words = _words(text)
    found: list[str] = []
    position = 0
    while position < len(words):
        for size in range(min(longest, len(words) - position), 0, -1):
            part = aliases.get(" ".join(words[position : position + size]))
            if part is not None:
                if part not in found:
                    found.append(part)
                position += size
                break
        else:
            position += 1
    return found


def _attached(steps: Sequence[PlanStep]) -> list[str]:
    return [step.args[0] for step in steps]


def _plain_question(body: str, obj: AssemblyObject, steps: tuple[PlanStep, ...]) -> Question | None:
    """Return the question plain words ask (parts by name, and the question's words), or None."""
    text = " ".join(_PLAIN_PREFIX.sub("", body).lower().split())
    parts = mentioned_parts(obj, text)
    step = _PLAIN_STEP.search(text)
    if _LEAVE_OUT.search(text):
        if step is not None:
            return Question(Kind.LEAVE_OUT, (resolve_step(steps, int(step.group(1))).args[0],))
        return Question(Kind.LEAVE_OUT, (parts[0],)) if len(parts) == 1 else None
    movable = [part for part in parts if part != obj.base]
    if len(movable) == 2 and re.search(r"\b(before|then)\b", text):
        return Question(Kind.ORDER, (movable[0], movable[1]))
    if len(movable) == 2 and re.search(r"\bafter\b", text):
        return Question(Kind.ORDER, (movable[1], movable[0]))
    if len(movable) != 1:
        return None
    (part,) = movable
    others = [other for other in _attached(steps) if other != part]
    if _FIRST.search(text):
        return Question(Kind.ORDER, (part, others[0])) if others else Question(Kind.ATTACH, (part,))
    if _LAST.search(text):
        return Question(Kind.ORDER, (others[-1], part)) if others else Question(Kind.ATTACH, (part,))
    return Question(Kind.ATTACH, (part,)) if _ATTACH.search(text) else None


def answerable_questions(obj: AssemblyObject, steps: Sequence[PlanStep]) -> list[str]:
    """Return plain questions about the plan ``steps`` on ``obj`` that can be answered, in the object's words."""
    attached = _attached(steps)
    questions = [f"Why not leave out the {obj.part(part).name}?" for part in attached]
    for part in obj.parts:
        if part.id == obj.base:
            continue
        if part.id not in attached:
            questions.append(f"Why not put the {part.name} on?")
        questions.append(f"What if the {part.name} went on first?")
        questions.append(f"What if the {part.name} went on last?")
    questions.append(f"Why not leave out the {obj.part(obj.base).name}?")
    return list(dict.fromkeys(questions))


def example_questions(obj: AssemblyObject, steps: Sequence[PlanStep], count: int = 3) -> list[str]:
    """Return a few questions to show as examples beside the plan: about parts left out, in it, and order."""
    attached = _attached(steps)
    left_out = [part.name for part in obj.parts if part.id not in attached and part.id != obj.base]
    examples = [f"Why not put the {left_out[0]} on first?"] if left_out else []
    examples += [f"Why not leave out the {obj.part(part).name}?" for part in attached[:1]]
    examples += [f"What if the {obj.part(part).name} went on last?" for part in attached[:1]]
    if len(examples) < count:
        examples.append(f"Why not leave out the {obj.part(obj.base).name}?")
    return examples[:count]


def suggested_questions(obj: AssemblyObject, steps: Sequence[PlanStep], text: str, count: int = 3) -> list[str]:
    """Return the answerable questions closest to ``text``: about the parts it names first, then by wording."""
    named = {obj.part(part).name for part in mentioned_parts(obj, text)}
    asked = " ".join(_words(text))

    def closeness(question: str) -> tuple[bool, float]:
        about_named = any(f"the {name}" in question for name in named)
        return about_named, difflib.SequenceMatcher(None, asked, question.lower()).ratio()

    return sorted(answerable_questions(obj, steps), key=closeness, reverse=True)[:count]
