"""How an experiment recruits on its public link: consent, completion codes, screening rules, demographics.

Also what a crowd platform puts in the link (Prolific's ``PROLIFIC_PID``, ``STUDY_ID``,
``SESSION_ID``; MTurk's external-question ``assignmentId``, ``hitId``, ``workerId``,
``turkSubmitTo``), read strictly: every value is checked for length and characters, and
``turkSubmitTo`` must be one of MTurk's two hosts, so nothing a link carries can send a
participant or their answers anywhere else. Everything here takes and returns values.
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any
from urllib.parse import urlencode, urlsplit

from causalplan.inputs import clean_text
from causalplan.studies.errors import InvalidRecruitmentError

DEFAULT_CONSENT = (
    "You are invited to take part in a research study about how people explain the way objects work. "
    "You will describe, in simple rules, why a few objects produce light; it takes about 20 minutes. "
    "Your answers are stored without your name and used only for research. Taking part is voluntary: "
    "you may stop at any time without giving a reason."
)
MAX_CONSENT_TEXT = 10_000
CODE_PATTERN = re.compile(r"[A-Za-z0-9]{1,32}")
"""A completion code as Prolific makes them (letters and digits); MTurk needs none."""
MAX_PLATFORM_ID_LENGTH = 64
"""Longest platform id (Prolific's are 24 hex digits, MTurk's about 14 to 30 letters and digits)."""
PLATFORM_ID_PATTERN = re.compile(rf"[A-Za-z0-9_-]{{1,{MAX_PLATFORM_ID_LENGTH}}}")
MTURK_HOSTS = ("www.mturk.com", "workersandbox.mturk.com")
"""The only hosts ``turkSubmitTo`` may name: MTurk's production and sandbox sites."""
MTURK_PREVIEW = "ASSIGNMENT_ID_NOT_AVAILABLE"
"""MTurk's ``assignmentId`` while a worker only previews the HIT."""
PROLIFIC_COMPLETE = "https://app.prolific.com/submissions/complete"
REDIRECT_SECONDS = 5
"""A finished page sends the participant on to Prolific by itself after this long (or at the click)."""
MAX_QUOTA = 100_000
MAX_TOO_FAST_SECONDS = 24 * 3600
MAX_TRIES = 10
DEFAULT_PLACES_PER_CLIENT = 2
"""Places one client address may hold admitted but not started (a household or a lab may share one)."""
MAX_PLACES_PER_CLIENT = 1000


@dataclass(frozen=True)
class DemographicQuestion:
    """One optional question at the end of the study: free number, or one of the choices."""

    id: str
    text: str
    choices: tuple[str, ...] = ()
    """Empty: a whole number (``low`` to ``high``)."""
    low: int = 0
    high: int = 0


DEMOGRAPHICS = {
    question.id: question
    for question in (
        DemographicQuestion("age", "How old are you (in years)?", low=16, high=120),
        DemographicQuestion("gender", "What is your gender?", ("woman", "man", "non-binary", "prefer not to say")),
        DemographicQuestion(
            "education",
            "What is the highest level of education you have completed?",
            ("secondary school", "vocational training", "bachelor's degree", "master's degree or higher", "other"),
        ),
        DemographicQuestion(
            "engineering",
            "Have you studied or worked in engineering, physics or electronics?",
            ("yes", "no", "prefer not to say"),
        ),
    )
}
"""The demographic questions an experiment may ask (each is optional for the participant)."""


@dataclass(frozen=True)
class Recruitment:
    """An experiment's recruiting settings (stored as ``ExperimentRecord.recruitment``)."""

    consent_text: str = DEFAULT_CONSENT
    completion_code: str = ""
    """Prolific completion code of those who finish ('' : no redirect to Prolific)."""
    screened_out_code: str = ""
    """Code of those screened out by the comprehension check ('' : none)."""
    no_consent_code: str = ""
    """Code of those who decline consent ('' : none)."""
    comprehension_tries: int | None = None
    """Screen out who has not answered every tutorial question right within this many tries (None: never)."""
    too_fast_seconds: int | None = None
    """Flag as excluded who finishes in fewer seconds than this (None: never)."""
    demographics: tuple[str, ...] = field(default=())
    """Ids of ``DEMOGRAPHICS`` asked at the end, in this order."""
    require_platform_id: bool = False
    """Refuse arrivals without a platform's ids (Prolific's PID and session, MTurk's worker and assignment)."""
    places_per_client: int | None = DEFAULT_PLACES_PER_CLIENT
    """Places one client address may hold admitted but not started (None: no limit); more consents from
    it are asked to try again later, so a bot looping from one address cannot keep the study full."""

    def as_dict(self) -> dict[str, Any]:
        return {**vars(self), "demographics": list(self.demographics)}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any] | None) -> Recruitment:
        """Return the settings stored by ``as_dict`` (None: the defaults)."""
        if not data:
            return cls()
        return cls(
            str(data.get("consent_text", DEFAULT_CONSENT)),
            str(data.get("completion_code", "")),
            str(data.get("screened_out_code", "")),
            str(data.get("no_consent_code", "")),
            data.get("comprehension_tries"),
            data.get("too_fast_seconds"),
            tuple(data.get("demographics", ())),
            bool(data.get("require_platform_id", False)),
            data.get("places_per_client", DEFAULT_PLACES_PER_CLIENT),
        )

    def questions(self) -> list[DemographicQuestion]:
        return [DEMOGRAPHICS[name] for name in self.demographics if name in DEMOGRAPHICS]


