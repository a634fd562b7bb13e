"""Function labels: compared after normalising case and whitespace only."""

from __future__ import annotations

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
