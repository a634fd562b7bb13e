"""A catalog overlay: fit probabilities measured elsewhere (``causalplan estimate-fits``) laid over the catalog.

The file (YAML or JSON) names objects and, per fit, the probability to use instead of the
catalog's::

    objects:
      desk_lamp:
        bulb_into_socket: {probability: 0.62, interval: [0.55, 0.68], trials: 200}

Only ``probability`` changes the catalog; the rest says where it came from. An unknown
object or fit, or a probability outside (0, 1], is an error that names it.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import yaml

from causalplan.causal.documents import DuplicateKeyError, load_yaml_refusing_duplicates
from causalplan.errors import CatalogError
from causalplan.objects.catalog import Catalog

MIN_PROBABILITY = 0.001
"""What a fit that never succeeded in its trials is written as: the planners need every fit possible."""


def overlay_data(estimates: dict[str, list[dict[str, object]]], command: str) -> dict[str, object]:
    """Return an overlay file's data for ``estimates`` (per object, ``FitEstimate.as_dict()`` items)."""
    objects: dict[str, object] = {}
    for object_id, fits in estimates.items():
        objects[object_id] = {
            str(fit["id"]): {
                "probability": max(MIN_PROBABILITY, float(str(fit["probability"]))),
                "interval": fit["interval"],
                "trials": fit["trials"],
            }
            for fit in fits
        }
    return {"estimated_by": command, "objects": objects}


def _problem(where: str, message: str, path: Path) -> CatalogError:
    return CatalogError(f"{path}: {where}: {message}", details={"file": str(path), "where": where})


def read_overlay(path: Path) -> dict[str, dict[str, float]]:
    """Return the probabilities an overlay file gives, per object and fit; CatalogError says what is wrong."""
    try:
        data = load_yaml_refusing_duplicates(path.read_text(encoding="utf-8"))
    except DuplicateKeyError as exc:
        where = f" (line {exc.line})" if exc.line is not None else ""
        message = f"{path} names {exc.key!r} twice{where}: keep one."
        raise CatalogError(message, details={"file": str(path), "line": exc.line}) from None
    except OSError as exc:
        raise CatalogError(f"Cannot read the overlay {path}: {exc.strerror}.", details={"file": str(path)}) from None
    except (UnicodeDecodeError, yaml.YAMLError) as exc:
        raise CatalogError(f"{path} is not YAML or JSON: {exc}", details={"file": str(path)}) from None
    if not isinstance(data, dict) or not isinstance(data.get("objects"), dict):
        raise _problem("the file", "needs 'objects': a mapping of object ids to their fits", path)
    found: dict[str, dict[str, float]] = {}
    for object_id, fits in data["objects"].items():
        if not isinstance(fits, dict):
            raise _problem(f"objects > {object_id}", "a mapping of fit ids to {probability: ...}", path)
        found[str(object_id)] = {}
        for fit_id, entry in fits.items():
            where = f"objects > {object_id} > {fit_id}"
            probability = entry.get("probability") if isinstance(entry, dict) else None
            if isinstance(probability, bool) or not isinstance(probability, int | float):
                raise _problem(where, "needs 'probability', a number", path)
            if not 0.0 < probability <= 1.0:
                raise _problem(where, f"probability {probability} is not in (0, 1]", path)
            found[str(object_id)][str(fit_id)] = float(probability)
    return found


def apply_overlay(catalog: Catalog, path: Path) -> Catalog:
    """Return the catalog with the overlay file's probabilities in place of its own."""
    probabilities = read_overlay(path)
    objects = dict(catalog.objects)
    for object_id, fits in probabilities.items():
        if object_id not in objects:
            raise _problem(f"objects > {object_id}", f"there is no object '{object_id}' in the catalog", path)
        obj = objects[object_id]
        known = {fit.id for fit in obj.fits}
        unknown = sorted(set(fits) - known)
        if unknown:
            raise _problem(
                f"objects > {object_id} > {unknown[0]}",
                f"the {obj.name} has no such fit ({', '.join(sorted(known))})",
                path,
            )
        new_fits = tuple(replace(fit, probability=fits.get(fit.id, fit.probability)) for fit in obj.fits)
        objects[object_id] = replace(obj, fits=new_fits)
    return Catalog(objects)
