"""Transfer verdicts for many trials at once (e.g. every participant of a study).

A batch file holds one trial per line (JSON Lines: ``{"id": ..., "model": {...},
"mapping": {...}}``, the same schemas as the model and mapping files), or a JSON/YAML list of
such trials. An entry that cannot be read becomes a trial with a ``problem`` (where it is and
why it cannot be read) and no model or mapping; it is judged ``invalid`` and never stops the
batch.

Each trial is decided as cheaply as it can be, and says how (``decided_by``): ``input`` (the
entry could not be read), ``validation`` (an invalid model or mapping), ``precheck`` (a
function the goal needs is carried by no part), ``planner``/``simulator`` otherwise. Equal
planning problems are solved once: Fast Downward runs on the label-free canonical form and its
answers are cached, and a plan's simulation is cached too, so the verdicts are exactly those of
``causalplan transfer`` one trial at a time.
"""

from __future__ import annotations

import csv
import io
import itertools
import json
import time
from collections import Counter
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

from causalplan.causal.diagnostics import Location, Report, Severity, error
from causalplan.causal.documents import NumberTooLongError, SourceMap, read_document, read_integer
from causalplan.errors import InputFileError
from causalplan.inputs import mapping_from_data, model_from_data
from causalplan.objects.catalog import Catalog
from causalplan.planners.val import PlanRejectedError, ValidatorError
from causalplan.transfer.verdict import Reason, TransferVerdict, Verdict, transfer_verdict

TRIAL_FIELDS = ("model", "mapping")
"""The fields every trial must have (``id`` is optional)."""
NAMED_AT_MOST = 5
"""Ids (and rows) a message names; it says how many more there are."""
CSV_FIELDS = ("id", *TRIAL_FIELDS)
"""The columns of a CSV of trials (``id`` may be empty or absent)."""


@dataclass(frozen=True)
class Trial:
    """One (model, mapping) pair to judge and where it came from, or why its entry could not be read."""

    id: str
    model: object
    mapping: object
    line: int | None
    problem: str | None = None
    """Why the entry could not be read, naming where; then there is no model or mapping to judge."""
    is_whole_file: bool = False
    """Whether this stands for the whole batch file, which could not be read (so it holds no trials)."""


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

    def json_line(self) -> str:
        """Return the trial's id and whole verdict as one line of JSON (no newline)."""
        return json.dumps({"id": self.trial_id, **self.verdict.as_dict()})

    def written(self) -> WrittenResult:
        """Return the result as the batch files hold it."""
        return WrittenResult(self.row(), self.json_line())


@dataclass(frozen=True)
class WrittenResult:
    """A trial's result as the batch files hold it: its CSV row and its line of JSON.

    What a cluster worker sends back instead of the whole verdict: plain strings and numbers
    are cheap to ship, and the caller writes them as they are.
    """

    row: dict[str, object]
    json_line: str


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


def _unreadable_trial(trial_id: str, line: int | None, problem: str) -> Trial:
    return Trial(trial_id, None, None, line, problem)


def _unreadable_file(line: int | None, problem: str) -> Trial:
    """Return the one trial of a batch file that cannot be read as a whole."""
    return Trial("file", None, None, line, problem, is_whole_file=True)


def read_trials(path: Path) -> Iterator[Trial]:
    """Yield the trials of a batch file; an entry that cannot be read is a trial with a ``problem``."""
    if path.suffix.lower() == ".jsonl":
        yield from _read_json_lines(path)
        return
    data, _source, problems = read_document(path)
    if problems:
        yield _unreadable_file(problems[0].location.line, f"The batch file could not be read. {problems[0].message}")
        return
    if not isinstance(data, list):
        yield _unreadable_file(
            1,
            "The batch file could not be read: it is not a list of trials "
            "(a JSON Lines file, one trial per line, is named *.jsonl).",
        )
        return
    for index, entry in enumerate(data, start=1):
        yield _trial(entry, f"entry-{index}", f"Entry {index}", None)


def _read_json_lines(path: Path) -> Iterator[Trial]:
    """Yield the trials of a JSON Lines file, one a line; blank lines are skipped."""
    # Bytes, decoded line by line: one line that is not UTF-8 must not stop the others.
    try:
        handle = path.open("rb")
    except OSError as exc:
        yield _unreadable_file(None, f"The batch file could not be read: {exc.strerror}.")
        return
    with handle:
        yield from trials_of_lines(enumerate(handle, start=1))


def trials_of_lines(lines: Iterable[tuple[int, bytes]]) -> Iterator[Trial]:
    """Yield the trials of numbered raw lines of a JSON Lines file; blank lines are skipped.

    Apart from the file, so that a cluster worker can parse its own chunk of lines.
    """
    for number, raw in lines:
        entry, why = _parse_line(raw)
        where = f"Line {number}"
        if why is not None:
            yield _unreadable_trial(f"line-{number}", number, f"{where} could not be read: {why}.")
        elif entry is not _BLANK:
            yield _trial(entry, f"entry-{number}", where, number)


