"""The JSON response of every route: Starlette's, but never failing on an unpaired surrogate."""

from __future__ import annotations

import json
from typing import Any

from fastapi.responses import JSONResponse


class SafeJSONResponse(JSONResponse):
    """JSON that always encodes: a lone surrogate (valid in Python text, not in UTF-8) becomes '?'."""

    def render(self, content: Any) -> bytes:
        text = json.dumps(content, ensure_ascii=False, allow_nan=False, indent=None, separators=(",", ":"))
        return text.encode("utf-8", "replace")
