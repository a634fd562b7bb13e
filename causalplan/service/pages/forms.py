"""Reading the pages' HTML forms (``application/x-www-form-urlencoded``) with clear errors.

The forms are small and have no file fields, so the standard library parses them; the
body's size is already bounded by the app's body limit.
"""

from __future__ import annotations

from urllib.parse import parse_qs

from fastapi import Request

from causalplan.causal.labels import has_control_characters
from causalplan.service.errors import InvalidFormError

MAX_FIELDS = 2000
FORM_TYPE = "application/x-www-form-urlencoded"


class Form:
    """The fields of a submitted form: one or several values per name."""

    def __init__(self, fields: dict[str, list[str]]) -> None:
        self.fields = fields

    def text(self, name: str, default: str | None = None, max_length: int = 10_000) -> str:
        """Return the one value of ``name`` (``default`` when absent); InvalidFormError when it is not one value."""
        values = self.fields.get(name)
        if not values:
            if default is None:
                raise InvalidFormError(f"The form has no '{name}' field.", details={"field": name})
            return default
        if len(values) > 1:
            raise InvalidFormError(f"The form has the field '{name}' {len(values)} times.", details={"field": name})
        if len(values[0]) > max_length:
            raise InvalidFormError(
                f"The field '{name}' is {len(values[0])} characters long; the limit is {max_length}.",
                details={"field": name, "limit": max_length},
            )
        return values[0]

    def texts(self, name: str, max_count: int = 100, max_length: int = 1000) -> list[str]:
        """Return every value of ``name`` (checkboxes, repeated fields), in order."""
        values = self.fields.get(name, [])
        if len(values) > max_count:
            raise InvalidFormError(f"The field '{name}' is given {len(values)} times; the limit is {max_count}.")
        for value in values:
            if len(value) > max_length:
                raise InvalidFormError(
                    f"A value of '{name}' is {len(value)} characters long; the limit is {max_length}.",
                    details={"field": name, "limit": max_length},
                )
        return values

    def flag(self, name: str) -> bool:
        """Return whether a checkbox was ticked."""
        return bool(self.fields.get(name))


async def read_form(request: Request) -> Form:
    """Return the request's form; InvalidFormError for another content type or text that is not UTF-8."""
    content_type = request.headers.get("content-type", "").split(";")[0].strip().lower()
    body = await request.body()
    if not body and not content_type:
        return Form({})  # a form without fields
    if content_type != FORM_TYPE:
        raise InvalidFormError(f"Send the form as {FORM_TYPE}, not '{content_type or 'nothing'}'.")
    try:
        text = body.decode("utf-8")
    except UnicodeDecodeError:
        raise InvalidFormError("The form is not UTF-8 text.") from None
    try:
        parsed = parse_qs(text, keep_blank_values=True, max_num_fields=MAX_FIELDS, errors="strict")
    except (ValueError, UnicodeDecodeError) as exc:
        raise InvalidFormError(f"The form cannot be read: {exc}.") from None
    # The API's rule: text holding control characters (NUL among them) is refused, not changed.
    # (A lone surrogate cannot get here: the strict decoding above refuses it.)
    for name, values in parsed.items():
        if has_control_characters(name) or any(has_control_characters(value) for value in values):
            shown = "".join(char for char in name if char.isprintable())[:100]
            raise InvalidFormError(
                f"The field '{shown}' contains invisible control characters (such as NUL); "
                "retype it using ordinary letters, digits and punctuation.",
                details={"field": shown},
            )
    # Browsers send textarea line breaks as CRLF.
    return Form({name: [value.replace("\r\n", "\n") for value in values] for name, values in parsed.items()})
