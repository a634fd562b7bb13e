"""What routes answer with: JSON that never fails on an unpaired surrogate, CSV exports, and films."""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Sequence
from typing import Any

from fastapi.responses import JSONResponse, Response


def render_json(content: Any) -> bytes:
    """Return ``content`` as compact UTF-8 JSON; a lone surrogate (valid in Python text, not in UTF-8) becomes '?'."""
    text = json.dumps(content, ensure_ascii=False, allow_nan=False, indent=None, separators=(",", ":"))
    return text.encode("utf-8", "replace")


class SafeJSONResponse(JSONResponse):
    """JSON that always encodes (``render_json``)."""

    def render(self, content: Any) -> bytes:
        return render_json(content)


_FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")


def _cell(value: object) -> str:
    text = value if isinstance(value, str) else "" if value is None else json.dumps(value, ensure_ascii=False)
    # A cell starting like a formula would run in a spreadsheet, and participants type these labels.
    return "'" + text if text.startswith(_FORMULA_STARTS) else text


def csv_bytes(columns: Sequence[str], rows: Sequence[dict[str, Any]]) -> bytes:
    """Return ``rows`` as CSV (values that are not text as JSON), with a header."""
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(columns)
    for row in rows:
        writer.writerow([_cell(row.get(column)) for column in columns])
    return buffer.getvalue().encode("utf-8", "replace")


def film_response(data: bytes, content_type: str) -> Response:
    """Return a file a job stored (a film, a 3D player's document): private to the asker's browser for an hour,
    never sniffed as another type."""
    return Response(
        data,
        media_type=content_type,
        headers={"Cache-Control": "private, max-age=3600", "X-Content-Type-Options": "nosniff"},
    )
