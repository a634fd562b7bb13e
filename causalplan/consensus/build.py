"""The consensus model: the rules enough participants hold, over labels aligned across people.

Functions align by words and parts, intermediate effects by words and the aligned nodes that
cause them, level by level from the functions up; every goal is one node. A rule's support is
the share of the crowd whose model holds it (same aligned causes, same aligned effect); rules
with at least ``min_support`` enter, a rule that would close a cycle is left out (the least
supported first), and so is one that leads nowhere near the goal. The step-3 mapping of each
test object is built the same way: a function sits on a part when enough of the people who
mapped that object put it there. Labels are only ever copied as written by someone, never
edited, so they cannot change what the PDDL means.
"""

from __future__ import annotations

import re
from collections import Counter
from dataclasses import asdict, dataclass, field

from causalplan.causal.documents import SourceMap
from causalplan.causal.labels import normalize_label
from causalplan.causal.model import CausalModel, read_model
from causalplan.consensus.alignment import TEXT_WEIGHT, THRESHOLD, LabelUse, cluster_uses
from causalplan.consensus.participants import Participant
from causalplan.errors import CausalPlanError
from causalplan.inputs import LoadedModel, mapping_from_data, model_from_data
from causalplan.objects.catalog import Catalog

MIN_SUPPORT = 0.5
"""The share of the crowd a rule (or a function's place in a mapping) needs to enter; see benchmarks/RESULTS.md."""
_KEYWORD = re.compile(r"(?<!\S)(and|or|causes)(?!\S)", re.IGNORECASE)


class NoCrowdError(CausalPlanError):
    """There is no participant whose model could be read, so there is nothing to agree on."""

    code = "no_crowd"


@dataclass(frozen=True)
class Node:
    """One node of the consensus: the labels people wrote for it, by whom, and where it sits."""

    id: str
    kind: str  # function | effect | goal
    label: str
    writings: dict[str, tuple[str, ...]]
    parts: dict[str, float] = field(default_factory=dict)

    @property
    def holders(self) -> set[str]:
        return {person for people in self.writings.values() for person in people}

    def as_dict(self) -> dict[str, object]:
        return {**asdict(self), "writings": {text: list(people) for text, people in self.writings.items()}}


@dataclass(frozen=True)
class RuleSupport:
    """One rule some participant holds, in aligned nodes, with who holds it and whether it entered."""

    causes: frozenset[str]
    effect: str
    holders: tuple[str, ...]
    share: float
    entered: bool
    why_left_out: str | None = None


@dataclass(frozen=True)
class MappingConsensus:
    """The consensus step-3 mapping of one test object, with each (part, node) pair's support."""

    test_object: str
    mappers: tuple[str, ...]
    support: dict[tuple[str, str], tuple[str, ...]]
    data: dict[str, object]


@dataclass
class Consensus:
    """What ``consensus`` computes before judging: the nodes, every rule's support, the model, the mappings."""

    training_object: str
    members: tuple[str, ...]
    left_out: dict[str, str]
    nodes: dict[str, Node]
    rules: list[RuleSupport]
    model_data: dict[str, object]
    loaded: LoadedModel
    mappings: dict[str, MappingConsensus]
    min_support: float
    models: dict[str, CausalModel] = field(default_factory=dict)
    """Each member's model as read."""

    def rule_text(self, rule: RuleSupport) -> str:
        causes = " AND ".join(sorted(self.nodes[cause].label for cause in rule.causes))
        return f"{causes} CAUSES {self.nodes[rule.effect].label}"


def _representative(writings: Counter[str]) -> str:
    """Return the writing most people used (then the shortest, then the first alphabetically)."""
    usable = [text for text in writings if not _KEYWORD.search(text)] or list(writings)
    return min(usable, key=lambda text: (-writings[text], len(text), text))


def _levels(model: CausalModel) -> dict[str, int]:
    """Return each non-function node's level: 1 + the highest level of its causes (functions are 0)."""
    effects = {rule.effect_key for rule in model.rules}
    carried = set(model.labelling.carriers()) - effects  # a label both carried and produced is an effect
    level = {key: 0 for key in carried}
    nodes = {rule.effect_key for rule in model.rules} | {key for rule in model.rules for key in rule.cause_keys}
    for key in nodes - carried:
        level.setdefault(key, 1)
    for _ in range(len(nodes) + 1):  # relaxation; a cycle stops growing after as many rounds as nodes
        changed = False
        for rule in model.rules:
            if rule.effect_key in carried:
                continue
            wanted = 1 + max(level.get(cause, 0) for cause in rule.cause_keys)
            if wanted > level[rule.effect_key] and wanted <= len(nodes):
                level[rule.effect_key] = wanted
                changed = True
        if not changed:
            break
    return level


