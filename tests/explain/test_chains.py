"""Why this step? The causal chain each step serves, in the model's words."""

from __future__ import annotations

from causalplan.explain.chains import explain_step
from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import build_task, catalog_task
from causalplan.planners.pipeline import plan_task
from tests.conftest import example_mapping, example_model


def test_the_shade_serves_the_failed_models_only_rule(catalog: Catalog) -> None:
    task = build_task(example_model("paper/failed_desk_lamp.yaml", catalog), catalog.get("desk_lamp"))
    plan = plan_task(task, "fd")
    number = [step.args[0] for step in plan.steps].index("shade") + 1
    why = explain_step(task, plan.steps, number)
    assert [label for label, _ in why.chains] == ["diffuse light"]
    assert [link.rule.index for link in why.chains[0][1]] == [1]
    assert "the shade carries 'diffuse light': rule 1 needs 'diffuse light'" in why.message


def test_a_chain_climbs_through_an_intermediate_effect(catalog: Catalog) -> None:
    task = build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp"))
    plan = plan_task(task, "fd")
    why = explain_step(task, plan.steps, 1)
    chains = dict(why.chains)
    # 'close the circuit' -> rule 1 -> 'electricity flows' -> rule 2 -> light.
    assert [(link.rule.index, link.cause) for link in chains["close the circuit"]] == [
        (1, "close the circuit"),
        (2, "electricity flows"),
    ]
    assert [link.rule.index for link in chains["turn electricity into light"]] == [2]


def test_each_step_of_the_flashlight_plan_serves_a_rule(catalog: Catalog) -> None:
    model = example_model("paper/desk_lamp.yaml", catalog)
    mapping = example_mapping("paper/flashlight_mapping.yaml", catalog)
    task = catalog_task(model, catalog, mapping)
    plan = plan_task(task, "fd")
    assert [step.args[0] for step in plan.steps] == ["batteries", "head"]
    # The batteries carry 'provide electricity', which the model uses: a chain, not a detour.
    assert explain_step(task, plan.steps, 1).chains


def test_a_step_that_only_opens_the_way_says_so(catalog: Catalog) -> None:
    model = example_model("near/candle.yaml", catalog)
    mapping = example_mapping("near/kerosene_lamp_mapping.yaml", catalog)
    task = catalog_task(model, catalog, mapping)
    plan = plan_task(task, "fd")
    assert [step.args[0] for step in plan.steps] == ["burner", "wick", "lighter"]
    why = explain_step(task, plan.steps, 1)
    assert (why.chains, why.reached_by) == ((), (2,))
    assert "it is needed only to reach a part that attaches to it: the wick (step 2)" in why.message
