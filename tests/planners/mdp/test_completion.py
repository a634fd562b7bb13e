"""The default policy's all-success completion, and anytime answers that are never broken plans (issue 44)."""

from __future__ import annotations

from causalplan.comparison.families import cyclic_components
from causalplan.planners.mdp.completion import completion
from causalplan.planners.mdp.model import compile_mdp, relevant_fits
from causalplan.planners.pipeline import plan_task
from causalplan.planners.result import PlanStatus


def test_the_completion_finds_the_way_round_a_cycle_of_shared_sockets() -> None:
    # A one-step look-ahead attached contacts half-way round the wrong way and stranded the
    # last one (its chance was 0): the plan then ended without the goal.
    task = cyclic_components(16, 1).task
    compiled = compile_mdp(task, relevant_fits(task))
    found = completion(compiled, (0, 0))
    made = 0
    for index in found.fits:
        made |= 1 << index
    assert found.fits and found.chance > 0.0
    assert compiled.goal_holds(compiled.parts_of((made, 0))[0])


def test_an_anytime_answer_on_many_components_is_a_replayed_plan_never_a_broken_one() -> None:
    # Before: "The planner's plan failed replay (the goal does not hold under the model after the last step)".
    result = plan_task(cyclic_components(16, 1).task, "mdp", 3.0)
    assert result.status is PlanStatus.SOLVED, result.message
    assert result.valid_under_model and result.steps