class _Aligner:
    """Assigns every (participant, label key) to a node, functions first, then effects level by level."""

    def __init__(self, models: dict[str, CausalModel], threshold: float, text_weight: float) -> None:
        self.models, self.threshold, self.text_weight = models, threshold, text_weight
        self.node_of: dict[tuple[str, str], str] = {}
        self.nodes: dict[str, Node] = {}

    def run(self) -> None:
        uses: dict[tuple[str, frozenset[str]], set[str]] = {}
        texts: dict[tuple[str, str], str] = {}
        for person, model in self.models.items():
            labels = model.node_labels()
            effects = {rule.effect_key for rule in model.rules}
            for key, parts in model.labelling.carriers().items():
                if key in effects or key == model.goal_key:
                    continue
                uses.setdefault((key, frozenset(parts)), set()).add(person)
                texts[(person, key)] = labels[key]
        self._assign("f", "function", uses, texts)
        levels = {person: _levels(model) for person, model in self.models.items()}
        top = max((lvl for per in levels.values() for lvl in per.values()), default=0)
        for level in range(1, top + 1):
            uses, texts = {}, {}
            for person, model in self.models.items():
                labels = model.node_labels()
                for key, at in levels[person].items():
                    if at != level or key == model.goal_key or (person, key) in self.node_of:
                        continue
                    causes = frozenset(
                        self.node_of.get((person, cause), f"?{cause}")
                        for rule in model.rules
                        if rule.effect_key == key
                        for cause in rule.cause_keys
                    )
                    uses.setdefault((key, causes), set()).add(person)
                    texts[(person, key)] = labels[key]
            self._assign("e", "effect", uses, texts)
        goal_writings: dict[str, list[str]] = {}
        for person, model in self.models.items():
            self.node_of[(person, model.goal_key)] = "goal"
            goal_writings.setdefault(model.goal, []).append(person)
        counts = Counter({text: len(people) for text, people in goal_writings.items()})
        self.nodes["goal"] = Node(
            "goal", "goal", _representative(counts), {t: tuple(p) for t, p in goal_writings.items()}
        )

    def _assign(
        self,
        prefix: str,
        kind: str,
        uses: dict[tuple[str, frozenset[str]], set[str]],
        texts: dict[tuple[str, str], str],
    ) -> None:
        ordered = sorted(uses.items(), key=str)
        items = [LabelUse(key, key, context, frozenset(people)) for (key, context), people in ordered]
        for group in cluster_uses(items, self.threshold, self.text_weight):
            node_id = f"{prefix}{sum(1 for n in self.nodes if n.startswith(prefix)) + 1}"
            writings: dict[str, list[str]] = {}
            parts: Counter[str] = Counter()
            for index in group:
                for person in sorted(items[index].holders):
                    self.node_of[(person, items[index].key)] = node_id
                    writings.setdefault(texts[(person, items[index].key)], []).append(person)
                    if kind == "function":
                        parts.update(items[index].context)
            holders = sum(len(people) for people in writings.values())
            counts = Counter({text: len(people) for text, people in writings.items()})
            self.nodes[node_id] = Node(
                node_id,
                kind,
                _representative(counts),
                {text: tuple(people) for text, people in sorted(writings.items())},
                {part: round(count / holders, 4) for part, count in sorted(parts.items())},
            )


def _unique_labels(nodes: dict[str, Node]) -> dict[str, Node]:
    """Return the nodes with labels made distinct: a repeated label gets its node id in brackets."""
    seen: Counter[str] = Counter(normalize_label(node.label) for node in nodes.values())
    return {
        node_id: node
        if seen[normalize_label(node.label)] == 1 or node.kind == "goal"
        else Node(node.id, node.kind, f"{node.label} ({node.id})", node.writings, node.parts)
        for node_id, node in nodes.items()
    }


def _select(supports: list[RuleSupport], min_support: float) -> list[RuleSupport]:
    """Return the rules with the entered flag decided: supported, acyclic, leading to the goal."""
    import networkx as nx

    chosen = {index for index, rule in enumerate(supports) if rule.share >= min_support - 1e-9}
    why: dict[int, str] = {
        index: f"held by {rule.share:.0%} of the crowd, below {min_support:.0%}"
        for index, rule in enumerate(supports)
        if index not in chosen
    }
    while True:
        graph = nx.DiGraph()
        for index in chosen:
            for cause in supports[index].causes:
                graph.add_edge(cause, supports[index].effect, rule=index)
        try:
            cycle = nx.find_cycle(graph)
        except nx.NetworkXNoCycle:
            break
        weakest = min((graph.edges[a, b]["rule"] for a, b in cycle), key=lambda i: (supports[i].share, i))
        chosen.discard(weakest)
        why[weakest] = "it would close a cycle with better supported rules"
    leads = nx.ancestors(graph, "goal") | {"goal"} if "goal" in graph else set()
    for index in sorted(chosen):
        if supports[index].effect not in leads:
            chosen.discard(index)
            why[index] = "its effect does not lead to the goal"
    return [
        RuleSupport(rule.causes, rule.effect, rule.holders, rule.share, index in chosen, why.get(index))
        for index, rule in enumerate(supports)
    ]


