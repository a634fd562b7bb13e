"""Repairs of a failed transfer: the smallest edit sets, each re-checked by a full verdict."""

from __future__ import annotations

from causalplan.explain.repair import Edit, EditKind, apply_edits, candidate_edits, search_repairs
from causalplan.objects.catalog import Catalog
from causalplan.transfer.verdict import Verdict
from tests.conftest import example_mapping, example_model


def test_the_failed_flashlight_mapping_is_repaired_through_the_head(catalog: Catalog) -> None:
    model = example_model("paper/failed_desk_lamp.yaml", catalog)
    mapping = example_mapping("paper/failed_flashlight_mapping.yaml", catalog)
    search = search_repairs(model, mapping, catalog)
    said = [repair.describe() for repair in search.repairs]
    assert "give 'turn electricity into light' to the head and take 'provide electricity' away from the head" in said
    assert all("turn electricity into light" in words or "drop" in words for words in said)
    # Smallest first, every one re-checked: a plan that transfers, found by the planner and simulator.
    sizes = [len(repair.edits) for repair in search.repairs]
    assert sizes == sorted(sizes) and sizes[0] == 1
    assert all(repair.verdict.verdict is Verdict.TRANSFERS for repair in search.repairs)
    assert all(repair.verdict.simulation is not None for repair in search.repairs)
    # Minimal: no pair contains a single edit that works alone.
    singles = {repair.edits[0] for repair in search.repairs if len(repair.edits) == 1}
    assert not any(set(repair.edits) & singles for repair in search.repairs if len(repair.edits) == 2)


def test_a_model_that_transfers_needs_no_repair(catalog: Catalog) -> None:
    model = example_model("paper/desk_lamp.yaml", catalog)
    mapping = example_mapping("paper/flashlight_mapping.yaml", catalog)
    search = search_repairs(model, mapping, catalog, simulate=False)
    assert (search.repairs, search.checked) == ((), 0)


def test_edits_change_the_mapping_and_the_model(catalog: Catalog) -> None:
    model = example_model("paper/failed_desk_lamp.yaml", catalog)
    mapping = example_mapping("paper/failed_flashlight_mapping.yaml", catalog)
    edits = (
        Edit(EditKind.GIVE_FUNCTION, "turn electricity into light", part="head"),
        Edit(EditKind.DROP_CAUSE, "diffuse light", rule=1),
    )
    edited = apply_edits(model, mapping, edits)
    assert edited is not None
    new_model, new_mapping = edited
    assert new_mapping.functions["head"] == ("diffuse light", "provide electricity", "turn electricity into light")
    assert new_model.rules[0].text == "provide electricity AND turn electricity into light CAUSES light"
    kinds = {edit.kind for edit in candidate_edits(model, mapping, catalog)}
    assert kinds == set(EditKind)


def test_a_search_stops_at_its_budget_with_what_it_found(catalog: Catalog) -> None:
    model = example_model("paper/failed_desk_lamp.yaml", catalog)
    mapping = example_mapping("paper/failed_flashlight_mapping.yaml", catalog)
    spent = search_repairs(model, mapping, catalog, simulate=False, seconds=0.0)
    assert (spent.repairs, spent.checked, spent.complete) == ((), 0, False)
    assert spent.as_dict()["complete"] is False
    whole = search_repairs(model, mapping, catalog, simulate=False, seconds=3600.0)
    assert whole.complete and whole.checked > 0 and whole.repairs
    assert whole.as_dict()["complete"] is True
