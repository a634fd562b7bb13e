"""Step 2 in a real browser: one status, notes only after typing, a plan never stale, why-not in plain words."""

from __future__ import annotations

import re

import pytest
from playwright.sync_api import Page, expect

from tests.service.pages.browsing import at_step2, shoot
from tests.service.pages.flows import LAMP_RULES

pytestmark = pytest.mark.slow  # a real Chromium drives the pages

STATUS = "#model-status"


def test_step_two_says_one_thing_and_never_shows_a_stale_plan(live_server: str, page: Page) -> None:
    at_step2(page, live_server)
    # Nothing typed yet: no problem and no note, one neutral status.
    expect(page.locator("#problems li")).to_have_count(0)
    expect(page.locator(STATUS)).to_have_text("Write your rules: they are checked as you type.")
    rules = page.get_by_label("Your rules, one per line")
    rules.fill("provide electricity AND close the circuit CAUSES electricity flows")
    expect(page.locator(STATUS)).to_contain_text("Not ready to submit yet")
    expect(page.locator(STATUS)).to_have_attribute("data-tone", "problem")
    rules.fill(LAMP_RULES)
    expect(page.locator(STATUS)).to_contain_text("Ready to submit: your rules have no problems. Show the robot's plan")
    page.get_by_role("button", name="Show the robot's plan").click()
    expect(page.locator(STATUS)).to_have_text(
        "Ready to submit: your rules have no problems, and the robot's plan makes the desk lamp produce light."
    )
    expect(page.locator(STATUS)).to_have_attribute("data-tone", "good")
    shoot(page, "step2-one-status")

    # Why not… in the participant's words, with the desk lamp's own examples.
    examples = page.locator(".why-not-examples")
    expect(examples).to_contain_text("Why not put the shade on first?")
    ask = page.get_by_label("Ask the robot about the desk lamp:")
    ask.fill("why not put the shade on first?")
    page.get_by_role("button", name="Ask the robot").click()
    answer = page.locator(".why-not-answer")
    expect(answer).to_contain_text("the light bulb cannot go in")
    ask.fill("make it brighter")
    page.get_by_role("button", name="Ask the robot").click()
    expect(answer).to_contain_text("did not understand")
    offered = page.locator(".why-not-suggestions button")
    expect(offered).to_have_count(3)
    offered.first.click()
    expect(answer).not_to_have_text(re.compile(r"did not understand|planning again|^$"))
    page.get_by_role("button", name="Why step 1?").click()
    expect(page.locator(".why-answer")).to_contain_text("light bulb")
    shoot(page, "step2-why-not-plain")

    # The rules change: the plan, its answers and its questions are out of date until shown again.
    rules.fill("provide electricity AND turn electricity into light CAUSES light")
    expect(page.locator("#plan")).to_have_class(re.compile(r"\bstale\b"))
    expect(page.locator("#plan-stale")).to_be_visible()
    expect(page.get_by_role("button", name="Why step 1?")).to_be_disabled()
    expect(page.get_by_role("button", name="Ask the robot")).to_be_disabled()
    expect(page.locator(".why-answer")).to_have_text("")
    expect(page.locator(".why-not-answer")).to_have_text("")
    expect(page.locator(STATUS)).to_contain_text("Your rules changed after the robot's plan")
    shoot(page, "step2-stale-plan")
    page.get_by_role("button", name="Show the robot's plan").click()
    expect(page.locator("#plan")).not_to_have_class(re.compile(r"\bstale\b"))
    expect(page.locator("#plan-stale")).to_be_hidden()
    expect(page.get_by_role("button", name="Why step 1?")).to_be_enabled()

    # Rules whose plan would not light the real lamp: still one status, saying so, and Submit stays open.
    rules.fill("provide electricity CAUSES light")
    page.get_by_role("button", name="Show the robot's plan").click()
    expect(page.locator(STATUS)).to_contain_text("You can submit, but following your rules the robot would not make")
    expect(page.locator(STATUS)).to_have_attribute("data-tone", "warning")
    expect(page.get_by_role("button", name="Submit my model")).to_be_enabled()
    expect(page.locator("#plan .feedback")).to_have_count(0)  # no second, red verdict beside the status
    shoot(page, "step2-plan-does-not-work")
