"""The exception root of causalplan: every error a user can cause has a stable ``code``."""

from __future__ import annotations


class CausalPlanError(Exception):
    """Base of all causalplan errors; ``code`` is stable and safe to match on."""

    code = "causalplan_error"

    def __init__(self, message: str, *, details: dict[str, object] | None = None) -> None:
        super().__init__(message)
        self.message = message
        self.details = details or {}


class InputFileError(CausalPlanError):
    """A file could not be read or parsed (missing, unreadable, malformed YAML/JSON)."""

    code = "input_file_error"


class CatalogError(CausalPlanError):
    """An object file of the catalog is malformed or inconsistent."""

    code = "catalog_error"


class UnknownObjectError(CausalPlanError):
    """An object id is not in the catalog."""

    code = "unknown_object"


class PlannerUnavailableError(CausalPlanError):
    """A planner binary or module could not be found or imported."""

    code = "planner_unavailable"
