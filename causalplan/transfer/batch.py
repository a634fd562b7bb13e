"""Transfer verdicts for many trials at once (e.g. every participant of a study).

A batch file holds one trial per line (JSON Lines: ``{"id": ..., "model": {...},
"mapping": {...}}``, the same schemas as the model and mapping files), or a JSON/YAML list of
such trials. A line that cannot be read becomes an ``invalid`` trial that names its line; it
never stops the batch.

Each trial is decided as cheaply as it can be, and says how (``decided_by``): ``validation``
(an invalid model or mapping), ``precheck`` (a function the goal needs is carried by no part),
``planner``/``simulator`` otherwise. Equal planning problems are solved once: Fast Downward
runs on the label-free canonical form and its answers are cached, and a plan's simulation is
cached too, so the verdicts are exactly those of ``causalplan transfer`` one trial at a time.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from causalplan.causal.diagnostics import Location, Report, error
from causalplan.causal.documents import SourceMap, read_document
from causalplan.inputs import mapping_from_data, model_from_data
from causalplan.objects.catalog import Catalog
from causalplan.transfer.verdict import TransferVerdict, invalid_verdict, transfer_verdict


@dataclass(frozen=True)
class Trial:
    """One (model, mapping) pair to judge, with where it came from."""

    id: str
    model: object
    mapping: object
    line: int | None


@dataclass(frozen=True)
class TrialResult:
    """A trial's verdict, and how long it took."""

    trial_id: str
    verdict: TransferVerdict
    seconds: float

    def row(self) -> dict[str, object]:
        """Return one flat CSV row."""
        verdict, plan = self.verdict, self.verdict.plan
        return {
            "id": self.trial_id,
            "verdict": verdict.verdict.value,
            "training_object": verdict.training_object,
            "test_object": verdict.test_object,
            "generalization": verdict.generalization,
            "decided_by": verdict.decided_by,
            "reasons": ";".join(reason.code for reason in verdict.reasons),
            "plan_length": len(plan.steps) if plan and plan.has_plan else "",
            "seconds": round(self.seconds, 6),
        }


CSV_COLUMNS = (
    "id",
    "verdict",
    "training_object",
    "test_object",
    "generalization",
    "decided_by",
    "reasons",
    "plan_length",
    "seconds",
)


def _unreadable(trial_id: str, line: int | None, message: str) -> Trial:
    return Trial(trial_id, {"__unreadable__": message}, None, line)


def read_trials(path: Path) -> Iterator[Trial]:
    """Yield the trials of a batch file; unreadable entries become trials that will be invalid."""
    if path.suffix.lower() == ".jsonl":
        with path.open(encoding="utf-8") as handle:
            for number, text in enumerate(handle, start=1):
                if not text.strip():
                    continue
                try:
                    entry = json.loads(text)
                except json.JSONDecodeError as exc:
                    yield _unreadable(f"line-{number}", number, f"line {number} is not JSON: {exc.msg}")
                    continue
                yield _trial(entry, number, number)
        return
    data, _source, problems = read_document(path)
    if problems:
        yield _unreadable("file", problems[0].location.line, problems[0].message)
        return
    if not isinstance(data, list):
        yield _unreadable("file", 1, "a batch file is a list of trials (or JSON Lines, one trial per line)")
        return
    for index, entry in enumerate(data, start=1):
        yield _trial(entry, index, None)


def _trial(entry: object, position: int, line: int | None) -> Trial:
    if not isinstance(entry, dict) or "model" not in entry or "mapping" not in entry:
        where = f"line {line}" if line else f"entry {position}"
        return _unreadable(f"entry-{position}", line, f"{where} needs 'model' and 'mapping' (and may have 'id')")
    return Trial(str(entry.get("id", f"entry-{position}")), entry["model"], entry["mapping"], line)


def evaluate_trial(trial: Trial, catalog: Catalog, planner: str, time_limit: float, simulate: bool) -> TrialResult:
    """Return the verdict of one trial (never raises for bad input)."""
    started = time.perf_counter()
    where = f"line {trial.line}" if trial.line else None
    if isinstance(trial.model, dict) and "__unreadable__" in trial.model:
        report = Report((error("invalid_input", str(trial.model["__unreadable__"]), Location(file=where)),))
        verdict = invalid_verdict(report, Report(), None, None)
    else:
        loaded_model = model_from_data(trial.model, SourceMap(where), catalog)
        loaded_mapping = mapping_from_data(trial.mapping, SourceMap(where), catalog)
        verdict = transfer_verdict(loaded_model, loaded_mapping, catalog, planner, time_limit, simulate)
    return TrialResult(trial.id, verdict, time.perf_counter() - started)


def run_batch(
    trials: list[Trial],
    catalog: Catalog,
    planner: str = "auto",
    time_limit: float = 30.0,
    simulate: bool = True,
    progress: Callable[[], None] | None = None,
) -> list[TrialResult]:
    """Return the results of every trial, in order."""
    results = []
    for trial in trials:
        results.append(evaluate_trial(trial, catalog, planner, time_limit, simulate))
        if progress is not None:
            progress()
    return results
