"""Reading a person's model and mapping from files or data, validated against the catalog."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from causalplan.causal.diagnostics import Report
from causalplan.causal.documents import SourceMap, parse_text, read_document
from causalplan.causal.model import CausalModel, Labelling, read_labelling, read_model
from causalplan.causal.validation import ObjectSummary, validate_mapping, validate_model
from causalplan.objects.catalog import Catalog


@dataclass(frozen=True)
class LoadedModel:
    """A model as far as it could be read (None when unreadable), and its validation report."""

    model: CausalModel | None
    report: Report

    @property
    def is_valid(self) -> bool:
        return self.model is not None and self.report.is_valid


@dataclass(frozen=True)
class LoadedMapping:
    """A step-3 mapping as far as it could be read, and its validation report."""

    mapping: Labelling | None
    report: Report

    @property
    def is_valid(self) -> bool:
        return self.mapping is not None and self.report.is_valid


def model_from_data(data: object, source: SourceMap, catalog: Catalog) -> LoadedModel:
    """Read and validate a model from parsed data (a dict in the file schema)."""
    model, problems = read_model(data, source)
    if model is None:
        return LoadedModel(None, Report(tuple(problems)))
    return LoadedModel(model, validate_model(model, catalog.summaries(), problems))


def merged_model_from_data(data: Mapping[str, Any], object_ids: Sequence[str], catalog: Catalog) -> LoadedModel:
    """Read and validate a model of several objects in one document (parts named ``object.part``), against them all."""
    model, problems = read_model(dict(data), SourceMap())
    if model is None:
        return LoadedModel(None, Report(tuple(problems)))
    objects = [catalog.get(object_id) for object_id in object_ids]
    summary = ObjectSummary(
        str(data["object"]),
        tuple(f"{obj.id}.{part}" for obj in objects for part in obj.part_ids),
        objects[0].goal,
        " and ".join(obj.name for obj in objects),
    )
    return LoadedModel(model, validate_model(model, {summary.id: summary}, problems))


def mapping_from_data(data: object, source: SourceMap, catalog: Catalog) -> LoadedMapping:
    """Read and validate a step-3 mapping from parsed data."""
    mapping, problems = read_labelling(data, source)
    if mapping is None:
        return LoadedMapping(None, Report(tuple(problems)))
    return LoadedMapping(mapping, validate_mapping(mapping, catalog.summaries(), problems))


def load_model(path: Path, catalog: Catalog) -> LoadedModel:
    """Read and validate a model file (YAML or JSON)."""
    data, source, problems = read_document(path)
    if problems:
        return LoadedModel(None, Report(tuple(problems)))
    return model_from_data(data, source, catalog)


def load_mapping(path: Path, catalog: Catalog) -> LoadedMapping:
    """Read and validate a step-3 mapping file (YAML or JSON)."""
    data, source, problems = read_document(path)
    if problems:
        return LoadedMapping(None, Report(tuple(problems)))
    return mapping_from_data(data, source, catalog)


def model_from_text(text: str, catalog: Catalog, file_name: str | None = None) -> LoadedModel:
    """Read and validate a model from YAML or JSON text."""
    data, source, problems = parse_text(text, file_name)
    if problems:
        return LoadedModel(None, Report(tuple(problems)))
    return model_from_data(data, source, catalog)


def clean_text(text: str) -> str:
    """Return ``text`` with NUL and unpaired surrogates replaced by U+FFFD (storable everywhere)."""
    if text.isascii() and "\x00" not in text:
        return text
    return "".join("\ufffd" if char == "\x00" or "\ud800" <= char <= "\udfff" else char for char in text)
