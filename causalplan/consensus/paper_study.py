"""A synthetic run of the paper's design: judge ``paper_population``'s trials and export them for ``analyze``.

Every trial is judged by the real transfer check (planner and true mechanism; the physics
simulator only when asked); identical model-and-mapping pairs are judged once. The result has
the shape of the research pages' export, so ``analyze`` reads it as it reads a real study.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import Any

from causalplan.causal.documents import SourceMap
from causalplan.causal.model import read_model
from causalplan.inputs import LoadedModel, mapping_from_data, merged_model_from_data
from causalplan.objects.catalog import Catalog
from causalplan.transfer.verdict import TransferVerdict, transfer_verdict


def _on_first_object(document: Mapping[str, Any], first: str) -> dict[str, Any]:
    """Return the model as the service stores it: the first training object's labels and all the rules."""
    functions = {
        part.partition(".")[2]: labels for part, labels in document["functions"].items() if part.startswith(f"{first}.")
    }
    return {"object": first, "goal": document["goal"], "functions": functions, "rules": document["rules"]}


def _judge(line: Mapping[str, Any], catalog: Catalog, simulate: bool) -> TransferVerdict:
    checked = merged_model_from_data(line["model"], line["training"], catalog)
    model, _ = read_model(_on_first_object(line["model"], line["training"][0]), SourceMap())
    loaded_model = LoadedModel(model if checked.is_valid else None, checked.report)
    loaded_mapping = mapping_from_data(line["mapping"], SourceMap(), catalog)
    return transfer_verdict(loaded_model, loaded_mapping, catalog, simulate=simulate)


def synthetic_export(
    lines: Sequence[Mapping[str, Any]], catalog: Catalog, name: str = "synthetic", simulate: bool = False
) -> dict[str, Any]:
    """Return the export of a synthetic study: one trial per line, judged, as ``analyze`` reads it."""
    judged: dict[str, TransferVerdict] = {}
    trials = []
    for line in lines:
        key = json.dumps([line["model"], line["mapping"]], sort_keys=True)
        if key not in judged:
            judged[key] = _judge(line, catalog, simulate)
        verdict = judged[key]
        trials.append(
            {
                "trial_id": line["id"],
                "participant_id": line["participant_id"],
                "condition": line["condition"],
                "training_order": list(line["training"]),
                "test_object": line["test"],
                "position": line["position"],
                "verdict": verdict.verdict.value,
                "decided_by": verdict.decided_by,
                "reasons": [{"code": reason.code} for reason in verdict.reasons],
                "model": line["model"],
                "mapping": line["mapping"],
            }
        )
    participants = sorted({str(line["participant_id"]) for line in lines})
    return {
        "experiment": {"name": name},
        "participants": [{"participant_id": p} for p in participants],
        "trials": trials,
    }