_BLANK = object()
"""What a blank line parses to: it is skipped."""


def is_blank_line(raw: bytes) -> bool:
    """Return whether a raw line of a JSON Lines file is blank: it is skipped, not a trial (as ``_parse_line``)."""
    try:
        return not raw.decode("utf-8-sig").strip()
    except UnicodeDecodeError:
        return False


def _parse_line(raw: bytes) -> tuple[object, str | None]:
    """Return a JSON Lines line's entry (``_BLANK`` for a blank line), or why it cannot be read."""
    try:
        text = raw.decode("utf-8-sig").rstrip("\r\n")
    except UnicodeDecodeError as exc:
        return None, f"it is not UTF-8 text (byte {exc.start})"
    if not text.strip():
        return _BLANK, None
    try:
        return json.loads(text, parse_int=read_integer), None
    except json.JSONDecodeError as exc:
        return None, f"it is not JSON ({exc.msg}, column {exc.colno})"
    except NumberTooLongError as exc:
        return None, f"it holds {exc}"
    except RecursionError:
        return None, "it is nested too deeply"


def _trial(entry: object, default_id: str, where: str, line: int | None) -> Trial:
    """Return the trial of one parsed entry, or an unreadable trial saying what the entry lacks."""
    if not isinstance(entry, dict):
        return _unreadable_trial(
            default_id, line, f"{where} could not be read: it is not an object with 'model' and 'mapping'."
        )
    trial_id = str(entry.get("id", default_id))
    missing = [name for name in TRIAL_FIELDS if name not in entry]
    if missing:
        lacks = " and no ".join(f"'{name}'" for name in missing)
        return _unreadable_trial(trial_id, line, f"{where} could not be read: it has no {lacks}.")
    return Trial(trial_id, entry["model"], entry["mapping"], line)


def csv_to_json_lines(text: str) -> str:
    """Return a CSV of trials (columns id, model, mapping; model and mapping cells hold JSON) as JSON Lines.

    Read as a spreadsheet writes it: with a byte-order mark or not, lines ending in CR LF, LF or a
    bare CR (old Mac and Excel files). A row without an id gets ``row-N`` (N its row, the header
    being row 1). InputFileError names the row and column of a cell that is not JSON (or holds a
    number too long to read), the missing columns, or the rows that share an id.
    """
    # newline="": the csv module splits the lines itself, whichever ending they have (its docs' rule).
    reader = csv.DictReader(io.StringIO(text.removeprefix("\ufeff"), newline=""))
    try:
        columns = list(reader.fieldnames or [])
        rows = list(reader)
    except csv.Error as exc:
        raise InputFileError(
            f"The CSV could not be read at line {reader.line_num}: {exc}.", details={"line": reader.line_num}
        ) from None
    missing = [name for name in TRIAL_FIELDS if name not in columns]
    if missing:
        raise InputFileError(
            f"The CSV has no column {' and no column '.join(repr(name) for name in missing)}; "
            f"its first line must name the columns {', '.join(CSV_FIELDS)}.",
            details={"columns": columns},
        )
    lines: list[str] = []
    rows_of: dict[str, list[int]] = {}
    for number, row in enumerate(rows, start=2):
        trial_id = row.get("id") or f"row-{number}"
        rows_of.setdefault(trial_id, []).append(number)
        entry: dict[str, object] = {"id": trial_id}
        for name in TRIAL_FIELDS:
            entry[name] = _json_cell(row.get(name) or "", number, name)
        lines.append(json.dumps(entry))
    _refuse_shared_ids(rows_of)
    return "\n".join(lines)


def _json_cell(cell: str, row: int, column: str) -> object:
    try:
        return json.loads(cell, parse_int=read_integer)
    except json.JSONDecodeError as exc:
        why = f"is not JSON ({exc.msg}, column {exc.colno})"
    except NumberTooLongError as exc:
        why = f"holds {exc}"
    except RecursionError:
        why = "is nested too deeply"
    raise InputFileError(f"Row {row} of the CSV: the {column} cell {why}.", details={"row": row, "column": column})


def _refuse_shared_ids(rows_of: dict[str, list[int]]) -> None:
    """Raise InputFileError naming every id that more than one row has, with its rows.

    Results are matched to trials by id: two trials with one id cannot be told apart afterwards.
    """
    shared = {trial_id: rows for trial_id, rows in rows_of.items() if len(rows) > 1}
    if not shared:
        return
    named = _some_of(
        (f"{trial_id!r} (rows {_some_of(map(str, rows), len(rows))})" for trial_id, rows in shared.items()),
        len(shared),
        "; ",
    )
    raise InputFileError(
        f"{len(shared)} trial id(s) are used more than once: {named}. Give each trial its own id "
        "(or none: it is then named after its place).",
        details={"duplicate_ids": {trial_id: rows[:100] for trial_id, rows in list(shared.items())[:100]}},
    )


