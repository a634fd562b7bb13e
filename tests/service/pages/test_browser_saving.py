"""Nothing typed is lost, in a real browser: reloads 100 ms after typing, Back and Forward, a failed submit.

Each check ends in a new tab as well, which has no outbox of its own: what it shows came from
the server.
"""

from __future__ import annotations

import re

import pytest
from playwright.sync_api import BrowserContext, Page, Route, expect

from tests.service.pages.browsing import complete_by_http, new_link, prolific_link, public_study
from tests.service.pages.flows import LAMP_RULES, TUTORIAL_RULES

pytestmark = pytest.mark.slow  # a real Chromium drives the pages

TYPING_TO_RELOAD_MS = 100
"""The issue's case: a reload (or Back) this soon after typing, well inside the save's debounce."""


def reload_soon(tab: Page) -> None:
    """Reload the page 100 ms after the last keystroke, as an impatient participant does."""
    tab.wait_for_timeout(TYPING_TO_RELOAD_MS)
    tab.reload()


def all_saved(tab: Page) -> None:
    """Wait until the server has acknowledged everything typed in this tab (its outbox is empty)."""
    tab.wait_for_function("() => !Object.keys(sessionStorage).some((name) => name.startsWith('causalplan:'))")


def in_new_tab(context: BrowserContext, url: str) -> Page:
    """Open ``url`` in a new tab: no outbox of its own, so what it shows is what the server stored."""
    tab = context.new_page()
    tab.goto(url)
    return tab


def test_text_typed_just_before_a_reload_back_or_forward_is_kept(live_server: str, page: Page) -> None:
    page.goto(new_link(live_server))
    expect(page).to_have_url(re.compile(r"/tutorial$"))
    practice = page.get_by_label("Rules for the wind-up toy car, one per line")
    page.get_by_label("No: decorating does not make the car move.").check()
    practice.fill(TUTORIAL_RULES)
    reload_soon(page)
    expect(practice).to_have_value(TUTORIAL_RULES)
    expect(page.get_by_label("No: decorating does not make the car move.")).to_be_checked()
    page.get_by_label("No: light must already exist before it can be diffused.").check()
    page.get_by_label("One rule: FIRST AND SECOND CAUSES EFFECT").check()
    all_saved(page)
    page.get_by_role("button", name="Continue to the study").click()

    expect(page).to_have_url(re.compile(r"/step1/1$"))
    bulb = page.get_by_label("Functions of the light bulb (one per line)")
    page.get_by_label("Functions of the base with cables (one per line)").fill("provide electricity")
    bulb.fill("turn electricity into light\nclose the circuit")
    reload_soon(page)
    expect(bulb).to_have_value("turn electricity into light\nclose the circuit")
    all_saved(page)
    step1 = page.url
    tab = in_new_tab(page.context, step1)
    expect(tab.get_by_label("Functions of the light bulb (one per line)")).to_have_value(
        "turn electricity into light\nclose the circuit"
    )
    tab.close()
    page.get_by_role("button", name="Save and continue").click()

    expect(page).to_have_url(re.compile(r"/step2$"))
    rules = page.get_by_label("Your rules, one per line")
    rules.fill("provide electricity CAUSES light")
    reload_soon(page)
    expect(rules).to_have_value("provide electricity CAUSES light")
    rules.fill(LAMP_RULES)
    page.wait_for_timeout(TYPING_TO_RELOAD_MS)
    page.go_back()  # to step 1, which stays open to change labels
    expect(page).to_have_url(step1)
    page.go_forward()
    expect(page).to_have_url(re.compile(r"/step2$"))
    expect(rules).to_have_value(LAMP_RULES)

    # A submission refused by the server, then newer text, then a reload: the newer text stays.
    invalid = "provide electricity AND close the circuit CAUSES electricity flow\nelectricity flows CAUSES light"
    rules.fill(invalid)
    # The button is disabled while the rules have problems: post the form as it is, the server refuses it.
    page.evaluate("HTMLFormElement.prototype.submit.call(document.getElementById('rules-form'))")
    expect(page).to_have_url(re.compile(r"/step2\?check=1$"))
    expect(page.locator("#problems li.error").first).to_contain_text("Rule 2 uses 'electricity flows'")
    expect(rules).to_have_value(invalid)
    rules.fill(LAMP_RULES)
    reload_soon(page)
    expect(rules).to_have_value(LAMP_RULES)
    all_saved(page)
    tab = in_new_tab(page.context, page.url)
    expect(tab.get_by_label("Your rules, one per line")).to_have_value(LAMP_RULES)
    tab.close()
    page.get_by_role("button", name="Submit my model").click()

    expect(page).to_have_url(re.compile(r"/step3/1$"))
    head = page.get_by_role("group", name="head")
    head.get_by_label("turn electricity into light").check()
    page.get_by_label("Other functions of the batteries (one per line)").fill("store electricity")
    reload_soon(page)
    expect(head.get_by_label("turn electricity into light")).to_be_checked()
    expect(page.get_by_label("Other functions of the batteries (one per line)")).to_have_value("store electricity")
    all_saved(page)
    tab = in_new_tab(page.context, page.url)
    expect(tab.get_by_label("Other functions of the batteries (one per line)")).to_have_value("store electricity")
    tab.close()


def test_the_end_page_goes_back_to_prolific_only_once_the_server_confirms(live_server: str, page: Page) -> None:
    experiment_id = public_study(live_server, completion_code="CPLT42")
    page.goto(prolific_link(live_server, experiment_id, "pid-waits-for-the-save"))
    page.get_by_role("button", name="I agree to take part").click()
    expect(page).to_have_url(re.compile(r"/tutorial$"))
    done = page.url.rsplit("/", 1)[0] + "/done"
    complete_by_http(page.url.rsplit("/", 1)[0])
    confirmed = {"yet": False}

    def progress(route: Route) -> None:
        if confirmed["yet"]:
            route.continue_()
        else:
            route.abort()  # the answer that would confirm the finish does not arrive

    def prolific(route: Route) -> None:
        route.fulfill(body="<p>recorded</p>", content_type="text/html")  # no network here

    page.route("**/progress", progress)
    page.route("https://app.prolific.com/**", prolific)
    page.goto(done)
    for _ in range(4):  # tries at 0, 1, 3 and 7 s: past the 5 s after which the page would leave
        with page.expect_event("requestfailed"):
            pass
    assert page.url == done
    expect(page.locator("#redirect-note")).to_contain_text("Making sure your answers are stored")
    confirmed["yet"] = True
    page.wait_for_url("https://app.prolific.com/submissions/complete?cc=CPLT42", timeout=30_000)
