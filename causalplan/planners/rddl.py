"""The task's MDP written in RDDL (the probabilistic planning competitions' format): domain and instance.

The domain is lifted over parts and fits and holds the model's rules: one boolean
interm-fluent per node of the causal model (a function node holds when an attached part
carries it; an effect node when all causes of one of its rules hold). The instance holds the
object: its parts and fits, each fit's success probability, which parts it joins and which
fits it makes unusable when it succeeds or fails (``mdp.model`` states these semantics).

A step attempts one fit (``attempt(?f)``); ``works(?f) ~ Bernoulli(P(?f))`` is its outcome.
``lit`` becomes true (and stays) one step after the goal node holds. Labels written by people
never appear in the text: nodes are ``n1, n2, ...`` and objects keep their catalog ids only
when those are plain identifiers (else ``part_3``, ``fit_7``). ``RddlTask`` maps both ways.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from causalplan.pddl.task import PlanningTask
from causalplan.planners.mdp.model import STEP_COST, compile_mdp

_IDENTIFIER = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
_RESERVED = {"if", "then", "else", "true", "false", "exists", "forall", "sum", "prod", "switch", "case", "default"}


@dataclass(frozen=True)
class RddlTask:
    """The RDDL text of a task, with the names it gives to parts, fits and the model's nodes."""

    name: str
    domain: str
    instance: str
    part_names: dict[str, str]  # part id -> RDDL object
    fit_names: dict[str, str]  # fit id -> RDDL object
    node_names: dict[str, str]  # node key -> interm-fluent

    def action(self, fit_id: str) -> str:
        """Return pyRDDLGym's key of the action that attempts ``fit_id``."""
        return f"attempt___{self.fit_names[fit_id]}"

    def attached(self, part_id: str) -> str:
        """Return pyRDDLGym's key of the state fluent saying ``part_id`` is attached."""
        return f"attached___{self.part_names[part_id]}"


def _names(ids: tuple[str, ...], prefix: str) -> dict[str, str]:
    """Keep each id that is a plain RDDL identifier; name the others ``{prefix}_{n}``, never twice.

    A kept id can look like a made-up name (a part called ``part_2``), so the made-up names skip
    every name already taken, compared without case.
    """
    kept = {identifier for identifier in ids if _IDENTIFIER.match(identifier) and identifier.lower() not in _RESERVED}
    taken = {identifier.lower() for identifier in kept}
    names: dict[str, str] = {}
    number = 0
    for identifier in ids:
        if identifier in kept:
            names[identifier] = identifier
            continue
        number += 1
        while f"{prefix}_{number}" in taken:
            number += 1
        names[identifier] = f"{prefix}_{number}"
        taken.add(names[identifier])
    return names


def _real(value: float) -> str:
    return repr(float(value))


