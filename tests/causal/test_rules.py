"""The step-2 keyword rule language: ``CAUSE [AND CAUSE ...] CAUSES EFFECT``."""

from __future__ import annotations

from causalplan.causal.diagnostics import Location, Severity
from causalplan.causal.rules import Rule, parse_rule

WHERE = Location(file="model.yaml", line=7, rule=3)


def parse(text: str, index: int = 3) -> tuple[Rule | None, list[str]]:
    """Parse one rule at WHERE; return it and the codes of what was found."""
    rule, problems = parse_rule(text, index, WHERE)
    return rule, [problem.code for problem in problems]


# --- well-formed rules ---------------------------------------------------------------------


def test_paper_rule_with_two_causes() -> None:
    rule, codes = parse("provide electricity AND turn electricity into light CAUSES light")
    assert codes == []
    assert rule is not None
    assert rule.causes == ("provide electricity", "turn electricity into light")
    assert rule.effect == "light"
    assert rule.index == 3


def test_rule_with_one_cause() -> None:
    rule, codes = parse("burning CAUSES light")
    assert codes == []
    assert rule is not None
    assert rule.causes == ("burning",)
    assert rule.effect == "light"


def test_rule_with_three_causes_keeps_their_order() -> None:
    rule, _ = parse("provide electricity AND turn electricity into light AND diffuse light CAUSES light")
    assert rule is not None
    assert rule.causes == ("provide electricity", "turn electricity into light", "diffuse light")


def test_keywords_are_case_insensitive() -> None:
    for text in ("a and b causes c", "a And b Causes c", "a AND b CAUSES c", "a aNd b cAuSeS c"):
        rule, codes = parse(text)
        assert codes == [], text
        assert rule is not None
        assert rule.causes == ("a", "b"), text
        assert rule.effect == "c", text


def test_labels_keep_the_case_people_wrote() -> None:
    rule, _ = parse("Provide Electricity CAUSES Light")
    assert rule is not None
    assert rule.causes == ("Provide Electricity",)
    assert rule.effect == "Light"
    assert rule.cause_keys == frozenset({"provide electricity"})
    assert rule.effect_key == "light"


def test_keywords_only_as_whole_words() -> None:
    rule, codes = parse("sand because of wind CAUSES dunes")
    assert codes == []
    assert rule is not None
    # 'sand' holds 'and', 'because' holds 'causes': neither is a keyword.
    assert rule.causes == ("sand because of wind",)
    assert rule.effect == "dunes"


def test_words_that_start_with_a_keyword_are_labels() -> None:
    rule, codes = parse("ANDROID AND ANDES CAUSES CAUSESWAY")
    assert codes == []
    assert rule is not None
    assert rule.causes == ("ANDROID", "ANDES")
    assert rule.effect == "CAUSESWAY"


def test_keyword_glued_to_punctuation_is_not_a_keyword() -> None:
    _, codes = parse("heat causes, light")
    assert codes == ["missing_causes_keyword"]


def test_whitespace_of_any_kind_separates_keywords_and_collapses() -> None:
    rule, codes = parse("  provide   electricity\tAND\nclose the  circuit   CAUSES\u00a0electricity flows  ")
    assert codes == []
    assert rule is not None
    assert rule.causes == ("provide electricity", "close the circuit")
    assert rule.effect == "electricity flows"
    assert rule.text == "provide electricity AND close the circuit CAUSES electricity flows"


def test_punctuation_in_labels_is_kept() -> None:
    rule, codes = parse("turn electricity into light (bulb) CAUSES light!")
    assert codes == []
    assert rule is not None
    assert rule.causes == ("turn electricity into light (bulb)",)
    assert rule.effect == "light!"
    assert rule.effect_key == "light!"


def test_word_or_is_allowed_inside_labels_without_warning() -> None:
    _, codes = parse("open the door CAUSES more light")
    assert codes == []


# --- canonical form ------------------------------------------------------------------------


def test_canonical_form_sorts_causes_and_normalises_labels() -> None:
    rule, _ = parse("Turn  Electricity into light and PROVIDE electricity causes LIGHT")
    assert rule is not None
    assert rule.canonical() == "provide electricity AND turn electricity into light CAUSES light"


def test_equivalent_rules_have_the_same_canonical_form() -> None:
    first, _ = parse("a AND b CAUSES c")
    second, _ = parse("B and   A causes C")
    assert first is not None and second is not None
    assert first.canonical() == second.canonical() == "a AND b CAUSES c"


