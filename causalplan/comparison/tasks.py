"""The tasks a comparison runs: example models (with or without a mapping) and synthetic objects.

A task is described by a plain JSON-ready spec, so a fresh worker process can rebuild it:
``{"model": path, "mapping": path | None, "catalog": [dirs]}`` or ``{"synthetic": n, "seed": s}``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from causalplan.causal.documents import read_document
from causalplan.errors import CausalPlanError, InputFileError
from causalplan.objects.catalog import load_catalog
from causalplan.pddl.task import PlanningTask

DEFAULT_TASKS: tuple[tuple[str, str | None], ...] = (
    ("examples/paper/desk_lamp.yaml", None),
    ("examples/paper/failed_desk_lamp.yaml", None),
    ("examples/near/candle.yaml", None),
    ("examples/paper/desk_lamp.yaml", "examples/paper/flashlight_mapping.yaml"),
    ("examples/near/candle.yaml", "examples/near/kerosene_lamp_mapping.yaml"),
    ("examples/far/abstract_desk_lamp.yaml", "examples/far/candle_mapping.yaml"),
)
"""The paper's examples, run when no task is named (paths relative to the repository)."""


@dataclass(frozen=True)
class ComparisonTask:
    """One task of a comparison: a name for the table, its object's size, how to rebuild it."""

    name: str
    parts: int
    spec: dict[str, object] = field(hash=False)


def _name(model: Path, mapping: Path | None) -> str:
    def short(path: Path) -> str:
        return f"{path.parent.name}/{path.stem}"

    return short(model) if mapping is None else f"{short(model)} -> {short(mapping)}"


def _file_error(path: Path, message: str) -> InputFileError:
    return InputFileError(f"{path}: {message}", details={"file": str(path)})


def _read(path: Path) -> object:
    """Return the data of a YAML/JSON file; InputFileError when it cannot be read."""
    data, _source, problems = read_document(path)
    if problems:
        raise _file_error(path, problems[0].message)
    return data


def build(spec: dict[str, object]) -> PlanningTask:
    """Rebuild a task from its spec (in a worker process); CausalPlanError says what is wrong."""
    if "synthetic" in spec:
        from causalplan.comparison.synthetic import synthetic_task

        return synthetic_task(int(str(spec["synthetic"])), int(str(spec.get("seed", 0))))
    from causalplan.inputs import load_mapping, load_model
    from causalplan.pddl.task import build_task

    folders = [Path(str(folder)) for folder in spec.get("catalog", []) or []]  # type: ignore[attr-defined]
    catalog = load_catalog(folders)
    model_path = Path(str(spec["model"]))
    loaded = load_model(model_path, catalog)
    if not loaded.is_valid or loaded.model is None:
        raise _file_error(model_path, loaded.report.errors[0].message)
    mapping = None
    if spec.get("mapping"):
        mapping_path = Path(str(spec["mapping"]))
        loaded_mapping = load_mapping(mapping_path, catalog)
        if not loaded_mapping.is_valid or loaded_mapping.mapping is None:
            raise _file_error(mapping_path, loaded_mapping.report.errors[0].message)
        mapping = loaded_mapping.mapping
    target = catalog.get(mapping.object_id if mapping else loaded.model.object_id)
    return build_task(loaded.model, target, mapping)


def from_files(model: Path, mapping: Path | None, catalog_folders: list[Path]) -> ComparisonTask:
    """Return the task of a model (and mapping), checking now that it builds.

    Paths are made absolute: the worker that rebuilds the task runs in a folder of its own.
    """
    spec: dict[str, object] = {
        "model": str(model.resolve()),
        "mapping": str(mapping.resolve()) if mapping else None,
        "catalog": [str(folder.resolve()) for folder in catalog_folders],
    }
    task = build(spec)
    return ComparisonTask(_name(model, mapping), len(task.obj.parts), spec)


def _from_task_file(path: Path, data: dict[str, Any], catalog_folders: list[Path]) -> ComparisonTask:
    """Return the task of a task file's ``data``: ``model``, optional ``mapping`` and ``catalog`` (paths from it)."""
    base = path.parent

    def resolve(value: object) -> Path:
        return (base / str(value)).resolve()

    extra = [resolve(folder) for folder in data.get("catalog", []) or []]
    return from_files(
        resolve(data["model"]), resolve(data["mapping"]) if data.get("mapping") else None, [*catalog_folders, *extra]
    )


def from_argument(path: Path, catalog_folders: list[Path]) -> ComparisonTask:
    """Return the task a command-line argument names: a model file or a task file."""
    data = _read(path)
    if isinstance(data, dict) and "model" in data and "rules" not in data:
        return _from_task_file(path, data, catalog_folders)
    return from_files(path, None, catalog_folders)


def synthetic(parts: int, seed: int = 0) -> ComparisonTask:
    """Return a synthetic task of ``parts`` parts."""
    from causalplan.comparison.synthetic import MAX_PARTS, MIN_PARTS

    if not MIN_PARTS <= parts <= MAX_PARTS:
        raise CausalPlanError(f"Synthetic tasks have {MIN_PARTS} to {MAX_PARTS} parts, not {parts}.")
    return ComparisonTask(f"synthetic-{parts}", parts, {"synthetic": parts, "seed": seed})


def default_tasks(root: Path) -> list[ComparisonTask]:
    """Return the paper's example tasks, found under ``root``; InputFileError if they are not there."""
    missing = [model for model, _ in DEFAULT_TASKS if not (root / model).exists()]
    if missing:
        raise InputFileError(
            f"The paper's examples are not under {root} (no {missing[0]}): name model files, "
            "or run from the causalplan repository, or use --synthetic."
        )
    return [from_files(root / model, root / mapping if mapping else None, []) for model, mapping in DEFAULT_TASKS]
