"""The errors of troubleshooting: children of ``CausalPlanError``, each with a stable ``code``."""

from __future__ import annotations

from causalplan.errors import CausalPlanError


class TroubleshootError(CausalPlanError):
    """A troubleshooting task that cannot be posed as asked."""

    code = "troubleshoot_error"


class NoFaultsError(TroubleshootError):
    """The object's catalog file lists no faults, so there are no priors to repair it by."""

    code = "object_without_faults"


class UnknownFaultPartError(TroubleshootError):
    """The fault is put on a part the object does not have."""

    code = "unknown_fault_part"


class FaultNotNeededError(TroubleshootError):
    """The fault is put on a part the true mechanism does not need: the object would still work."""

    code = "fault_not_needed"


class MappingMismatchError(TroubleshootError):
    """The model (or its step-3 mapping) does not fit the object: another object, or no way to the goal on it."""

    code = "mapping_does_not_fit"


class NotTroubleshootableError(TroubleshootError):
    """The object's structure is outside what troubleshooting handles (a part attached two ways, no full assembly)."""

    code = "not_troubleshootable"


class TooLargeError(TroubleshootError):
    """The exact solver would need more states than its limit (the object has too many parts)."""

    code = "troubleshooting_too_large"