def export_rddl(task: PlanningTask) -> RddlTask:
    """Return the RDDL domain and instance of ``task``'s MDP (all of the object's fits)."""
    obj = task.obj
    name = re.sub(r"[^A-Za-z0-9_]", "_", f"causalplan_{obj.id}")
    parts = _names(obj.part_ids, "part")
    fits = _names(tuple(fit.id for fit in obj.fits), "fit")
    compiled = compile_mdp(task, obj.fits)
    rules = task.rules
    keys: list[str] = []
    for rule in rules:
        for key in (*sorted(rule.cause_keys), rule.effect_key):
            if key not in keys:
                keys.append(key)
    if task.goal_key not in keys:
        keys.append(task.goal_key)
    nodes = {key: f"n{number}" for number, key in enumerate(keys, start=1)}
    carriers = task.carriers()

    declarations = [
        "P(fit) : { non-fluent, real, default = 1.0 };",
        "MOVING(fit, part) : { non-fluent, bool, default = false };",
        "FIXED(fit, part) : { non-fluent, bool, default = false };",
        "TAKEN_ON_SUCCESS(fit, fit) : { non-fluent, bool, default = false };",
        "TAKEN_ON_FAILURE(fit, fit) : { non-fluent, bool, default = false };",
        *(f"CARRIES_{nodes[key]}(part) : {{ non-fluent, bool, default = false }};" for key in keys),
        "attached(part) : { state-fluent, bool, default = false };",
        "unusable(fit) : { state-fluent, bool, default = false };",
        "lit : { state-fluent, bool, default = false };",
        "works(fit) : { interm-fluent, bool };",
        "tried(fit) : { interm-fluent, bool };",
        *(f"{nodes[key]} : {{ interm-fluent, bool }};" for key in keys),
        "attempt(fit) : { action-fluent, bool, default = false };",
    ]
    cpfs = [
        "works(?f) = Bernoulli(P(?f));",
        "tried(?f) = attempt(?f) ^ ~unusable(?f) ^ (exists_{?q : part} [FIXED(?f, ?q) ^ attached(?q)])"
        " ^ ~(exists_{?q : part} [MOVING(?f, ?q) ^ attached(?q)]);",
    ]
    for key in keys:
        alternatives = [
            "(" + " ^ ".join(nodes[cause] for cause in sorted(rule.cause_keys)) + ")"
            for rule in rules
            if rule.effect_key == key
        ]
        alternatives.append(f"(exists_{{?p : part}} [CARRIES_{nodes[key]}(?p) ^ attached(?p)])")
        cpfs.append(f"{nodes[key]} = {' | '.join(alternatives)};")
    cpfs += [
        "attached'(?p) = attached(?p) | exists_{?f : fit} [tried(?f) ^ works(?f) ^ MOVING(?f, ?p)];",
        "unusable'(?f) = unusable(?f) | exists_{?g : fit} [tried(?g) ^ ((works(?g) ^ TAKEN_ON_SUCCESS(?g, ?f))"
        " | (~works(?g) ^ TAKEN_ON_FAILURE(?g, ?f)))];",
        f"lit' = lit | {nodes[task.goal_key]};",
    ]
    domain = "\n".join(
        [
            f"domain {name} {{",
            "    requirements = { concurrent, intermediate-nodes };",
            "    types { part : object; fit : object; };",
            "    pvariables {",
            *(f"        {line}" for line in declarations),
            "    };",
            "    cpfs {",
            *(f"        {line}" for line in cpfs),
            "    };",
            f"    reward = (if (~lit ^ {nodes[task.goal_key]}) then 1.0 else 0.0)"
            f" - {_real(STEP_COST)} * (sum_{{?f : fit}} [attempt(?f)]);",
            "    action-preconditions { (sum_{?f : fit} [attempt(?f)]) <= 1; };",
            "}",
            "",
        ]
    )
    facts: list[str] = []
    for index, fit in enumerate(obj.fits):  # compiled over obj.fits: a fit's index is its bit
        f = fits[fit.id]
        facts += [
            f"P({f}) = {_real(fit.probability)};",
            f"MOVING({f}, {parts[fit.moving_part]}) = true;",
            f"FIXED({f}, {parts[fit.fixed_part]}) = true;",
        ]
        for other_index, other in enumerate(obj.fits):
            bit = 1 << other_index
            if compiled.taken_on_success[index] & bit:
                facts.append(f"TAKEN_ON_SUCCESS({f}, {fits[other.id]}) = true;")
            if compiled.taken_on_failure[index] & bit:
                facts.append(f"TAKEN_ON_FAILURE({f}, {fits[other.id]}) = true;")
    for key in keys:
        facts += [f"CARRIES_{nodes[key]}({parts[part]}) = true;" for part in carriers.get(key, ())]
    instance = "\n".join(
        [
            f"non-fluents nf_{name} {{",
            f"    domain = {name};",
            "    objects {",
            f"        part : {{{', '.join(parts.values())}}};",
            f"        fit : {{{', '.join(fits.values())}}};",
            "    };",
            "    non-fluents {",
            *(f"        {line}" for line in facts),
            "    };",
            "}",
            "",
            f"instance inst_{name} {{",
            f"    domain = {name};",
            f"    non-fluents = nf_{name};",
            f"    init-state {{ attached({parts[obj.base]}) = true; }};",
            "    max-nondef-actions = 1;",
            f"    horizon = {len(obj.fits) + 2};",
            "    discount = 1.0;",
            "}",
            "",
        ]
    )
    return RddlTask(name, domain, instance, parts, fits, nodes)
