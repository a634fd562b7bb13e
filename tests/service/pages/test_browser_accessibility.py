"""axe-core finds no violation on any page: every participant step (with the plan, its answers and a
stale plan), the end, consent, a refusal, and the research pages (with a robot's repair in the 3D
player). Offline: axe is vendored under ``tests/vendor/axe-core`` and injected into each page (the
pages' CSP is bypassed for it alone)."""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from playwright.sync_api import Browser, Page, expect

from tests.service.fixtures import RESEARCH_TOKEN
from tests.service.pages.browsing import (
    LAPTOP,
    new_link,
    opened_page,
    prolific_link,
    public_study,
    saved,
)
from tests.service.pages.flows import LAMP_RULES, TUTORIAL_RULES

pytestmark = pytest.mark.slow  # a real Chromium drives the pages

AXE = Path(__file__).resolve().parents[2] / "vendor" / "axe-core" / "axe.min.js"


@pytest.fixture
def checked(browser: Browser) -> Iterator[Page]:
    """A page whose content security policy lets the injected axe run (the pages' own scripts are unchanged)."""
    with opened_page(browser, viewport=LAPTOP, bypass_csp=True) as opened:
        yield opened


def violations(page: Page) -> list[dict[str, Any]]:
    """Return axe-core's violations on the page as it is now: rule, impact, and the first elements."""
    page.add_script_tag(path=str(AXE))
    found: list[dict[str, Any]] = page.evaluate(
        """async () => (await axe.run(document, {resultTypes: ['violations']})).violations.map((v) => ({
            id: v.id, impact: v.impact, nodes: v.nodes.slice(0, 3).map((n) => n.target.join(' '))
        }))"""
    )
    return found


def test_axe_finds_no_violation_on_any_page(live_server: str, checked: Page) -> None:
    page = checked
    found: dict[str, list[dict[str, Any]]] = {}

    def audit(name: str) -> None:
        found[name] = violations(page)

    page.goto(new_link(live_server))
    expect(page).to_have_url(re.compile(r"/tutorial$"))
    audit("tutorial")
    page.get_by_label("No: decorating does not make the car move.").check()
    page.get_by_label("No: light must already exist before it can be diffused.").check()
    page.get_by_label("One rule: FIRST AND SECOND CAUSES EFFECT").check()
    page.get_by_label("Rules for the wind-up toy car, one per line").fill(TUTORIAL_RULES)
    saved(page)
    audit("tutorial, answered")
    page.get_by_role("button", name="Continue to the study").click()
    expect(page).to_have_url(re.compile(r"/step1/1$"))
    audit("step 1")
    page.get_by_label("Functions of the base with cables (one per line)").fill("provide electricity")
    bulb = page.get_by_label("Functions of the light bulb (one per line)")
    bulb.fill("turn electricity into light\nclose the circuit")
    saved(page)
    page.get_by_role("button", name="Save and continue").click()
    expect(page).to_have_url(re.compile(r"/step2$"))
    audit("step 2, nothing typed")
    rules = page.get_by_label("Your rules, one per line")
    rules.fill("provide electricity AND close the circuit CAUSES electricity flow")
    expect(page.locator("#problems li.error").first).to_be_visible()
    audit("step 2, a problem")
    rules.fill(LAMP_RULES)
    page.get_by_role("button", name="Show the robot's plan").click()
    expect(page.locator(".plan-object img")).to_have_js_property("complete", True)
    page.get_by_label("Ask the robot about the desk lamp:").fill("make it brighter")
    page.get_by_role("button", name="Ask the robot").click()
    expect(page.locator(".why-not-suggestions button").first).to_be_visible()
    page.get_by_role("button", name="Why step 1?").click()
    expect(page.locator(".why-answer")).to_contain_text("light bulb")
    audit("step 2, the plan with answers and suggestions")
    expect(page.locator("#graph")).to_have_attribute("src", re.compile(r"graph\.svg"))  # drawn
    expect(page.locator("#graph")).to_be_visible()
    page.locator(".graph-zoom").first.click()
    expect(page.locator("dialog.graph-dialog")).to_be_visible()
    audit("step 2, the graph full size")
    page.get_by_role("button", name="Close", exact=True).click()
    rules.fill(LAMP_RULES + "\n")
    expect(page.locator("#plan-stale")).to_be_visible()
    audit("step 2, a stale plan")
    rules.fill(LAMP_RULES)
    saved(page)
    page.get_by_role("button", name="Submit my model").click()
    expect(page).to_have_url(re.compile(r"/step3/1$"))
    audit("step 3")
    page.get_by_role("group", name="batteries").get_by_label("provide electricity").check()
    head = page.get_by_role("group", name="head")
    head.get_by_label("turn electricity into light").check()
    head.get_by_label("close the circuit").check()
    saved(page)
    page.get_by_role("button", name="Submit: can the robot build the flashlight?").click()
    expect(page.locator("#verdict")).to_be_visible()
    audit("step 3, the verdict")
    page.get_by_role("button", name="Finish").click()
    expect(page.locator("h1")).to_have_text("Thank you: you have finished")
    audit("the end")

    study = public_study(live_server, completion_code="CPLT42", no_consent_code="NOPE1")
    page.goto(prolific_link(live_server, study, "pid-axe"))
    audit("consent")
    page.goto(prolific_link(live_server, study, "pid-axe-declines"))
    # After 5 s the page leaves for Prolific (unreachable here): that navigation is cancelled, so the
    # page stays put while axe looks, however long that takes on a busy machine.
    page.route("https://app.prolific.com/**", lambda route: route.abort("aborted"))
    page.get_by_role("button", name="I do not agree").click()
    expect(page.locator("#study-message")).to_be_visible()
    audit("declined")
    page.goto(f"{live_server}/p/{'A' * 22}/step1/1")
    audit("an unknown link")

    page.goto(f"{live_server}/research/login")
    audit("research sign-in")
    page.get_by_label("Research token").fill(RESEARCH_TOKEN)
    page.get_by_role("button", name="Sign in").click()
    expect(page.locator("h1")).to_have_text("Experiments")
    audit("research: experiments")
    page.get_by_role("link", name="Define a new experiment").click()
    audit("research: a new experiment")
    page.goto(f"{live_server}/research/experiments/{study}")
    page.get_by_role("button", name="Save the recruiting settings").click()
    expect(page.locator("#recruitment-saved")).to_be_visible()
    audit("research: an experiment, settings saved")
    page.get_by_role("link", name="Robot repairs").click()
    audit("research: robot repairs")
    page.get_by_label("The broken part").select_option("desk_lamp/light_bulb")
    page.get_by_label("Whose policy the robot follows").select_option("oracle")
    page.get_by_role("button", name="Watch the robot repair it").click()
    expect(page.get_by_role("list", name="The robot's actions").locator("li")).to_have_count(7, timeout=120_000)
    audit("research: the robot's repair in the 3D player")

    assert {name: items for name, items in found.items() if items} == {}
