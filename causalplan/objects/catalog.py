"""The object catalog: the built-in objects shipped as data files, plus a user's own folder.

Checking an object file needs pydantic and its schema, which are slow to import; a file that was
checked before is read back from ``objects.cache`` instead, keyed by its exact text.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, replace
from functools import cached_property
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from causalplan.causal.diagnostics import Location
from causalplan.causal.documents import parse_text
from causalplan.causal.labels import closest
from causalplan.causal.validation import ObjectSummary
from causalplan.errors import CatalogError, UnknownObjectError
from causalplan.objects.cache import cached_object
from causalplan.objects.model import AssemblyObject, Connector, Fault, Fit, Grasp, Part, Requirement
from causalplan.objects.shapes import build_geometry, unit

if TYPE_CHECKING:
    from pydantic import ValidationError

    from causalplan.objects.schema import FaultsSchema, FitSchema, ObjectSchema

OBJECT_FILE_SUFFIXES = (".yaml", ".yml", ".json")


def _split_endpoint(endpoint: str, field: str, fit_id: str, connectors: set[tuple[str, str]]) -> tuple[str, str]:
    part, _, connector = endpoint.partition(".")
    if (part, connector) not in connectors:
        raise ValueError(f"fit '{fit_id}': {field} '{endpoint}' is not a 'part.connector' of this object")
    return part, connector


def _build_fit(schema: FitSchema, specs: dict[tuple[str, str], str]) -> Fit:
    endpoints = set(specs)
    moving = _split_endpoint(schema.moving, "moving", schema.id, endpoints)
    fixed = _split_endpoint(schema.fixed, "fixed", schema.id, endpoints)
    if moving[0] == fixed[0]:
        raise ValueError(f"fit '{schema.id}' attaches part '{moving[0]}' to itself")
    if specs[moving] != specs[fixed]:
        raise ValueError(
            f"fit '{schema.id}': {schema.moving} ({specs[moving]}) does not fit "
            f"{schema.fixed} ({specs[fixed]}); connectors that fit share a spec"
        )
    blocks = tuple(_split_endpoint(item, "blocks", schema.id, endpoints) for item in schema.blocks)
    if schema.text is not None:
        try:
            schema.text.format(moving="", fixed="")
        except (KeyError, IndexError, ValueError) as exc:
            raise ValueError(f"fit '{schema.id}': text may only use {{moving}} and {{fixed}} ({exc})") from exc
    return Fit(
        schema.id,
        schema.primitive,
        *moving,
        *fixed,
        schema.probability,
        blocks,
        schema.text,
        schema.tolerance_mm,
        schema.tolerance_deg,
    )


FAULT_PRIORS_SUM_TOLERANCE = 1e-6


def _build_faults(schema: FaultsSchema, obj: AssemblyObject) -> tuple[Fault, ...]:
    """Cross-check the faults against the object (known parts, once each, needed, priors summing to 1)."""
    parts = [fault.part for fault in schema.parts]
    unknown = sorted(set(parts) - set(obj.part_ids))
    if unknown:
        raise ValueError(f"faults: {', '.join(unknown)} is not a part of this object ({', '.join(obj.part_ids)})")
    duplicates = sorted({part for part in parts if parts.count(part) > 1})
    if duplicates:
        raise ValueError(f"faults: part(s) {', '.join(duplicates)} listed twice")
    not_needed = [part for part in parts if not obj.is_needed(part)]
    if not_needed:
        raise ValueError(
            f"faults: the true mechanism does not need {', '.join(not_needed)}, so it cannot be what stops the "
            f"{obj.goal}; list only parts that every way of meeting some requirement uses"
        )
    total = sum(fault.probability for fault in schema.parts)
    if abs(total - 1.0) > FAULT_PRIORS_SUM_TOLERANCE:
        raise ValueError(f"faults: the probabilities sum to {total:g}, not 1 (one part is broken)")
    return tuple(Fault(fault.part, fault.probability, fault.looks, fault.visible) for fault in schema.parts)


def build_object(schema: ObjectSchema) -> AssemblyObject:
    """Cross-check a schema-valid object file and return the object; ValueError says what is wrong."""
    from causalplan.objects.schema import RESERVED_WORDS

    part_ids = [part.id for part in schema.parts]
    fit_ids = [fit.id for fit in schema.fits]
    for ids, what in ((part_ids, "part"), (fit_ids, "fit")):
        duplicates = sorted({item for item in ids if ids.count(item) > 1})
        if duplicates:
            raise ValueError(f"duplicate {what} id(s): {', '.join(duplicates)}")
    clashes = sorted((set(part_ids) & set(fit_ids)) | ((set(part_ids) | set(fit_ids)) & RESERVED_WORDS))
    if clashes:
        raise ValueError(f"id(s) {', '.join(clashes)} clash with another id or a PDDL keyword")
    if schema.base not in part_ids:
        raise ValueError(f"base '{schema.base}' is not one of the parts ({', '.join(part_ids)})")
    specs: dict[tuple[str, str], str] = {}
    for part in schema.parts:
        for connector in part.connectors:
            if (part.id, connector.id) in specs:
                raise ValueError(f"part '{part.id}' has two connectors '{connector.id}'")
            specs[(part.id, connector.id)] = connector.spec
    fits = tuple(_build_fit(fit, specs) for fit in schema.fits)
    for requirement in schema.mechanism.requires:
        unknown = [fit_id for fit_id in requirement.any if fit_id not in fit_ids]
        if unknown:
            raise ValueError(f"mechanism requirement '{requirement.says}' names unknown fit(s): {', '.join(unknown)}")
        unknown = [fit_id for fit_id in requirement.after if fit_id not in fit_ids]
        if unknown:
            raise ValueError(
                f"mechanism requirement '{requirement.says}': 'after' names unknown fit(s): {', '.join(unknown)}"
            )
        itself = sorted(set(requirement.after) & set(requirement.any))
        if itself:
            raise ValueError(
                f"mechanism requirement '{requirement.says}': fit(s) {', '.join(itself)} cannot come after themselves"
            )
    obj = AssemblyObject(
        id=schema.id,
        name=schema.name,
        category=schema.category,
        goal=schema.goal,
        description=schema.description,
        base=schema.base,
        parts=tuple(
            Part(
                p.id,
                p.name,
                tuple(Connector(c.id, c.kind, c.spec, c.at, unit(c.axis) if c.axis else None) for c in p.connectors),
                build_geometry(p.geometry) if p.geometry else None,
                Grasp(p.grasp.at, unit(p.grasp.approach), unit(p.grasp.fingers), p.grasp.width) if p.grasp else None,
            )
            for p in schema.parts
        ),
        fits=fits,
        mechanism=tuple(
            Requirement(tuple(r.any), r.says, r.function, tuple(r.after)) for r in schema.mechanism.requires
        ),
        mechanism_explanation=schema.mechanism.explanation,
    )
    if schema.faults is None:
        return obj
    return replace(obj, faults=_build_faults(schema.faults, obj), fault_priors=schema.faults.priors)


def _describe_validation_error(exc: ValidationError) -> str:
    lines = []
    for item in exc.errors():
        where = " > ".join(str(piece) for piece in item["loc"]) or "the file"
        lines.append(f"{where}: {item['msg']}")
    return "; ".join(lines)


def parse_object(text: str, file_name: str) -> AssemblyObject:
    """Parse one object file's text (or take it from the cache); CatalogError says what is wrong and where."""
    return cached_object(text, lambda: _parse_object(text, file_name))


