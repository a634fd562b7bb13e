"""The participant and research pages in a real browser: Playwright drives the OS's Chromium headless.

Against a real uvicorn server on a free loopback port (``live_server``). Each step's page is
saved as a screenshot under ``out/screenshots/`` (git ignores ``out/``) to look at; the browser
and the steps other browser tests share are in ``browsing``.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from playwright.sync_api import Browser, Page, expect

from tests.service.fixtures import AUTH, RESEARCH_TOKEN, serving, settings_for, sqlite_url
from tests.service.pages.browsing import (
    LAPTOP,
    PLAYER,
    complete_by_http,
    lamp_plan_shown,
    new_link,
    prolific_link,
    public_study,
    saved,
    shoot,
)
from tests.service.pages.flows import LAMP_RULES, TUTORIAL_RULES

pytestmark = pytest.mark.slow  # a real Chromium drives the pages


def test_a_participant_does_the_tutorial_and_the_three_steps_and_sees_the_verdict(live_server: str, page: Page) -> None:
    page.goto(new_link(live_server))
    expect(page).to_have_url(re.compile(r"/tutorial$"))
    expect(page.locator("h1")).to_contain_text("Tutorial")
    expect(page.locator(".part img").first).to_have_attribute("alt", "Picture of the chassis")
    continue_button = page.get_by_role("button", name="Continue to the study")
    expect(continue_button).to_be_disabled()  # the practice rules are still empty
    page.get_by_label("No: decorating does not make the car move.").check()
    page.get_by_label("No: light must already exist before it can be diffused.").check()
    page.get_by_label("One rule: FIRST AND SECOND CAUSES EFFECT").check()
    page.get_by_label("Rules for the wind-up toy car, one per line").fill(TUTORIAL_RULES)
    expect(continue_button).to_be_enabled()
    expect(page.locator("#problems")).to_contain_text("'hold things together' (of chassis) is not used by any rule")
    saved(page)
    shoot(page, "participant-0-tutorial")
    continue_button.click()

    expect(page).to_have_url(re.compile(r"/step1/1$"))
    expect(page.locator("h1")).to_have_text("Step 1: what do the parts of the desk lamp do?")
    page.get_by_label("Functions of the base with cables (one per line)").fill("provide electricity")
    page.get_by_label("Functions of the light bulb (one per line)").fill(
        "turn electricity into light\nclose the circuit"
    )
    saved(page)
    shoot(page, "participant-1-functions")
    page.get_by_role("button", name="Save and continue").click()

    expect(page).to_have_url(re.compile(r"/step2$"))
    rules = page.get_by_label("Your rules, one per line")
    rules.fill(LAMP_RULES)
    expect(page.locator("#problems")).to_have_class(re.compile(r"\bok\b"))
    expect(page.get_by_role("button", name="Submit my model")).to_be_enabled()
    page.get_by_role("button", name="Show the robot's plan").click()
    plan = page.locator("#plan-body")
    expect(plan).to_contain_text("Screw the light bulb into the base with cables.")
    picture = plan.locator("img")
    expect(picture).to_have_attribute("alt", "The desk lamp after the robot's plan, in the simulator")
    expect(picture).to_have_js_property("complete", True)
    assert picture.evaluate("image => image.naturalWidth") == 480  # the simulator's picture arrived
    expect(plan.locator(".picture-waiting")).to_have_count(0)  # and its progress bar went
    shoot(page, "participant-2-rules-and-plan")
    page.get_by_role("button", name="Submit my model").click()

    expect(page).to_have_url(re.compile(r"/step3/1$"))
    expect(page.locator("h1")).to_have_text("Step 3: a new object, the flashlight")
    expect(page.locator(".rules")).to_contain_text("electricity flows AND turn electricity into light CAUSES light")
    expect(page.locator("textarea#rules")).to_have_count(0)  # the training model cannot be edited
    batteries = page.get_by_role("group", name="batteries")
    batteries.get_by_label("provide electricity").check()
    head = page.get_by_role("group", name="head")
    head.get_by_label("turn electricity into light").check()
    head.get_by_label("close the circuit").check()
    saved(page)
    shoot(page, "participant-3-new-object")
    page.get_by_role("button", name="Submit: can the robot build the flashlight?").click()

    expect(page.locator("#verdict")).to_have_text("Your model works for the flashlight.")
    expect(page.locator(".result")).to_contain_text("Insert the batteries into the case.")
    shoot(page, "participant-4-verdict")
    page.get_by_role("button", name="Finish").click()
    expect(page.locator("h1")).to_have_text("Thank you: you have finished")
    expect(page.locator("main")).to_contain_text("The flashlight: your model works.")


def test_an_invalid_rule_shows_its_error_inline_and_blocks_submission(live_server: str, page: Page) -> None:
    page.goto(new_link(live_server, tutorial=False))
    page.get_by_label("Functions of the base with cables (one per line)").fill("provide electricity")
    page.get_by_label("Functions of the light bulb (one per line)").fill("turn electricity into light")
    page.get_by_role("button", name="Save and continue").click()
    expect(page).to_have_url(re.compile(r"/step2$"))

    rules = page.get_by_label("Your rules, one per line")
    rules.fill(
        "provide electricity AND turn electricity into light CAUSES electricity flows\nelectricity flow CAUSES light"
    )
    problem = page.locator("#problems li.error")
    expect(problem).to_contain_text("Problem (line 2): Rule 2 uses 'electricity flow'")
    expect(problem).to_contain_text("Did you mean 'electricity flows'?")
    expect(problem).to_contain_text("unknown_cause")
    submit = page.get_by_role("button", name="Submit my model")
    expect(submit).to_be_disabled()
    expect(page.locator("#model-status")).to_contain_text("Not ready to submit yet")
    saved(page)
    shoot(page, "invalid-rule-blocked")

    # Without the script (a forged post), the server refuses the invalid model all the same.
    code = page.url.split("/p/")[1].split("/")[0]
    response = page.request.post(
        f"{live_server}/p/{code}/step2", form={"rules": "electricity flow CAUSES light"}, max_redirects=0
    )
    assert response.status == 303 and response.headers["location"] == f"/p/{code}/step2?check=1"
    assert "Rule 1 uses" in page.request.get(f"{live_server}/p/{code}/step2?check=1").text()

    rules.fill(
        "provide electricity AND turn electricity into light CAUSES electricity flows\nelectricity flows CAUSES light"
    )
    expect(page.locator("#problems")).to_have_class(re.compile(r"\bok\b"))
    expect(submit).to_be_enabled()
    submit.click()
    expect(page).to_have_url(re.compile(r"/step3/1$"))


def test_a_reload_mid_step_keeps_the_work(live_server: str, page: Page) -> None:
    page.goto(new_link(live_server, tutorial=False))
    page.get_by_label("Functions of the light bulb (one per line)").fill("turn electricity into light")
    page.get_by_label("Functions of the shade (one per line)").fill("<script>alert(1)</script>")
    saved(page)
    page.reload()
    expect(page.get_by_label("Functions of the light bulb (one per line)")).to_have_value("turn electricity into light")
    expect(page.get_by_label("Functions of the shade (one per line)")).to_have_value("<script>alert(1)</script>")
    page.get_by_label("Functions of the base with cables (one per line)").fill("provide electricity")
    page.get_by_role("button", name="Save and continue").click()

    rules = page.get_by_label("Your rules, one per line")
    rules.fill("provide electricity AND turn electricity into light CAUSES light")
    saved(page)
    page.reload()
    expect(page.get_by_label("Your rules, one per line")).to_have_value(
        "provide electricity AND turn electricity into light CAUSES light"
    )
    # The label typed in step 1 is shown as text, never run: it is in the page and in the graph.
    expect(page.locator(".functions")).to_contain_text("<script>alert(1)</script>")
    expect(page.locator("#problems")).to_contain_text("'<script>alert(1)</script>' (of shade) is not used")
    shoot(page, "reload-keeps-work")


def test_the_researcher_defines_an_experiment_and_the_export_contains_the_trial(live_server: str, page: Page) -> None:
    page.goto(f"{live_server}/research")
    expect(page).to_have_url(re.compile(r"/research/login"))
    page.get_by_label("Research token").fill("not the token")
    page.get_by_role("button", name="Sign in").click()
    expect(page.locator("#login-error")).to_have_text("That is not the research token.")
    page.get_by_label("Research token").fill(RESEARCH_TOKEN)
    page.get_by_role("button", name="Sign in").click()
    expect(page.locator("h1")).to_have_text("Experiments")
    cookies = {cookie["name"]: cookie for cookie in page.context.cookies()}
    assert cookies["causalplan_research"]["httpOnly"] and cookies["causalplan_research"]["sameSite"] == "Strict"

    page.get_by_role("link", name="Define a new experiment").click()
    page.get_by_label("Name", exact=True).fill("Browser study")
    condition = page.get_by_role("group", name="Condition 1")
    condition.get_by_label("Name (e.g. near, far)").fill("near")
    condition.get_by_label("Training object 1").select_option("desk_lamp")
    condition.get_by_label("flashlight (electric)").check()
    shoot(page, "research-0-new-experiment")
    page.get_by_role("button", name="Create the experiment").click()
    expect(page.locator("h1")).to_have_text("Browser study")
    page.get_by_label("Make").fill("2")
    page.get_by_role("button", name="Make links").click()
    links = page.locator("#participants-table input.link-box")
    expect(links).to_have_count(2)
    complete_by_http(links.first.input_value())

    page.reload()
    expect(page.locator("#participants-table")).to_contain_text("finished")
    expect(page.locator("#results")).to_contain_text("flashlight")
    expect(page.locator("#trials summary")).to_contain_text("fails")
    expect(page.locator("img.plot")).to_have_count(1)  # one chart of the rates (the crowd's graph needs two models)
    expect(page.locator("#rates-chart")).to_have_js_property("complete", True)
    assert page.locator("#rates-chart").evaluate("image => image.naturalWidth") > 0
    expect(page.locator("#rates")).to_contain_text("0/1")  # the one rates table, as `analyze` counts
    expect(page.locator("#analysis")).to_contain_text("unmodelled_function")
    page.get_by_label("near").fill("30")  # the quota of the only condition
    page.get_by_label("Finished").fill("DONE42")
    page.get_by_role("button", name="Save the recruiting settings").click()
    expect(page.locator("#places")).to_contain_text("30")
    expect(page.get_by_label("Finished")).to_have_value("DONE42")
    shoot(page, "research-1-results")

    with page.expect_download() as download:
        page.locator("#export-json").click()
    exported: dict[str, Any] = json.loads(Path(download.value.path()).read_text())
    (trial,) = exported["trials"]
    assert trial["test_object"] == "flashlight" and trial["verdict"] == "fails"
    assert trial["mapping"]["functions"] == {"batteries": ["provide electricity"], "head": ["shine"]}
    assert [reason["code"] for reason in trial["reasons"]] == ["missing_function", "unmodelled_function"]
    assert trial["model"]["rules"] == ["provide electricity AND turn electricity into light CAUSES light"]
    assert {p["progress"] for p in exported["participants"]} == {"finished", "tutorial"}
    with page.expect_download() as download:
        page.locator("#export-csv").click()
    csv_text = Path(download.value.path()).read_text()
    assert trial["trial_id"] in csv_text and "unmodelled_function" in csv_text


# -- the public study link, as a Prolific participant meets it ---------------------------------------


def recruitment_of(base: str, experiment_id: str) -> dict[str, Any]:
    with httpx.Client(base_url=base, timeout=30) as client:
        found: dict[str, Any] = client.get(f"/v1/experiments/{experiment_id}/recruitment", headers=AUTH).json()
        return found


def test_a_prolific_participant_consents_passes_the_check_and_lands_on_the_completion_url(
    live_server: str, page: Page
) -> None:
    experiment_id = public_study(
        live_server, completion_code="CPLT42", comprehension_tries=2, consent_text="Consent text of this study."
    )
    # Prolific's site is not reachable from the tests: its completion page is answered here, as it would be.
    page.route(
        "https://app.prolific.com/**", lambda route: route.fulfill(body="<h1>Prolific</h1>", content_type="text/html")
    )
    page.goto(prolific_link(live_server, experiment_id, "5f1e2d3c4b5a697887766554"))
    expect(page.locator("#consent-text")).to_have_text("Consent text of this study.")
    shoot(page, "public-0-consent")
    page.get_by_role("button", name="I agree to take part").click()

    expect(page).to_have_url(re.compile(r"/tutorial$"))
    expect(page.locator("#tries-left")).to_have_text("You have 2 tries left to answer all three questions correctly.")
    page.get_by_label("Yes: every part's function belongs in a rule.").check()  # wrong, once
    page.get_by_label("No: light must already exist before it can be diffused.").check()
    page.get_by_label("One rule: FIRST AND SECOND CAUSES EFFECT").check()
    page.get_by_label("Rules for the wind-up toy car, one per line").fill(TUTORIAL_RULES)
    saved(page)
    page.get_by_role("button", name="Continue to the study").click()
    expect(page.locator(".question.wrong .feedback")).to_contain_text("Not quite.")
    expect(page.locator("#tries-left")).to_have_text("You have 1 try left to answer all three questions correctly.")
    page.get_by_label("No: decorating does not make the car move.").check()
    page.get_by_role("button", name="Continue to the study").click()

    expect(page).to_have_url(re.compile(r"/step1/1$"))
    page.get_by_label("Functions of the base with cables (one per line)").fill("provide electricity")
    page.get_by_label("Functions of the light bulb (one per line)").fill(
        "turn electricity into light\nclose the circuit"
    )
    page.get_by_role("button", name="Save and continue").click()
    page.get_by_label("Your rules, one per line").fill(LAMP_RULES)
    submit = page.get_by_role("button", name="Submit my model")
    expect(submit).to_be_enabled()
    submit.click()
    expect(page).to_have_url(re.compile(r"/step3/1$"))
    page.get_by_role("group", name="batteries").get_by_label("provide electricity").check()
    head = page.get_by_role("group", name="head")
    head.get_by_label("turn electricity into light").check()
    head.get_by_label("close the circuit").check()
    page.get_by_role("button", name="Submit: can the robot build the flashlight?").click()
    expect(page.locator("#verdict")).to_have_text("Your model works for the flashlight.")
    page.get_by_role("button", name="Finish").click()
    expect(page.locator("h1")).to_have_text("Thank you: you have finished")
    shoot(page, "public-1-finished")
    page.get_by_role("link", name="Return to Prolific to record your submission").click()
    expect(page).to_have_url("https://app.prolific.com/submissions/complete?cc=CPLT42")


def test_the_same_prolific_id_coming_back_returns_to_its_own_progress(live_server: str, browser: Browser) -> None:
    experiment_id = public_study(live_server)
    link = prolific_link(live_server, experiment_id, "pid-comes-back")
    first = browser.new_context(viewport=LAPTOP)
    page = first.new_page()
    page.goto(link)
    page.get_by_role("button", name="I agree to take part").click()
    page.get_by_label("No: decorating does not make the car move.").check()
    saved(page)
    own_page = page.url
    first.close()

    second = browser.new_context(viewport=LAPTOP)  # another browser: no cookie, only the platform id
    again = second.new_page()
    again.goto(link)
    expect(again).to_have_url(own_page)
    expect(again.get_by_label("No: decorating does not make the car move.")).to_be_checked()
    second.close()
    assert recruitment_of(live_server, experiment_id)["arrivals"] == {
        "arrived": 1,
        "consented": 1,
        "declined": 0,
        "undecided": 0,
    }


def test_declining_consent_stores_nothing_but_the_arrival(live_server: str, page: Page) -> None:
    experiment_id = public_study(live_server, no_consent_code="NOCONS1")
    page.goto(prolific_link(live_server, experiment_id, "pid-declines"))
    page.get_by_role("button", name="I do not agree").click()
    expect(page.locator("h1")).to_have_text("Thank you")
    expect(page.locator("#study-message")).to_contain_text("You chose not to take part.")
    expect(page.get_by_role("link", name="Return to Prolific to record your submission")).to_have_attribute(
        "href", "https://app.prolific.com/submissions/complete?cc=NOCONS1"
    )
    shoot(page, "public-2-declined")
    found = recruitment_of(live_server, experiment_id)
    assert found["arrivals"] == {"arrived": 1, "consented": 0, "declined": 1, "undecided": 0}
    assert [place["taken"] for place in found["places"]] == [0]
    with httpx.Client(base_url=live_server, timeout=30) as client:
        assert client.get(f"/v1/experiments/{experiment_id}/participants", headers=AUTH).json()["data"] == []


def test_a_full_quota_is_refused_politely(live_server: str, page: Page) -> None:
    experiment_id = public_study(live_server, quotas={"near": 1})
    page.goto(prolific_link(live_server, experiment_id, "pid-takes-the-place"))
    page.get_by_role("button", name="I agree to take part").click()
    expect(page).to_have_url(re.compile(r"/tutorial$"))
    page.goto(prolific_link(live_server, experiment_id, "pid-too-late"))
    expect(page.locator("h1")).to_have_text("This study is full")
    expect(page.locator("#study-message")).to_contain_text("Every place in this study has been taken")
    shoot(page, "public-3-full")
    assert recruitment_of(live_server, experiment_id)["arrivals"]["arrived"] == 1


@pytest.fixture(scope="module")
def filming_server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """A real server that films the robot small (the robot's run is the same at any size; filming is quicker)."""
    url = sqlite_url(tmp_path_factory.mktemp("db"))
    with serving(settings_for(url, robot_video_width=160, robot_video_height=120)) as base:
        yield base


@pytest.mark.slow
def test_watch_the_robot_plays_the_run_in_3d_and_its_last_frame_is_the_assembled_lamp(
    filming_server: str, page: Page
) -> None:
    code = lamp_plan_shown(page, filming_server)
    page.get_by_role("button", name="Watch the robot").click()
    canvas = page.locator(".robot-player canvas")
    expect(canvas).to_have_count(1, timeout=60_000)
    page.wait_for_function(f"() => {PLAYER}.state().frames > 2")
    before = canvas.screenshot()
    first = page.evaluate(f"{PLAYER}.state().time")
    page.wait_for_function(f"() => {PLAYER}.state().time > {first} + 1", timeout=30_000)
    assert canvas.screenshot() != before  # the arm has moved on the canvas
    assert float(page.locator(".player-timeline").input_value()) > first  # and the timeline with it
    expect(page.get_by_role("button", name="Submit my model")).to_be_enabled()  # the page stays usable

    fits = page.request.post(f"{filming_server}/p/{code}/plan", data={"rules": LAMP_RULES}).json()["plans"][0]["fits"]
    run = page.request.post(f"{filming_server}/p/{code}/films/playback", data={"object": "desk_lamp", "fits": fits})
    assembled = run.json()["assembled"]
    page.evaluate(f"{PLAYER}.seek({PLAYER}.state().seconds - 0.5); {PLAYER}.play()")
    page.wait_for_function(f"() => !{PLAYER}.state().playing", timeout=30_000)
    state = page.evaluate(f"{PLAYER}.state()")
    assert state["time"] == state["seconds"] == run.json()["seconds"]
    assert set(assembled) == {"light_bulb"}  # the rules need only the bulb screwed in
    for part, pose in assembled.items():
        assert max(abs(a - b) for a, b in zip(state["parts"][part], pose, strict=True)) < 1e-4, part
    expect(page.get_by_role("button", name="Play again")).to_be_visible()
    shoot(page, "participant-2-watch-the-robot")


@pytest.mark.slow
def test_the_film_of_the_desk_lamp_is_made_in_the_background_and_offered_to_download(
    filming_server: str, page: Page
) -> None:
    lamp_plan_shown(page, filming_server)
    page.get_by_role("button", name="Make a film to download (MP4)").click()
    progress = page.locator(".film-progress")
    expect(progress).to_contain_text("frames", timeout=30_000)  # frames filmed of those expected
    expect(page.get_by_role("button", name="Submit my model")).to_be_enabled()  # the page stays usable
    link = page.locator("a.film-download")
    expect(link).to_have_count(1, timeout=120_000)
    expect(link).to_contain_text("Download the film (MP4")
    film = page.request.get(filming_server + str(link.get_attribute("href")))
    assert film.ok and film.headers["content-type"] == "video/mp4" and len(film.body()) > 1000
    assert not progress.is_visible()
