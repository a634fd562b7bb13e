"""What ``causalplan analyze`` writes: a tidy CSV with its codebook, the JSON of everything, the rates chart."""

from __future__ import annotations

import csv
import json
from pathlib import Path

from causalplan.studies.analysis import Analysis
from causalplan.studies.rates import rates_chart
from causalplan.studies.trials import TrialRow

# One entry per column of trials.csv: (name, type, description). The codebook is written from it.
CODEBOOK: tuple[tuple[str, str, str], ...] = (
    ("trial_id", "text", "The step-3 trial's id in the export."),
    ("participant_id", "text", "The participant's id (one participant can have several trials)."),
    ("condition", "text", "The experiment condition the participant was assigned to."),
    ("training_objects", "text", "The training objects the model was built from, in the order shown, joined by '+'."),
    ("training_span", "text", "'one category' when the training objects share a category, else 'both categories'."),
    ("test_object", "text", "The catalog id of the object the model was tried on."),
    ("test_category", "text", "The test object's category (electric, combustion, ...)."),
    ("trained_category", "0/1", "1 when a training object shares the test object's category."),
    ("generalization", "text", "'near' when trained_category is 1, else 'far'."),
    ("position", "integer", "The trial's place in the participant's order of test objects (1 = first)."),
    ("verdict", "text", "transfers, fails, invalid or undecided (the planner could not decide in time)."),
    ("transferred", "0/1/empty", "1 transfers; 0 fails or invalid; empty when undecided (not analysed)."),
    ("decided_by", "text", "What settled the verdict: validation, precheck, planner or simulator."),
    ("reason_codes", "text", "The verdict's reason codes, joined by ';' (e.g. missing_function)."),
    ("misconception", "text", "Necessary causes the true mechanism does not need, joined by ';' (empty: none)."),
    ("excluded", "0/1", "1 when the participant was screened out; excluded trials are not analysed."),
    ("exclusion_reason", "text", "Why the participant was excluded (empty when included)."),
)


def tidy_row(row: TrialRow, analysis: Analysis) -> dict[str, object]:
    """Return one trial as a CSV row with the codebook's columns."""
    spans = {rate.condition: rate.training_span for rate in analysis.rates}
    found = analysis.misconceptions.get(row.participant_id, ())
    return {
        "trial_id": row.trial_id,
        "participant_id": row.participant_id,
        "condition": row.condition,
        "training_objects": "+".join(row.training_objects),
        "training_span": spans.get(row.condition) or "",
        "test_object": row.test_object,
        "test_category": row.test_category,
        "trained_category": int(row.trained_category),
        "generalization": row.generalization,
        "position": row.position,
        "verdict": row.verdict,
        "transferred": "" if row.outcome is None else row.outcome,
        "decided_by": row.decided_by,
        "reason_codes": ";".join(row.reason_codes),
        "misconception": ";".join(item.function for item in found),
        "excluded": int(row.excluded),
        "exclusion_reason": row.exclusion_reason or "",
    }


def write_outputs(analysis: Analysis, folder: Path) -> list[Path]:
    """Write trials.csv, codebook.csv, analysis.json, rates.png and rates.svg; return their paths."""
    folder.mkdir(parents=True, exist_ok=True)
    written = [folder / name for name in ("trials.csv", "codebook.csv", "analysis.json", "rates.png", "rates.svg")]
    with written[0].open("w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=[name for name, _, _ in CODEBOOK])
        writer.writeheader()
        writer.writerows(tidy_row(row, analysis) for row in analysis.rows)
    with written[1].open("w", newline="", encoding="utf-8") as handle:
        codebook = csv.writer(handle)
        codebook.writerow(["column", "type", "description"])
        codebook.writerows(CODEBOOK)
    written[2].write_text(json.dumps(analysis.as_dict(), indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    written[3].write_bytes(rates_chart(analysis.table, "png"))
    written[4].write_bytes(rates_chart(analysis.table, "svg"))
    return written
