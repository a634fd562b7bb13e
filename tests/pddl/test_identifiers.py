"""Labels written by people become safe, distinct, deterministic PDDL identifiers."""

from __future__ import annotations

import re
import unicodedata

from hypothesis import given
from hypothesis import strategies as st

from causalplan.pddl.identifiers import comment, node_identifiers, slug

PDDL_NAME = re.compile(r"^[a-z][a-z0-9-]*$")


def test_slug_keeps_words_and_drops_structure() -> None:
    assert slug("provide electricity") == "provide-electricity"
    assert slug("x) (:action evil") == "x-action-evil"
    assert slug("Lumière") == "lumiere"
    assert slug("电") == ""


def test_colliding_labels_get_distinct_names_in_sorted_order() -> None:
    names = node_identifiers(["a b", "a-b", "a_b", "a b!"])
    assert len(set(names.values())) == 4
    assert names["a b"] == "n-a-b"
    assert names["a b!"] == "n-a-b-2"  # sorted: "a b" < "a b!" < "a-b" < "a_b"
    assert names["a_b"] == "n-a-b-4"
    assert node_identifiers(["a_b", "a b", "a-b", "a b!"]) == names


def test_labels_without_ascii_letters_still_get_names() -> None:
    names = node_identifiers(["光", "電気"])
    assert sorted(names.values()) == ["n-label", "n-label-2"]


def test_comment_cannot_break_out_of_its_line() -> None:
    assert "\n" not in comment("light\n(:action evil)")
    assert "\r" not in comment("light\r(:action evil)")


@given(st.lists(st.text(max_size=40), max_size=12))
def test_every_identifier_is_a_plain_pddl_name_and_distinct(labels: list[str]) -> None:
    names = node_identifiers(labels)
    assert set(names) == set(labels)
    assert len(set(names.values())) == len(names)
    assert all(PDDL_NAME.match(name) for name in names.values())


def test_composed_and_decomposed_labels_get_one_identifier() -> None:
    composed, decomposed = unicodedata.normalize("NFC", "café"), unicodedata.normalize("NFD", "café")
    names = node_identifiers([composed, decomposed, "cafe"])
    assert names[composed] == names[decomposed]
    assert len({names[composed], names["cafe"]}) == 2
