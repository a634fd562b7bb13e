"""Why not …? Plan again with the question's constraint compiled in, compare, and name what decides.

The alternative is planned by Fast Downward's optimal search on the same task with the
question's ``PlanConstraints`` in its problem file, then replayed and (when asked) validated
by VAL like any plan. The answer's ``code`` is one of a closed set:

* ``already_does``: the plan already does what the question asks (no alternative is planned);
* ``not_needed``: the alternative works, but the part carries nothing the model needs;
* ``also_works``: the alternative works and is as short as the plan;
* ``longer`` / ``shorter``: it works with more (fewer) steps;
* ``goal_unreachable``: without the part the model cannot produce the goal (the rule that needs it is named);
* ``blocked``: the order cannot be done: the first part covers or takes a connector the other needs;
* ``no_assembly_sequence``: no order of connecting the parts meets the constraint;
* ``violates_true_mechanism``: the alternative satisfies the model but the real object would not work.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from causalplan.causal.graph import goal_holds
from causalplan.causal.labels import normalize_label
from causalplan.errors import CausalPlanError
from causalplan.explain.questions import Kind, Question
from causalplan.objects.model import AssemblyObject, Fit
from causalplan.pddl.task import PlanningTask
from causalplan.planners.fd import DEFAULT_TIME_LIMIT
from causalplan.planners.pipeline import plan_task
from causalplan.planners.result import PlanResult, PlanStatus, PlanStep

ALTERNATIVE_PLANNER = "fd-opt"
"""The alternative is a shortest plan under the constraint, so "as short" is a fair comparison."""


class PlanUnavailableError(CausalPlanError):
    """There is no plan to ask about (the model has none on this object)."""

    code = "no_plan_to_explain"


@dataclass(frozen=True)
class Contrast:
    """The answer to one why-not question: the code, the words, what decides it, and both plans."""

    question: Question
    text: str
    code: str
    message: str
    decided_by: dict[str, object]
    plan: PlanResult
    alternative: PlanResult
    simulation_failure: str | None = None

    def as_dict(self) -> dict[str, object]:
        """Return the answer as a JSON-ready dict (the alternative as ``causalplan plan --json`` has it).

        The plan asked about is not repeated: ``Explanation.as_dict`` holds it once.
        """
        return {
            "question": self.text,
            "asked": self.question.as_dict(),
            "code": self.code,
            "message": self.message,
            "decided_by": self.decided_by,
            "alternative": self.alternative.as_dict(),
            "simulation_failure": self.simulation_failure,
        }


def _quoted(labels: list[str] | tuple[str, ...]) -> str:
    return ", ".join(f"'{label}'" for label in labels)


def _labels_of(task: PlanningTask, part: str) -> tuple[str, ...]:
    return tuple(task.labelling.functions.get(part, ()))


def _used_by_rules(task: PlanningTask) -> set[str]:
    return {key for rule in task.rules for key in rule.cause_keys}


def _not_needed(task: PlanningTask, part: str) -> tuple[str, dict[str, object]]:
    """Return why the model does not need ``part`` (the plan works without it), and what decides it."""
    name = task.obj.part(part).name
    labels = _labels_of(task, part)
    used = _used_by_rules(task)
    unused = [label for label in labels if normalize_label(label) not in used]
    if not labels:
        return f"your model gives the {name} no function, so it does not need it for {task.goal}", {"part": part}
    if unused and len(unused) == len(labels):
        return (
            f"your model does not need the {name} for {task.goal}: no rule uses {_quoted(unused)}",
            {"function": unused[0], "rules_using_it": []},
        )
    carriers = task.carriers()
    elsewhere = [
        f"'{label}' from the {task.obj.part(other).name}"
        for label in labels
        for other in carriers.get(normalize_label(label), ())
        if other != part
    ]
    where = f": the plan already gets {', '.join(elsewhere)}" if elsewhere else ""
    return f"your model does not need the {name} for {task.goal}{where}", {"part": part, "function": labels[0]}


def _decisive_function(task: PlanningTask, parts: set[str]) -> tuple[str, list[int]] | None:
    """Return a function that only ``parts`` carry and without which the goal fails, with the rules that use it."""
    carriers = task.carriers()
    for part in sorted(parts):
        for label in _labels_of(task, part):
            key = normalize_label(label)
            if set(carriers.get(key, ())) - parts:
                continue
            others = {k for k, holders in carriers.items() if set(holders) - parts and k != key}
            if not goal_holds(others, task.rules, task.goal_key):
                return label, [rule.index for rule in task.rules if key in rule.cause_keys]
    return None


def _unreachable_without(task: PlanningTask, parts: set[str]) -> tuple[str, dict[str, object]] | None:
    """Return why the goal cannot hold without ``parts`` (naming the function and rule), or None if it can."""
    carriers = {key: tuple(p for p in holders if p not in parts) for key, holders in task.carriers().items()}
    if goal_holds({key for key, holders in carriers.items() if holders}, task.rules, task.goal_key):
        return None
    names = " and ".join(f"the {task.obj.part(part).name}" for part in sorted(parts))
    decisive = _decisive_function(task, parts)
    if decisive is None:
        return f"then {task.goal} cannot be produced: without {names} your rules never reach it", {
            "parts": sorted(parts)
        }
    label, rule_indexes = decisive
    rules = [rule for rule in task.rules if rule.index in rule_indexes]
    quoted_rules = "; ".join(f"rule {rule.index} ({rule.text})" for rule in rules)
    words = (
        f"then {task.goal} cannot be produced: {quoted_rules} needs '{label}', and only {names} carries it"
        if rules
        else f"then {task.goal} cannot be produced: only {names} carries '{label}'"
    )
    return words, {"function": label, "rules": rule_indexes}


def _blocker(obj: AssemblyObject, first: str, then: str) -> tuple[Fit, Fit, tuple[str, str]] | None:
    """Return a fit attaching ``first`` that rules out every fit attaching ``then``, one such fit, and the connector."""
    then_fits = [fit for fit in obj.fits if fit.moving_part == then]
    for fit in obj.fits:
        if fit.moving_part != first or not then_fits:
            continue
        excluded = set(obj.excluded_fits(fit))
        if all(other.id in excluded for other in then_fits):
            other = then_fits[0]
            taken = set(fit.connectors()) | set(fit.blocks)
            connector = next(iter(sorted(taken & set(other.connectors()))), other.connectors()[1])
            return fit, other, connector
    return None


def _blocked_words(obj: AssemblyObject, blocker: tuple[Fit, Fit, tuple[str, str]]) -> tuple[str, dict[str, object]]:
    """Return, in words and as data, how the first fit of ``blocker`` rules out the second."""
    fit, other, (owner, connector) = blocker
    covers = "covers" if (owner, connector) in fit.blocks else "takes"
    words = (
        f"then the {obj.part(fit.moving_part).name} {covers} the {connector.replace('_', ' ')} of the "
        f"{obj.part(owner).name} and the {obj.part(other.moving_part).name} cannot go in"
    )
    return words, {"fit": fit.id, "rules_out": other.id, "connector": f"{owner}.{connector}"}


def _simulated_failure(obj: AssemblyObject, fits: tuple[Fit, Fit]) -> str | None:
    """Return the simulator's failure code when the robot tries ``fits`` in this order (None when it works)."""
    from causalplan.sim import RenderMode, simulate_plan  # the simulator loads only when an order is tried

    steps = tuple(
        PlanStep(fit.primitive, (fit.moving_part, fit.fixed_part), fit.id, obj.step_text(fit)) for fit in fits
    )
    report = simulate_plan(obj, steps, render=RenderMode.NONE)
    failed = [step for step in report.steps if step.failure is not None]
    return failed[0].failure.value if failed and failed[0].failure is not None else None


