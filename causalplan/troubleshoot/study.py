"""Troubleshooting as a dependent measure of a study: do the participants' models help the robot repair?

Reads an experiment export (the research page's JSON: each trial with its ``condition``,
``test_object``, ``model`` and ``mapping``) and, per condition and test object, solves the
exact policy of every participant's model (through their step-3 mapping) on the broken test
object, scored under the catalog's fault priors, beside ``uniform`` (no model) and ``oracle``
(the catalog's priors). Trials of excluded participants are left out. A trial whose model or
mapping cannot be read back, or whose mapping reaches no goal on the object, is counted as
not scored, never guessed.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from causalplan.causal.diagnostics import Report
from causalplan.causal.documents import SourceMap
from causalplan.causal.model import CausalModel, read_model
from causalplan.errors import CausalPlanError
from causalplan.inputs import mapping_from_data, model_from_data
from causalplan.objects.catalog import Catalog
from causalplan.troubleshoot.measures import StrategyResult, score
from causalplan.troubleshoot.priors import model_suspicion
from causalplan.troubleshoot.solver import solve
from causalplan.troubleshoot.task import TroubleshootingTask, troubleshooting_task

MAX_TRIAL_STATES = 1_000_000
"""The (belief, assembly) states one trial may solve: every catalog object needs far fewer."""


@dataclass
class TroubleshootingByObject:
    """One condition on one test object: the participants' models' expected actions against the baselines."""

    condition: str
    test_object: str
    uniform: float | None = None
    oracle: float | None = None
    model_actions: list[float] = field(default_factory=list)
    """Each scored trial's expected actions to the repair under the catalog's priors."""
    not_scored: int = 0

    @property
    def mean_model(self) -> float | None:
        return sum(self.model_actions) / len(self.model_actions) if self.model_actions else None

    @property
    def better_than_uniform(self) -> int:
        """Return how many models need fewer expected actions than no model."""
        return sum(1 for actions in self.model_actions if self.uniform is not None and actions < self.uniform - 1e-9)

    def summary(self) -> str:
        """Return the row in one sentence."""
        if self.mean_model is None or self.uniform is None or self.oracle is None:
            return (
                f"{self.condition} on the {self.test_object}: no model could be scored ({self.not_scored} not scored)."
            )
        words = (
            f"{self.condition} on the {self.test_object}: the participants' models need {self.mean_model:.2f} expected "
            f"actions to repair it (no model {self.uniform:.2f}, the catalog's priors {self.oracle:.2f}); "
            f"{self.better_than_uniform} of {len(self.model_actions)} do better than no model"
        )
        return words + (f" ({self.not_scored} not scored)." if self.not_scored else ".")

    def as_dict(self) -> dict[str, object]:
        return {
            "condition": self.condition,
            "test_object": self.test_object,
            "scored": len(self.model_actions),
            "not_scored": self.not_scored,
            "model_mean_expected_actions": None if self.mean_model is None else round(self.mean_model, 6),
            "uniform_expected_actions": None if self.uniform is None else round(self.uniform, 6),
            "oracle_expected_actions": None if self.oracle is None else round(self.oracle, 6),
            "better_than_uniform": self.better_than_uniform,
            "summary": self.summary(),
        }


def _excluded(export: Mapping[str, Any]) -> set[str]:
    participants = export.get("participants")
    if not isinstance(participants, list):
        return set()
    return {str(item.get("participant_id")) for item in participants if isinstance(item, dict) and item.get("excluded")}


def _model_of(document: object, catalog: Catalog) -> CausalModel | None:
    """Return a trial's model, enough to troubleshoot with (its rules and goal); None when it cannot be read.

    A model file's form (``object``, ``functions``, ``rules``) is validated as a file is. A
    study's form keeps step 1's functions per training object, without ``object``: the study
    checked it at step 2, and the rules and the goal are all the mapping needs, so only they
    are read back (their syntax checked).
    """
    if not isinstance(document, Mapping):
        return None
    if "object" in document:
        loaded = model_from_data(document, SourceMap(), catalog)
        return loaded.model if loaded.is_valid else None
    rules_only = {
        "object": "study",
        "goal": document.get("goal", "light"),
        "functions": {},
        "rules": document.get("rules"),
    }
    model, problems = read_model(rules_only, SourceMap())
    return model if model is not None and Report(tuple(problems)).is_valid else None


def troubleshooting_by_object(export: Mapping[str, Any], catalog: Catalog) -> list[TroubleshootingByObject]:
    """Return, per (condition, test object) in the order met, the models' troubleshooting against the baselines."""
    trials = export.get("trials")
    rows: dict[tuple[str, str], TroubleshootingByObject] = {}
    # Each test object's task and its baselines' table, made once (None: it cannot be troubleshot).
    baselines: dict[str, tuple[TroubleshootingTask, dict[str, StrategyResult]] | None] = {}
    excluded = _excluded(export)
    for item in trials if isinstance(trials, list) else []:
        if not isinstance(item, dict) or str(item.get("participant_id")) in excluded:
            continue
        test_object = str(item.get("test_object"))
        key = (str(item.get("condition")), test_object)
        row = rows.setdefault(key, TroubleshootingByObject(*key))
        if test_object not in baselines:
            try:
                task = troubleshooting_task(catalog.get(test_object), max_states=MAX_TRIAL_STATES)
            except CausalPlanError:
                baselines[test_object] = None
            else:
                baselines[test_object] = (task, task.table())
        baseline = baselines[test_object]
        if baseline is None:
            row.not_scored += 1
            continue
        base, table = baseline
        row.uniform, row.oracle = table["uniform"].expected_actions, table["oracle"].expected_actions
        model = _model_of(item.get("model"), catalog)
        mapping = mapping_from_data(item.get("mapping"), SourceMap(), catalog)
        if model is None or mapping.mapping is None or not mapping.is_valid:
            row.not_scored += 1
            continue
        try:
            believed = model_suspicion(model.rules, model.goal_key, mapping.mapping, base.obj)
            policy = solve(base.structure, believed.suspicion, MAX_TRIAL_STATES)
        except CausalPlanError:
            row.not_scored += 1
            continue
        row.model_actions.append(score(policy, base.obj)[0].expected_actions)
    return list(rows.values())
