"""The tutorial: the wind-up toy car (goal: motion), its functions, and three questions.

It teaches the keywords (AND joins causes that are all needed; several rules with the same
effect are alternatives) and the difference the paper's participants tripped on: functions
that cause the goal and functions that do not ("hold things together", "diffuse light").
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from causalplan.objects.catalog import Catalog
from causalplan.studies.steps import ParticipantModel

TUTORIAL_OBJECT = "toy_car"
TUTORIAL_FUNCTIONS: dict[str, tuple[str, ...]] = {
    "chassis": ("hold things together",),
    "wind_up_motor": ("store energy", "turn the axle"),
    "wheels": ("roll on the ground",),
    "sticker": ("decorate the car",),
}
EXAMPLE_RULES = (
    "store energy AND turn the axle CAUSES the axle spins",
    "the axle spins AND roll on the ground CAUSES motion",
)


@dataclass(frozen=True)
class Question:
    """A multiple-choice question: the choices (value, words), the right value, and why."""

    id: str
    text: str
    choices: tuple[tuple[str, str], ...]
    answer: str
    explanation: str


QUESTIONS = (
    Question(
        "sticker",
        "The sticker's function is 'decorate the car'. Should a rule use it to cause motion?",
        (
            ("yes", "Yes: every part's function belongs in a rule."),
            ("no", "No: decorating does not make the car move."),
        ),
        "no",
        "Only functions that help produce the goal belong in the rules. 'Decorate the car' and "
        "'hold things together' do not make the car move, so leave them out of the rules.",
    ),
    Question(
        "diffuse",
        "A lamp's shade 'diffuses light'. Can 'diffuse light' be a cause of light?",
        (
            ("yes", "Yes: the shade is part of the lamp, so it helps make light."),
            ("no", "No: light must already exist before it can be diffused."),
        ),
        "no",
        "Diffusing light changes light that is already there; it does not produce it. "
        "A cause has to come before its effect.",
    ),
    Question(
        "and",
        "Two functions are both needed for an effect. How do you write that?",
        (
            ("and", "One rule: FIRST AND SECOND CAUSES EFFECT"),
            ("two", "Two rules: FIRST CAUSES EFFECT, then SECOND CAUSES EFFECT"),
        ),
        "and",
        "AND joins causes that are all needed. Two rules with the same effect are alternatives: "
        "either one alone would produce it.",
    ),
)


def wrong_answers(answers: Mapping[str, str]) -> list[Question]:
    """Return the questions not answered, or answered wrongly."""
    return [question for question in QUESTIONS if answers.get(question.id) != question.answer]


def practice_model(rules: tuple[str, ...], catalog: Catalog) -> ParticipantModel:
    """Return the tutorial's practice model: the toy car's given functions and the participant's rules."""
    goal = catalog.get(TUTORIAL_OBJECT).goal
    return ParticipantModel(goal, {TUTORIAL_OBJECT: TUTORIAL_FUNCTIONS}, rules)