def _length_words(plan: PlanResult, alternative: PlanResult) -> tuple[str, str]:
    difference = len(alternative.steps) - len(plan.steps)
    if difference == 0:
        return "also_works", "that plan also works and is as short"
    if difference > 0:
        return (
            "longer",
            f"that plan also works but takes {difference} more step(s) "
            f"({len(alternative.steps)} against {len(plan.steps)})",
        )
    return "shorter", f"that plan also works and is {-difference} step(s) shorter"


def _answer_unsolvable(
    task: PlanningTask, question: Question, simulate: bool
) -> tuple[str, str, dict[str, object], str | None]:
    obj = task.obj
    if question.kind is Kind.LEAVE_OUT:
        found = _unreachable_without(task, set(question.parts))
        if found is not None:
            return "goal_unreachable", found[0], found[1], None
    if question.kind is Kind.ORDER:
        blocker = _blocker(obj, *question.parts)
        if blocker is not None:
            words, decided = _blocked_words(obj, blocker)
            failure = _simulated_failure(obj, blocker[:2]) if simulate else None
            words += f"; in simulation the robot's step fails: {failure}" if failure else ""
            return "blocked", words, decided, failure
    return (
        "no_assembly_sequence",
        f"no order of connecting the {obj.name}'s parts does that and still produces {task.goal} under your model",
        {},
        None,
    )