def test_different_rules_have_different_canonical_forms() -> None:
    first, _ = parse("a AND b CAUSES c")
    second, _ = parse("a CAUSES c")
    assert first is not None and second is not None
    assert first.canonical() != second.canonical()


# --- errors ----------------------------------------------------------------------------------


def test_missing_causes_keyword() -> None:
    rule, problems = parse_rule("provide electricity AND turn electricity into light", 2, WHERE)
    assert rule is None
    assert [p.code for p in problems] == ["missing_causes_keyword"]
    assert problems[0].severity is Severity.ERROR
    assert "Rule 2" in problems[0].message
    assert problems[0].hint is not None and "CAUSES" in problems[0].hint


def test_causes_inside_a_word_is_missing_causes_keyword() -> None:
    rule, codes = parse("light because electricity")
    assert rule is None
    assert codes == ["missing_causes_keyword"]


def test_multiple_causes_keywords() -> None:
    rule, problems = parse_rule("a CAUSES b CAUSES c", 1, WHERE)
    assert rule is None
    assert [p.code for p in problems] == ["multiple_causes_keywords"]
    assert "2 times" in problems[0].message
    assert problems[0].hint is not None and "separate rules" in problems[0].hint


def test_rule_without_causes() -> None:
    rule, problems = parse_rule("CAUSES light", 1, WHERE)
    assert rule is None
    assert [p.code for p in problems] == ["rule_without_causes"]
    assert problems[0].hint is not None and "CAUSES light" in problems[0].hint


def test_rule_without_effect() -> None:
    rule, codes = parse("provide electricity CAUSES")
    assert rule is None
    assert codes == ["rule_without_effect"]


def test_rule_of_only_the_keyword_lacks_both_sides() -> None:
    rule, codes = parse("causes")
    assert rule is None
    assert codes == ["rule_without_causes", "rule_without_effect"]


def test_and_with_nothing_after_it_is_empty_label() -> None:
    rule, codes = parse("provide electricity AND CAUSES light")
    assert rule is None
    assert codes == ["empty_label"]


def test_and_with_nothing_before_it_is_empty_label() -> None:
    rule, codes = parse("AND provide electricity CAUSES light")
    assert rule is None
    assert codes == ["empty_label"]


def test_double_and_is_empty_label() -> None:
    rule, codes = parse("a AND AND b CAUSES light")
    assert rule is None
    assert codes == ["empty_label"]


def test_empty_rule() -> None:
    for text in ("", "   ", "\t\n"):
        rule, codes = parse(text)
        assert rule is None
        assert codes == ["empty_rule"], repr(text)


def test_control_character_is_invalid_character() -> None:
    for text in ("a\x00 CAUSES light", "a CAUSES li\x07ght", "a\u200b CAUSES light"):
        rule, codes = parse(text)
        assert rule is None
        assert codes == ["invalid_character"], repr(text)


def test_errors_carry_the_given_location() -> None:
    _, problems = parse_rule("nothing here", 3, WHERE)
    assert problems[0].location == WHERE


# --- warnings -------------------------------------------------------------------------------


def test_duplicate_cause_warns_and_keeps_one() -> None:
    rule, problems = parse_rule("provide electricity AND Provide  Electricity CAUSES light", 4, WHERE)
    assert rule is not None
    assert rule.causes == ("provide electricity",)
    assert [p.code for p in problems] == ["duplicate_cause"]
    assert problems[0].severity is Severity.WARNING
    assert problems[0].location == WHERE


def test_or_in_a_cause_warns() -> None:
    rule, problems = parse_rule("batteries OR cables CAUSES electricity", 1, WHERE)
    assert rule is not None
    assert rule.causes == ("batteries OR cables",)
    assert [p.code for p in problems] == ["or_in_label"]
    assert problems[0].severity is Severity.WARNING
    assert problems[0].hint is not None and "one rule per alternative" in problems[0].hint


def test_or_in_the_effect_warns_in_any_case() -> None:
    _, codes = parse("heat CAUSES light or warmth")
    assert codes == ["or_in_label"]


def test_each_label_with_or_warns_once() -> None:
    _, codes = parse("a or b AND c or d CAUSES e")
    assert codes == ["or_in_label", "or_in_label"]


def test_and_after_causes_is_an_error_with_one_rule_per_effect_as_the_fix() -> None:
    rule, problems = parse_rule("heat CAUSES light AND warmth", 3, Location(rule=3))
    assert rule is None
    assert [problem.code for problem in problems] == ["multiple_effects"]
    assert problems[0].hint is not None and "one rule per effect" in problems[0].hint
