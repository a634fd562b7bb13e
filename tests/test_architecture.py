"""docs/architecture.md: the files its request flows name exist, so the map cannot drift from the code."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
ARCHITECTURE = ROOT / "docs" / "architecture.md"
FLOWS_HEADING = "## How a request flows"
_PATH = re.compile(r"`([\w./-]+/[\w.-]+\.(?:py|html|js|md))`")


def flows_section(text: str) -> str:
    """Return the part of the document under ``FLOWS_HEADING``, up to the next second-level heading."""
    start = text.index(FLOWS_HEADING) + len(FLOWS_HEADING)
    end = text.find("\n## ", start)
    return text[start : end if end != -1 else len(text)]


def named_files(section: str) -> list[str]:
    """Return the file paths a section names in backticks, in order, each once."""
    return list(dict.fromkeys(_PATH.findall(section)))


def test_the_two_flows_name_only_files_that_exist() -> None:
    section = flows_section(ARCHITECTURE.read_text(encoding="utf-8"))
    assert "`POST /v1/plans`" in section and "`POST /p/<code>/step3/<n>`" in section
    files = named_files(section)
    assert len(files) >= 20, files
    assert [name for name in files if not (ROOT / name).is_file()] == []


def test_a_file_that_is_gone_is_found() -> None:
    section = "1. `causalplan/service/answers.py` answers; `causalplan/service/documents.py` reads."
    files = named_files(section)
    assert files == ["causalplan/service/answers.py", "causalplan/service/documents.py"]
    assert [name for name in files if not (ROOT / name).is_file()] == ["causalplan/service/answers.py"]