def why_not(
    task: PlanningTask,
    question: Question,
    plan: PlanResult,
    time_limit: float = DEFAULT_TIME_LIMIT,
    val: bool = True,
    simulate: bool = False,
) -> Contrast:
    """Return the answer to ``question`` about ``plan`` (a solved plan of ``task``).

    ``simulate``: when an order cannot be done, also run it in the simulator and name its failure.
    """
    if not plan.has_plan:
        raise PlanUnavailableError(
            f"There is no plan to ask about: {plan.message}", details={"status": plan.status.value}
        )
    obj = task.obj
    text = question.text(obj)
    if question.kind is Kind.LEAVE_OUT and question.parts[0] == obj.base:
        name = obj.part(obj.base).name
        words = (
            f"The {name} is where the robot starts: every other part is attached to it, "
            f"so the {obj.name} cannot be built without it"
        )
        return Contrast(question, text, "is_base", _sentence(words), {"part": obj.base}, plan, plan)
    constraints = question.constraints(obj)
    in_plan = [step.args[0] for step in plan.steps]
    if not constraints.violations(obj, [step.fit for step in plan.steps]):
        doing = ", ".join(f"step {number}: {step.text.rstrip('.')}" for number, step in enumerate(plan.steps, start=1))
        return Contrast(question, text, "already_does", f"The plan already does that ({doing})", {}, plan, plan)
    alternative = plan_task(replace(task, constraints=constraints), ALTERNATIVE_PLANNER, time_limit, val=val)
    if alternative.status is PlanStatus.SOLVED:
        code, words = _length_words(plan, alternative)
        decided: dict[str, object] = {}
        if question.kind is Kind.ATTACH and question.parts[0] not in in_plan:
            code = "not_needed"
            reason, decided = _not_needed(task, question.parts[0])
            words = (
                f"{reason}; attaching it anyway is also a plan "
                f"({len(alternative.steps)} step(s) against {len(plan.steps)})"
            )
        if plan.valid_under_true_mechanism and not alternative.valid_under_true_mechanism:
            code = "violates_true_mechanism"
            words += f", but the real {obj.name} would not produce {obj.goal}: it also needs " + "; ".join(
                alternative.unmet_requirements
            )
        return Contrast(question, text, code, _sentence(words), decided, plan, alternative)
    if alternative.status is PlanStatus.UNSOLVABLE:
        code, words, decided, failure = _answer_unsolvable(task, question, simulate)
        return Contrast(question, text, code, _sentence(words), decided, plan, alternative, failure)
    return Contrast(
        question,
        text,
        "undecided",
        _sentence(f"the planner could not decide ({alternative.status.value}): {alternative.message}"),
        {},
        plan,
        alternative,
    )


def _sentence(words: str) -> str:
    text = words.strip()
    return text[:1].upper() + text[1:] + ("" if text.endswith(".") else ".")