def _parse_object(text: str, file_name: str) -> AssemblyObject:
    from pydantic import ValidationError

    from causalplan.objects.schema import ObjectSchema

    data, source, problems = parse_text(text, file_name)
    if problems:
        raise CatalogError(
            f"{file_name}: {problems[0].message}", details={"file": file_name, **problems[0].location.as_dict()}
        )
    try:
        schema = ObjectSchema.model_validate(data)
    except ValidationError as exc:
        first_loc = exc.errors()[0]["loc"]
        location: Location = source.locate(*first_loc)
        raise CatalogError(
            f"{file_name}: {_describe_validation_error(exc)}", details={"file": file_name, **location.as_dict()}
        ) from None
    try:
        return build_object(schema)
    except ValueError as exc:
        raise CatalogError(f"{file_name}: {exc}", details={"file": file_name}) from None


def _builtin_files() -> Iterator[tuple[str, str]]:
    folder = resources.files("causalplan.objects") / "data"
    for entry in sorted(folder.iterdir(), key=lambda item: item.name):
        if entry.name.endswith(OBJECT_FILE_SUFFIXES):
            yield f"causalplan/objects/data/{entry.name}", entry.read_text(encoding="utf-8")


def _user_files(folder: Path) -> Iterator[tuple[str, str]]:
    if not folder.is_dir():
        raise CatalogError(
            f"The catalog folder {folder} does not exist or is not a folder.", details={"file": str(folder)}
        )
    for path in sorted(folder.iterdir()):
        if path.suffix.lower() in OBJECT_FILE_SUFFIXES:
            try:
                text = path.read_text(encoding="utf-8")
            except (OSError, UnicodeDecodeError) as exc:
                raise CatalogError(f"{path} cannot be read as UTF-8 text: {exc}", details={"file": str(path)}) from None
            yield str(path), text


@dataclass(frozen=True)
class Catalog:
    """All objects known to a run, by id."""

    objects: dict[str, AssemblyObject]

    def get(self, object_id: str) -> AssemblyObject:
        """Return the object with this id; UnknownObjectError suggests a close id."""
        try:
            return self.objects[object_id]
        except KeyError:
            guess = closest(object_id, sorted(self.objects))
            hint = f" Did you mean '{guess}'?" if guess else ""
            raise UnknownObjectError(
                f"There is no object '{object_id}' in the catalog.{hint}", details={"object": object_id}
            ) from None

    @cached_property
    def _summaries(self) -> Mapping[str, ObjectSummary]:
        return {obj.id: ObjectSummary(obj.id, obj.part_ids, obj.goal, obj.name) for obj in self.objects.values()}

    def summaries(self) -> Mapping[str, ObjectSummary]:
        """Return what model validation needs to know of each object (worked out once per catalog)."""
        return self._summaries


def load_catalog(extra_folders: Iterable[Path] = ()) -> Catalog:
    """Return the built-in catalog plus the objects in ``extra_folders`` (ids must be new)."""
    objects: dict[str, AssemblyObject] = {}
    origins: dict[str, str] = {}
    sources: list[Iterable[tuple[str, str]]] = [_builtin_files(), *(_user_files(folder) for folder in extra_folders)]
    for files in sources:
        for name, text in files:
            obj = parse_object(text, name)
            if obj.id in objects:
                raise CatalogError(
                    f"{name}: object id '{obj.id}' is already defined by {origins[obj.id]}.", details={"file": name}
                )
            objects[obj.id] = obj
            origins[obj.id] = name
    return Catalog(objects)
