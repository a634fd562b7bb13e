"""Function labels: compared after normalising case and whitespace only."""

from __future__ import annotations

import unicodedata

import pytest
from hypothesis import given
from hypothesis import strategies as st

from causalplan.causal.labels import closest, display_label, has_control_characters, normalize_label


def test_normalize_folds_case() -> None:
    assert normalize_label("Provide ELECTRICITY") == "provide electricity"


def test_normalize_collapses_and_trims_whitespace() -> None:
    assert normalize_label("  provide \t electricity\n") == "provide electricity"


def test_normalize_treats_unicode_spaces_as_whitespace() -> None:
    assert normalize_label("provide\u00a0electricity") == "provide electricity"


def test_normalize_keeps_punctuation() -> None:
    assert normalize_label("turn electricity into light!") == "turn electricity into light!"
    assert normalize_label("turn-electricity") != normalize_label("turn electricity")
    assert normalize_label("light.") != normalize_label("light")


def test_normalize_keeps_word_order_and_spelling() -> None:
    assert normalize_label("electricity provide") != normalize_label("provide electricity")
    assert normalize_label("provide electricty") != normalize_label("provide electricity")


def test_normalize_uses_full_case_folding() -> None:
    assert normalize_label("STRASSE") == normalize_label("Straße")


def test_normalize_is_idempotent() -> None:
    once = normalize_label("  Turn  Electricity INTO light ")
    assert normalize_label(once) == once


def test_display_keeps_case_and_collapses_whitespace() -> None:
    assert display_label("  Provide   Electricity\t") == "Provide Electricity"


def test_display_of_only_whitespace_is_empty() -> None:
    assert display_label(" \t\n ") == ""


def test_control_characters_are_detected() -> None:
    assert has_control_characters("light\x00")
    assert has_control_characters("li\u200bght")  # zero-width space (format character)


def _has_control_characters_by_category(label: str) -> bool:
    return any(unicodedata.category(char) in {"Cc", "Cf", "Cs", "Co"} and not char.isspace() for char in label)


@given(st.text(alphabet=st.characters(codec=None), max_size=12))
def test_the_printable_shortcut_agrees_with_the_categories(label: str) -> None:
    """``isprintable`` answers most labels in C; whatever it lets through is checked character by character."""
    assert has_control_characters(label) == _has_control_characters_by_category(label)


@pytest.mark.parametrize(
    "label",
    ["a\u200db", "a\ud800", "a\ue000", "a\u2028b", "a\u00a0b", "a\u0378", "a\x7f", "a\u00adb", "a\U000e0001"],
)
def test_every_kind_of_unprintable_character_is_judged_by_its_category(label: str) -> None:
    assert has_control_characters(label) == _has_control_characters_by_category(label)


def test_whitespace_and_accents_are_not_control_characters() -> None:
    assert not has_control_characters("provide\telectricity\n")
    assert not has_control_characters("lumière, ça brûle")


def test_closest_finds_a_typo() -> None:
    assert closest("provide electricty", ["provide electricity", "close the circuit"]) == "provide electricity"


def test_closest_finds_the_field_rules() -> None:
    assert closest("rule", ["object", "goal", "functions", "rules"]) == "rules"


def test_closest_returns_none_when_nothing_is_close() -> None:
    assert closest("banana", ["provide electricity", "close the circuit"]) is None


def test_closest_of_no_candidates_is_none() -> None:
    assert closest("light", []) is None


def test_closest_respects_the_cutoff() -> None:
    candidates = ["desk_lamp"]  # 'desk' is 8/13 similar to 'desk_lamp'
    assert closest("desk", candidates, cutoff=0.6) == "desk_lamp"
    assert closest("desk", candidates, cutoff=0.7) is None


def test_composed_and_decomposed_accents_are_one_label() -> None:
    composed, decomposed = unicodedata.normalize("NFC", "café"), unicodedata.normalize("NFD", "café")
    assert composed != decomposed
    assert normalize_label(composed) == normalize_label(decomposed) == "café"
    assert display_label(decomposed) == composed
