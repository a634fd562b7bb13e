"""What the browser tests share: Chromium, its fixtures, and the steps many of them take.

Chromium is the one thing the tests take from the OS: README command 2 installs Debian's
``chromium`` when it is missing; ``CAUSALPLAN_TEST_CHROMIUM`` names another binary. The
fixtures (``playwright``, ``browser``, ``page``) are this folder's ``conftest``.

Each step's page may be saved as a screenshot under ``out/screenshots/`` (git ignores ``out/``)
to look at.
"""

from __future__ import annotations

import os
import re
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import httpx
import pytest
from playwright.sync_api import Browser, Page, ViewportSize, expect

from tests.service.fixtures import AUTH, RESEARCH_TOKEN
from tests.service.pages.flows import LAMP_RULES, TUTORIAL_ANSWERS, TUTORIAL_RULES, experiment, links

ROOT = Path(__file__).resolve().parents[3]
SCREENSHOTS = ROOT / "out" / "screenshots"
CHROMIUM_VARIABLE = "CAUSALPLAN_TEST_CHROMIUM"
CHROMIUM_NAMES = ("chromium", "chromium-browser")
"""Debian's name for the binary, and Ubuntu's."""
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]
LAPTOP: ViewportSize = {"width": 1366, "height": 900}
ASSERTION_TIMEOUT_MS = 20_000
"""How long an ``expect`` waits for the page (Playwright's 5 s default flaked with the suite on two shared cores)."""

expect.set_options(timeout=ASSERTION_TIMEOUT_MS)  # every browser test module imports this one


def chromium_executable() -> str:
    """Return the Chromium binary to drive: the variable's, else the first of ``CHROMIUM_NAMES`` on PATH.

    Playwright's own browser download is never used (it cannot be fetched here); without a
    Chromium the tests fail saying how to get one, rather than at a path that is not there.
    """
    named = os.environ.get(CHROMIUM_VARIABLE)
    if named:
        return named
    for name in CHROMIUM_NAMES:
        found = shutil.which(name)
        if found:
            return found
    pytest.fail(
        f"No Chromium on PATH (looked for {', '.join(CHROMIUM_NAMES)}): README command 2 installs Debian's "
        f"'chromium' when it is missing (apt-get install chromium), or set {CHROMIUM_VARIABLE} to a binary."
    )


@contextmanager
def opened_page(browser: Browser, **context: Any) -> Iterator[Page]:
    """Open a page in a new browser context (``context``: its options); assert it had no script error."""
    browser_context = browser.new_context(**context)
    opened = browser_context.new_page()
    errors: list[str] = []
    opened.on("pageerror", lambda error: errors.append(str(error)))
    yield opened
    browser_context.close()
    assert not errors, f"script errors on the page: {errors}"


def shoot(page: Page, name: str) -> None:
    """Save a screenshot of the whole page as an artifact."""
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=SCREENSHOTS / f"{name}.png", full_page=True)
    # A full-page shot stretches the viewport for a moment. Chromium may then scroll back to the
    # focused field when it loses focus, which can be between the press and the release of the
    # next click, so the click misses its button: restore the viewport and let go of the focus now.
    page.set_viewport_size(LAPTOP)
    page.evaluate("document.activeElement && document.activeElement.blur()")


def new_link(base: str, tutorial: bool = True) -> str:
    """Define a one-condition experiment (desk lamp, then flashlight) through the API; return a participant link."""
    with httpx.Client(base_url=base, timeout=30) as client:
        (participant,) = links(client, experiment(client, tutorial=tutorial)["id"])
        url: str = participant["url"]
        return url


def saved(page: Page) -> None:
    """Wait until the page says the latest change is saved."""
    expect(page.locator("#save-status")).to_contain_text("Saved at", timeout=15_000)


PLAYER = "document.querySelector('.robot-player').player"


def signed_in(page: Page, base: str) -> None:
    """Sign in to the research pages with the research token; the page is the experiments' list."""
    page.goto(f"{base}/research/login")
    page.get_by_label("Research token").fill(RESEARCH_TOKEN)
    page.get_by_role("button", name="Sign in").click()
    expect(page.locator("h1")).to_have_text("Experiments")


def at_step2(page: Page, base: str) -> None:
    """Open a new participant's link (no tutorial) and do step 1 of the desk lamp: the page is step 2."""
    page.goto(new_link(base, tutorial=False))
    page.get_by_label("Functions of the base with cables (one per line)").fill("provide electricity")
    bulb = page.get_by_label("Functions of the light bulb (one per line)")
    bulb.fill("turn electricity into light\nclose the circuit")
    saved(page)
    page.get_by_role("button", name="Save and continue").click()
    expect(page).to_have_url(re.compile(r"/step2$"))


def lamp_plan_shown(page: Page, base: str) -> str:
    """Reach step 2 with the desk lamp's rules and show the robot's plan; return the participant's code."""
    at_step2(page, base)
    page.get_by_label("Your rules, one per line").fill(LAMP_RULES)
    expect(page.locator("#problems")).to_have_class(re.compile(r"\bok\b"))
    page.get_by_role("button", name="Show the robot's plan").click()
    code = re.search(r"/p/([^/]+)/step2$", page.url)
    assert code is not None
    return code.group(1)


def complete_by_http(link: str) -> None:
    """Take a participant through every step by posting the forms (no browser): desk lamp, then flashlight."""
    with httpx.Client(timeout=60, follow_redirects=True) as client:
        page = client.get(link)
        base = link.rsplit("/p/", 1)[0]
        code = link.rsplit("/", 1)[1]
        if page.url.path.endswith("/tutorial"):
            client.post(f"{base}/p/{code}/tutorial", data={**TUTORIAL_ANSWERS, "rules": TUTORIAL_RULES})
        client.post(
            f"{base}/p/{code}/step1/1",
            data={"part:base_with_cables": "provide electricity", "part:light_bulb": "turn electricity into light"},
        )
        client.post(
            f"{base}/p/{code}/step2", data={"rules": "provide electricity AND turn electricity into light CAUSES light"}
        )
        verdict = client.post(
            f"{base}/p/{code}/step3/1",
            data={"chosen:batteries": "provide electricity", "added:head": "shine"},
        )
        assert "Your model does not work for the flashlight." in verdict.text, verdict.text
        assert "you have finished" in client.post(f"{base}/p/{code}/step3/1/next").text


def public_study(base: str, **recruiting: Any) -> str:
    """Define a desk-lamp-to-flashlight experiment with a tutorial and recruiting settings; return its id."""
    with httpx.Client(base_url=base, timeout=30) as client:
        experiment_id: str = experiment(client, tutorial=True)["id"]
        response = client.put(f"/v1/experiments/{experiment_id}/recruitment", json=recruiting, headers=AUTH)
        assert response.status_code == 200, response.text
        return experiment_id


def prolific_link(base: str, experiment_id: str, pid: str) -> str:
    return f"{base}/s/{experiment_id}?PROLIFIC_PID={pid}&STUDY_ID=study1&SESSION_ID=session-{pid}"
