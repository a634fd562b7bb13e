"""Why this step? The causal chain a step of a plan serves, in the model's own words.

A step attaches a part; the part carries functions (step 1, or the step-3 mapping); a rule
whose causes all hold in the finished assembly turns them into its effect, and so on up to
the goal. A step whose part carries nothing the rules use is there only to reach a part that
does (it is the part the later one attaches to).
"""

from __future__ import annotations

from dataclasses import dataclass

from causalplan.causal.graph import active_nodes
from causalplan.causal.labels import normalize_label
from causalplan.causal.rules import Rule
from causalplan.pddl.task import PlanningTask
from causalplan.planners.result import PlanStep


@dataclass(frozen=True)
class Link:
    """One rule of a chain: it turns ``cause`` (with the rule's other causes) into its effect."""

    rule: Rule
    cause: str

    def as_dict(self) -> dict[str, object]:
        return {"rule": self.rule.index, "rule_text": self.rule.text, "cause": self.cause, "effect": self.rule.effect}


@dataclass(frozen=True)
class StepExplanation:
    """Why step ``number`` is in the plan: the functions its part carries and the chain of each."""

    number: int
    step: PlanStep
    part: str
    chains: tuple[tuple[str, tuple[Link, ...]], ...]
    """Each function the part carries that leads to the goal, with the rules that lead there."""
    unused_functions: tuple[str, ...]
    reached_by: tuple[int, ...]
    """When the part carries nothing the model uses: the later steps that attach to it."""
    message: str

    def as_dict(self) -> dict[str, object]:
        """Return the explanation as a JSON-ready dict."""
        return {
            "step": self.number,
            "text": self.step.text,
            "part": self.part,
            "chains": [
                {"function": label, "rules": [link.as_dict() for link in links]} for label, links in self.chains
            ],
            "unused_functions": list(self.unused_functions),
            "reached_by": list(self.reached_by),
            "message": self.message,
        }


def chain_to_goal(key: str, rules: tuple[Rule, ...], goal_key: str, holding: set[str]) -> tuple[Rule, ...] | None:
    """Return the shortest sequence of rules from node ``key`` to the goal, each firing on ``holding``.

    A rule fires when all its causes hold. None when no such chain exists.
    """
    paths: dict[str, tuple[Rule, ...]] = {key: ()}
    frontier = [key]
    while frontier:
        following: list[str] = []
        for node in frontier:
            if node == goal_key:
                return paths[node]
            for rule in rules:
                if node in rule.cause_keys and rule.cause_keys <= holding and rule.effect_key not in paths:
                    paths[rule.effect_key] = (*paths[node], rule)
                    following.append(rule.effect_key)
        frontier = following
    return None


def _quoted(labels: list[str]) -> str:
    return " and ".join(f"'{label}'" for label in labels)


def _chain_words(label: str, rules: tuple[Rule, ...], goal: str, labels: dict[str, str]) -> str:
    words = []
    cause = label
    for rule in rules:
        others = [labels.get(key, key) for key in sorted(rule.cause_keys) if key != normalize_label(cause)]
        with_others = f" (with {_quoted(others)})" if others else ""
        effect = "the goal" if rule.effect_key == normalize_label(goal) else f"'{rule.effect}'"
        words.append(f"rule {rule.index} needs '{cause}'{with_others} to produce {effect}")
        cause = rule.effect
    return "; ".join(words)


def explain_step(task: PlanningTask, steps: tuple[PlanStep, ...], number: int) -> StepExplanation:
    """Return why step ``number`` (from 1) of ``steps``, a plan of ``task``, is there."""
    step = steps[number - 1]
    part = step.args[0]
    obj = task.obj
    name = obj.part(part).name
    assembled = {obj.base, *(s.args[0] for s in steps)}
    holding = active_nodes(task.functions_of(assembled), task.rules)
    node_labels = task.node_labels()
    carried = list(task.labelling.functions.get(part, ()))
    chains: list[tuple[str, tuple[Link, ...]]] = []
    unused: list[str] = []
    for label in carried:
        rules = chain_to_goal(normalize_label(label), task.rules, task.goal_key, holding)
        if rules is None:
            unused.append(label)
        else:
            links = [Link(rule, label if index == 0 else rules[index - 1].effect) for index, rule in enumerate(rules)]
            chains.append((label, tuple(links)))
    opening = f"Step {number} ({step.text.rstrip('.')}) attaches the {name}"
    if chains:
        parts = [
            f"the {name} carries '{label}': "
            + _chain_words(label, tuple(link.rule for link in links), task.goal, node_labels)
            for label, links in chains
        ]
        message = f"{opening} because {'; and '.join(parts)} ({task.goal})."
        return StepExplanation(number, step, part, tuple(chains), tuple(unused), (), message)
    later = tuple(k for k in range(number + 1, len(steps) + 1) if steps[k - 1].args[1] == part)
    what = (
        f"carries {_quoted(unused)}, which no rule on the way to {task.goal} uses"
        if unused
        else ("carries no function in your model")
    )
    if later:
        reached = [f"the {obj.part(steps[k - 1].args[0]).name} (step {k})" for k in later]
        message = f"{opening}: it {what}; it is needed only to reach a part that attaches to it: {', '.join(reached)}."
    else:
        message = f"{opening}: it {what}, and no later step attaches to it; the model does not need it."
    return StepExplanation(number, step, part, (), tuple(unused), later, message)
