"""The disk cache of checked catalog objects: hits skip the checks, edits miss, damage is ignored."""

from __future__ import annotations

from pathlib import Path

import pytest

from causalplan.objects import cache
from causalplan.objects.catalog import parse_object
from causalplan.objects.model import AssemblyObject
from tests.conftest import EXAMPLES

LAMP = (EXAMPLES / "catalog/bedside_lamp.yaml").read_text()


@pytest.fixture
def folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("CAUSALPLAN_CACHE_DIR", str(tmp_path))
    return tmp_path


def _must_not_parse() -> AssemblyObject:
    raise AssertionError("parsed although the cache holds this text")


def test_a_checked_file_is_read_back_without_checking_again(folder: Path) -> None:
    first = parse_object(LAMP, "lamp.yaml")
    assert len(list(folder.glob("object-*.pickle"))) == 1
    assert cache.cached_object(LAMP, _must_not_parse) == first


def test_an_edited_file_misses_the_cache(folder: Path) -> None:
    parse_object(LAMP, "lamp.yaml")
    edited = parse_object(LAMP.replace("name: bedside lamp", "name: reading lamp"), "lamp.yaml")
    assert edited.name == "reading lamp"
    assert len(list(folder.glob("object-*.pickle"))) == 2


def test_an_edit_to_the_code_that_builds_objects_misses_the_cache(
    folder: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    parse_object(LAMP, "lamp.yaml")
    monkeypatch.setattr(cache, "_code_version", lambda: b"edited code, same causalplan version")
    parse_object(LAMP, "lamp.yaml")
    assert len(list(folder.glob("object-*.pickle"))) == 2


def test_a_damaged_entry_is_remade(folder: Path) -> None:
    parse_object(LAMP, "lamp.yaml")
    (entry,) = folder.glob("object-*.pickle")
    entry.write_bytes(b"not a pickle")
    assert parse_object(LAMP, "lamp.yaml").id == "bedside_lamp"
    assert entry.read_bytes() != b"not a pickle"


def test_invalid_files_are_never_cached(folder: Path) -> None:
    from causalplan.errors import CatalogError

    with pytest.raises(CatalogError):
        parse_object(LAMP.replace("base: lamp_body", "base: nothing"), "lamp.yaml")
    assert list(folder.glob("object-*.pickle")) == []


def test_the_cache_can_be_turned_off_or_unwritable(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("CAUSALPLAN_CACHE_DIR", "off")
    assert cache.cache_folder() is None
    assert parse_object(LAMP, "lamp.yaml").id == "bedside_lamp"
    blocker = tmp_path / "file"
    blocker.write_text("a file where the folder should be")
    monkeypatch.setenv("CAUSALPLAN_CACHE_DIR", str(blocker / "cache"))
    assert parse_object(LAMP, "lamp.yaml").id == "bedside_lamp"


def test_without_a_setting_the_folder_is_the_users_cache_folder(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.delenv("CAUSALPLAN_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))  # what platformdirs honours on Linux
    assert cache.cache_folder() == tmp_path / "causalplan"