def _bounded(value: int | None, low: int, high: int, what: str, problems: list[str]) -> None:
    if value is not None and not low <= value <= high:
        problems.append(f"{what} must be between {low} and {high}, not {value}.")


def read_recruitment(values: Mapping[str, Any]) -> Recruitment:
    """Return checked recruiting settings; InvalidRecruitmentError lists every problem (``details['errors']``)."""
    problems: list[str] = []
    consent = clean_text(str(values.get("consent_text") or "")).strip() or DEFAULT_CONSENT
    if len(consent) > MAX_CONSENT_TEXT:
        problems.append(f"The consent text is {len(consent)} characters long; the limit is {MAX_CONSENT_TEXT}.")
    codes = {}
    for name, words in (
        ("completion_code", "completion code"),
        ("screened_out_code", "screened-out code"),
        ("no_consent_code", "no-consent code"),
    ):
        code = str(values.get(name) or "").strip()
        if code and not CODE_PATTERN.fullmatch(code):
            problems.append(f"The {words} must be 1 to 32 letters and digits.")
        codes[name] = code
    tries, too_fast = values.get("comprehension_tries"), values.get("too_fast_seconds")
    _bounded(tries, 1, MAX_TRIES, "The number of tries of the comprehension check", problems)
    _bounded(too_fast, 1, MAX_TOO_FAST_SECONDS, "The too-fast threshold (seconds)", problems)
    per_client = values.get("places_per_client", DEFAULT_PLACES_PER_CLIENT)
    _bounded(per_client, 1, MAX_PLACES_PER_CLIENT, "The places one client address may hold", problems)
    demographics = tuple(dict.fromkeys(str(name) for name in values.get("demographics") or ()))
    unknown = [name for name in demographics if name not in DEMOGRAPHICS]
    if unknown:
        problems.append(f"There is no demographic question '{unknown[0]}'; choose from {', '.join(DEMOGRAPHICS)}.")
    if problems:
        raise InvalidRecruitmentError(
            "The recruiting settings are not valid: " + " ".join(problems), details={"errors": problems}
        )
    return Recruitment(
        consent,
        **codes,
        comprehension_tries=tries,
        too_fast_seconds=too_fast,
        demographics=demographics,
        require_platform_id=bool(values.get("require_platform_id", False)),
        places_per_client=per_client,
    )


def read_quotas(values: Mapping[str, int | None], conditions: list[str]) -> dict[str, int | None]:
    """Return a quota (or None: no limit) per condition; an error for an unknown condition or a bad number."""
    unknown = sorted(set(values) - set(conditions))
    if unknown:
        raise InvalidRecruitmentError(
            f"The experiment has no condition '{unknown[0]}'; its conditions are: {', '.join(conditions)}.",
            details={"condition": unknown[0]},
        )
    problems: list[str] = []
    for name, quota in values.items():
        _bounded(quota, 0, MAX_QUOTA, f"The quota of condition '{name}'", problems)
    if problems:
        raise InvalidRecruitmentError(" ".join(problems), details={"errors": problems})
    return {name: values.get(name) for name in conditions}


@dataclass(frozen=True)
class PlatformVisit:
    """Who a crowd platform says arrived: the platform, its ids, and where MTurk wants the answer posted."""

    platform: str
    """``prolific``, ``mturk`` or ``direct`` (no platform ids in the link)."""
    participant: str | None = None
    study: str | None = None
    session: str | None = None
    submit_to: str | None = None
    is_preview: bool = False
    """MTurk shows the HIT before the worker accepts it: nothing may be stored then."""