def repeated_ids(ids: Iterable[str]) -> dict[str, int]:
    """Return each trial id that more than one trial has, with how many have it, in the order first seen."""
    return {trial_id: count for trial_id, count in Counter(ids).items() if count > 1}


def repeated_ids_warning(repeated: dict[str, int]) -> str:
    """Return the warning a batch with ``repeated`` ids gets (a JSON Lines file may repeat ids; a CSV may not)."""
    named = _some_of((f"{trial_id!r} ({count} trials)" for trial_id, count in repeated.items()), len(repeated))
    return (
        f"{len(repeated)} trial id(s) are used by more than one trial: {named}. Their results can be told "
        "apart only by their place: every result is in the file's order."
    )


def _some_of(names: Iterable[str], total: int, separator: str = ", ") -> str:
    """Return the first ``NAMED_AT_MOST`` of ``total`` names, joined, and how many more there are."""
    first = list(itertools.islice(names, NAMED_AT_MOST))
    more = f" and {total - len(first)} more" if total > len(first) else ""
    return separator.join(first) + more


def _unreadable_verdict(problem: str, line: int | None) -> TransferVerdict:
    """Return the verdict of an entry that could not be read: ``invalid``, decided by the input alone."""
    report = Report((error("unreadable_trial", problem, Location(line=line)),))
    return TransferVerdict(
        Verdict.INVALID,
        None,
        None,
        None,
        "input",
        (Reason("unreadable_trial", Severity.ERROR, problem),),
        diagnostics={"input": report.as_dict()},
    )


def _unchecked_verdict(exc: PlanRejectedError | ValidatorError, training: str, test: str) -> TransferVerdict:
    """Return the verdict of a trial whose plan VAL rejected or could not check: ``undecided``, with VAL's words."""
    return TransferVerdict(
        Verdict.UNDECIDED, training, test, None, "validator", (Reason(exc.code, Severity.ERROR, exc.message),)
    )


def undecided_results(trials: Iterable[Trial], code: str, message: str) -> list[TrialResult]:
    """Return ``undecided`` results of ``trials`` that could not be judged, each with the reason ``code``."""
    results = []
    for trial in trials:
        model, mapping = trial.model, trial.mapping
        training = model.get("object") if isinstance(model, dict) else None
        test = mapping.get("object") if isinstance(mapping, dict) else None
        verdict = TransferVerdict(
            Verdict.UNDECIDED,
            training if isinstance(training, str) else None,
            test if isinstance(test, str) else None,
            None,
            "worker",
            (Reason(code, Severity.ERROR, message),),
        )
        results.append(TrialResult(trial.id, verdict, 0.0))
    return results


Judge = Callable[[TransferVerdict, Catalog], TransferVerdict]
"""A last judge of a verdict, e.g. the robot (``transfer.robot_verdict.robot_judged``; passed in, so
a batch loads PyBullet only when it is asked to)."""


def evaluate_trial(
    trial: Trial,
    catalog: Catalog,
    planner: str,
    time_limit: float,
    simulate: bool,
    val: bool = False,
    judge: Judge | None = None,
) -> TrialResult:
    """Return the verdict of one trial (never raises for bad input; a plan VAL rejects is ``undecided``).

    ``judge`` has the last word on the verdict (e.g. the robot's).
    """
    started = time.perf_counter()
    if trial.problem is not None:
        verdict = _unreadable_verdict(trial.problem, trial.line)
    else:
        source = SourceMap(f"line {trial.line}" if trial.line else None)
        loaded_model = model_from_data(trial.model, source, catalog)
        loaded_mapping = mapping_from_data(trial.mapping, source, catalog)
        try:
            verdict = transfer_verdict(loaded_model, loaded_mapping, catalog, planner, time_limit, simulate, val=val)
            if judge is not None:
                verdict = judge(verdict, catalog)
        except (PlanRejectedError, ValidatorError) as exc:
            assert loaded_model.model is not None and loaded_mapping.mapping is not None  # only valid ones plan
            verdict = _unchecked_verdict(exc, loaded_model.model.object_id, loaded_mapping.mapping.object_id)
    return TrialResult(trial.id, verdict, time.perf_counter() - started)


def run_batch(
    trials: list[Trial],
    catalog: Catalog,
    planner: str = "auto",
    time_limit: float = 30.0,
    simulate: bool = True,
    progress: Callable[[], None] | None = None,
    val: bool = False,
    judge: Judge | None = None,
) -> list[TrialResult]:
    """Return the results of every trial, in order; ``val``: VAL checks each plan, ``judge`` has the last word."""
    results = []
    for trial in trials:
        results.append(evaluate_trial(trial, catalog, planner, time_limit, simulate, val, judge))
        if progress is not None:
            progress()
    return results