def build_consensus(
    participants: list[Participant],
    catalog: Catalog,
    min_support: float = MIN_SUPPORT,
    threshold: float = THRESHOLD,
    text_weight: float = TEXT_WEIGHT,
) -> Consensus:
    """Return the crowd's consensus model and mappings (not yet judged)."""
    readable: dict[str, CausalModel] = {}
    left_out: dict[str, str] = {}
    for person in participants:
        model, problems = read_model(person.model, SourceMap(person.where or person.id))
        if person.model is None or model is None or not model.object_id:
            why = person.problems or [problem.message for problem in problems[:1]] or ["the model could not be read"]
            left_out[person.id] = "; ".join(why)
            continue
        if model.object_id not in catalog.objects:
            left_out[person.id] = f"the model's object '{model.object_id}' is not in the catalog"
            continue
        readable[person.id] = model
    if not readable:
        raise NoCrowdError("No participant has a model that can be read: " + "; ".join(left_out.values()))
    training = Counter(model.object_id for model in readable.values()).most_common(1)[0][0]
    for person_id, model in list(readable.items()):
        if model.object_id != training:
            left_out[person_id] = f"trained on {model.object_id}, the crowd on {training}"
            del readable[person_id]
    aligner = _Aligner(readable, threshold, text_weight)
    aligner.run()
    nodes = _unique_labels(aligner.nodes)
    holders: dict[tuple[frozenset[str], str], set[str]] = {}
    for member, model in readable.items():
        for rule in model.rules:
            causes = frozenset(aligner.node_of[(member, key)] for key in rule.cause_keys)
            holders.setdefault((causes, aligner.node_of[(member, rule.effect_key)]), set()).add(member)
    crowd = len(readable)
    supports = [
        RuleSupport(causes, effect, tuple(sorted(people)), round(len(people) / crowd, 4), False)
        for (causes, effect), people in sorted(holders.items(), key=lambda item: (-len(item[1]), str(item[0])))
    ]
    supports = _select(supports, min_support)
    model_data = _model_data(training, nodes, supports)
    loaded = model_from_data(model_data, SourceMap("consensus model"), catalog)
    mappings = {
        test: _mapping(test, participants, readable, aligner.node_of, nodes, model_data, min_support, catalog)
        for test in sorted({test for person in participants if person.id in readable for test in person.mappings})
    }
    return Consensus(
        training, tuple(readable), left_out, nodes, supports, model_data, loaded, mappings, min_support, readable
    )


def _model_data(training: str, nodes: dict[str, Node], supports: list[RuleSupport]) -> dict[str, object]:
    entered = [rule for rule in supports if rule.entered]
    used = sorted({cause for rule in entered for cause in rule.causes if nodes[cause].kind == "function"})
    functions: dict[str, list[str]] = {}
    for node_id in used:
        node = nodes[node_id]
        top = max(node.parts.items(), key=lambda item: item[1])[0]
        parts = [part for part, share in node.parts.items() if share >= 0.5] or [top]
        for part in parts:
            functions.setdefault(part, []).append(node.label)
    rules = [
        " AND ".join(sorted(nodes[cause].label for cause in rule.causes)) + f" CAUSES {nodes[rule.effect].label}"
        for rule in entered
    ]
    return {"object": training, "goal": nodes["goal"].label, "functions": functions, "rules": rules}


def _mapping(
    test: str,
    participants: list[Participant],
    readable: dict[str, CausalModel],
    node_of: dict[tuple[str, str], str],
    nodes: dict[str, Node],
    model_data: dict[str, object],
    min_support: float,
    catalog: Catalog,
) -> MappingConsensus:
    """Return the consensus mapping of ``test``: each model function on the parts enough mappers chose."""
    support: dict[tuple[str, str], set[str]] = {}
    mappers: list[str] = []
    for person in participants:
        if person.id not in readable or test not in person.mappings:
            continue
        loaded = mapping_from_data(person.mappings[test], SourceMap(person.where), catalog)
        if loaded.mapping is None:
            continue
        mappers.append(person.id)
        for part, labels in loaded.mapping.functions.items():
            for label in labels:
                key = normalize_label(label)
                node = node_of.get((person.id, key), f"unmodelled: {key}")
                support.setdefault((part, node), set()).add(person.id)
    functions = model_data["functions"]
    assert isinstance(functions, dict)
    in_model = {label for labels in functions.values() for label in labels}
    functions_of_model = {node_id for node_id, node in nodes.items() if node.label in in_model}
    mapped: dict[str, list[str]] = {}
    for (part, node), people in sorted(support.items()):
        if node in functions_of_model and len(people) / max(1, len(mappers)) >= min_support - 1e-9:
            mapped.setdefault(part, []).append(nodes[node].label)
    return MappingConsensus(
        test,
        tuple(mappers),
        {pair: tuple(sorted(people)) for pair, people in sorted(support.items())},
        {"object": test, "functions": mapped},
    )