PROLIFIC_PARAMETERS = ("PROLIFIC_PID", "STUDY_ID", "SESSION_ID")
MTURK_PARAMETERS = ("workerId", "hitId", "assignmentId", "turkSubmitTo")


def _platform_id(parameters: Mapping[str, str], name: str) -> str:
    value = parameters.get(name, "")
    if not PLATFORM_ID_PATTERN.fullmatch(value):
        # The value itself is never repeated back: it may be anything a link was made to carry.
        raise InvalidRecruitmentError(
            f"The link's '{name}' must be 1 to {MAX_PLATFORM_ID_LENGTH} letters, digits, '-' or '_'. "
            "Open the study again from the platform's page.",
            details={"parameter": name},
        )
    return value


def mturk_host(value: str) -> str:
    """Return ``turkSubmitTo`` as a clean origin; InvalidRecruitmentError unless it is one of MTurk's two hosts."""
    parts = urlsplit(value) if len(value) <= 64 else None
    if (
        parts is None
        or parts.scheme != "https"
        or parts.hostname not in MTURK_HOSTS
        or parts.netloc != parts.hostname
        or parts.path not in ("", "/")
        or parts.query
        or parts.fragment
    ):
        raise InvalidRecruitmentError(
            f"The link's 'turkSubmitTo' must be https://{MTURK_HOSTS[0]} or https://{MTURK_HOSTS[1]}.",
            details={"parameter": "turkSubmitTo"},
        )
    return f"https://{parts.hostname}"


def read_visit(parameters: Mapping[str, str]) -> PlatformVisit:
    """Return who arrived according to the link's query; InvalidRecruitmentError names the first bad parameter."""
    if any(name in parameters for name in PROLIFIC_PARAMETERS):
        pid, study, session = (_platform_id(parameters, name) for name in PROLIFIC_PARAMETERS)
        return PlatformVisit("prolific", pid, study, session)
    if any(name in parameters for name in MTURK_PARAMETERS):
        if parameters.get("assignmentId") == MTURK_PREVIEW:
            return PlatformVisit("mturk", is_preview=True)
        worker, hit, assignment = (_platform_id(parameters, name) for name in MTURK_PARAMETERS[:3])
        return PlatformVisit("mturk", worker, hit, assignment, mturk_host(parameters.get("turkSubmitTo", "")))
    return PlatformVisit("direct")


def prolific_url(code: str) -> str:
    """Return where Prolific records a submission with completion ``code``."""
    return f"{PROLIFIC_COMPLETE}?{urlencode({'cc': code})}"


def mturk_submit_url(submit_to: str) -> str:
    """Return where an MTurk external question posts its answer (``submit_to`` checked by ``mturk_host``)."""
    return f"{mturk_host(submit_to)}/mturk/externalSubmit"


MTURK_FRAME_ORIGINS = ("https://worker.mturk.com", "https://www.mturk.com", "https://workersandbox.mturk.com")
"""Where MTurk shows an external question in a frame (the worker sites, production and sandbox)."""


@dataclass(frozen=True)
class Finish:
    """Where a participant goes when the study ends: a link to Prolific, or a form posted to MTurk."""

    platform: str
    url: str
    fields: tuple[tuple[str, str], ...] = ()
    """For MTurk: the form's hidden fields (the assignment id, and how the study ended)."""

    @property
    def origin(self) -> str:
        parts = urlsplit(self.url)
        return f"{parts.scheme}://{parts.netloc}"


def finish(platform: str, assignment: str | None, submit_to: str | None, code: str, outcome: str) -> Finish | None:
    """Return how the study hands the participant back to their platform (None: it does not).

    ``code`` is the experiment's code for this ``outcome`` (completed, screened_out or no_consent).
    """
    if platform == "prolific" and code:
        return Finish(platform, prolific_url(code))
    if platform == "mturk" and assignment and submit_to:
        return Finish(platform, mturk_submit_url(submit_to), (("assignmentId", assignment), ("outcome", outcome)))
    return None


def platform_id_view(value: str | None, experiment_id: str, view: str) -> str | None:
    """Return a platform id as an export shows it: as stored, hashed, or left out.

    The hash is SHA-256 of the experiment's id and the platform id: the same person has the same
    hash throughout one experiment's exports (to join tables) but a different one in another.
    """
    if value is None or view == "omit":
        return None
    if view == "hashed":
        return hashlib.sha256(f"{experiment_id}:{value}".encode()).hexdigest()
    return value
