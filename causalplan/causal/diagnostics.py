"""Diagnostics: what is wrong with a person's input, where, and how to fix it."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum


class Severity(StrEnum):
    """How bad a diagnostic is: errors make the input invalid, warnings do not."""

    ERROR = "error"
    WARNING = "warning"


@dataclass(frozen=True)
class Location:
    """Where a diagnostic points: a file line, a rule (1-based index), a part, a label."""

    file: str | None = None
    line: int | None = None
    rule: int | None = None
    part: str | None = None

    def describe(self) -> str:
        """Return the location in words, e.g. ``model.yaml, line 7, rule 2``."""
        pieces: list[str] = []
        if self.file:
            pieces.append(self.file)
        if self.line is not None:
            pieces.append(f"line {self.line}")
        if self.rule is not None:
            pieces.append(f"rule {self.rule}")
        if self.part is not None:
            pieces.append(f"part '{self.part}'")
        return ", ".join(pieces)

    def as_dict(self) -> dict[str, object]:
        """Return the non-empty fields as a JSON-ready dict."""
        return {key: value for key, value in vars(self).items() if value is not None}


@dataclass(frozen=True)
class Diagnostic:
    """One finding: a stable ``code``, a plain-words ``message`` and optional ``hint``."""

    code: str
    severity: Severity
    message: str
    location: Location = field(default_factory=Location)
    hint: str | None = None

    def as_dict(self) -> dict[str, object]:
        """Return the diagnostic as a JSON-ready dict."""
        result: dict[str, object] = {
            "code": self.code,
            "severity": self.severity.value,
            "message": self.message,
            "location": self.location.as_dict(),
        }
        if self.hint:
            result["hint"] = self.hint
        return result


def error(code: str, message: str, location: Location | None = None, hint: str | None = None) -> Diagnostic:
    """Return an error diagnostic."""
    return Diagnostic(code, Severity.ERROR, message, location or Location(), hint)


def warning(code: str, message: str, location: Location | None = None, hint: str | None = None) -> Diagnostic:
    """Return a warning diagnostic."""
    return Diagnostic(code, Severity.WARNING, message, location or Location(), hint)


@dataclass(frozen=True)
class Report:
    """The outcome of validating an input: valid when it has no errors."""

    diagnostics: tuple[Diagnostic, ...] = ()

    @property
    def errors(self) -> list[Diagnostic]:
        return [d for d in self.diagnostics if d.severity is Severity.ERROR]

    @property
    def warnings(self) -> list[Diagnostic]:
        return [d for d in self.diagnostics if d.severity is Severity.WARNING]

    @property
    def is_valid(self) -> bool:
        return not self.errors

    def codes(self) -> list[str]:
        """Return the codes of all diagnostics, in order."""
        return [d.code for d in self.diagnostics]

    def merged(self, other: Report) -> Report:
        """Return a report with the diagnostics of both."""
        return Report(self.diagnostics + other.diagnostics)

    def as_dict(self) -> dict[str, object]:
        """Return the report as a JSON-ready dict."""
        return {
            "valid": self.is_valid,
            "errors": [d.as_dict() for d in self.errors],
            "warnings": [d.as_dict() for d in self.warnings],
        }
