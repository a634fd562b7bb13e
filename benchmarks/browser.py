"""Time what a participant waits for in a browser: from "Show the robot's plan" to the picture.

    python benchmarks/browser.py [--rounds N]

Starts the service (uvicorn in a thread, a temporary SQLite database, the catalog's plans
drawn ahead as in production) and waits until the drawing ahead is done. Then, in Debian's
Chromium driven by Playwright, one participant per model (six models of four catalog
objects: different part sets, so different plans and pictures) does step 1 and types the
rules of step 2; the page's own script is then timed from the click on "Show the robot's
plan" until every picture of the plan has loaded, interleaved with the plan-only request
(the same POST the button sends, timed in the page with ``fetch``). The browser's cache is
off, so each picture is fetched from the server. A last round per model first forgets the
server's kept plan pictures: the wait of a picture that was not drawn ahead, for reference.

Prints the medians and the target of issue 21: click-to-picture median at most 3x the
plan-only median, both measured in this run. Needs Chromium at /usr/bin/chromium
(``apt-get install -y chromium``); never ``playwright install``.
"""

from __future__ import annotations

import argparse
import os
import platform
import socket
import statistics
import tempfile
import threading
import time
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import httpx
import uvicorn
from playwright.sync_api import Page, sync_playwright

from causalplan.service.main import create_app
from causalplan.settings import Settings

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]
TOKEN = "browser-benchmark-token"
TARGET_RATIO = 3.0


@dataclass(frozen=True)
class Case:
    """One participant's model: the training object, step 1's functions by part, step 2's rules."""

    name: str
    training: str
    test: str
    functions: dict[str, str]
    rules: str


CASES = (
    Case(
        "desk lamp, the paper's model",
        "desk_lamp",
        "flashlight",
        {"base_with_cables": "provide electricity", "light_bulb": "turn electricity into light\nclose the circuit"},
        "provide electricity AND close the circuit CAUSES electricity flows\n"
        "electricity flows AND turn electricity into light CAUSES light",
    ),
    Case(
        "desk lamp with its shade",
        "desk_lamp",
        "flashlight",
        {
            "base_with_cables": "provide electricity",
            "light_bulb": "turn electricity into light",
            "shade": "diffuse light",
        },
        "provide electricity AND turn electricity into light AND diffuse light CAUSES light",
    ),
    Case(
        "flashlight, head and batteries",
        "flashlight",
        "desk_lamp",
        {"batteries": "provide electricity", "head": "turn electricity into light"},
        "provide electricity AND turn electricity into light CAUSES light",
    ),
    Case(
        "flashlight, all three parts",
        "flashlight",
        "desk_lamp",
        {"batteries": "provide electricity", "head": "turn electricity into light", "case": "hold the batteries"},
        "provide electricity AND hold the batteries AND turn electricity into light CAUSES light",
    ),
    Case(
        "candle",
        "candle",
        "kerosene_lamp",
        {"wax": "provide fuel", "wick": "burn the fuel", "match": "light the wick"},
        "provide fuel AND burn the fuel AND light the wick CAUSES light",
    ),
    Case(
        "kerosene lamp",
        "kerosene_lamp",
        "candle",
        {"fuel_tank": "hold the fuel", "wick": "burn the fuel", "lighter": "light the wick"},
        "hold the fuel AND burn the fuel AND light the wick CAUSES light",
    ),
)

CLICK_TO_PICTURE = """
() => new Promise((resolve, reject) => {
  const body = document.getElementById("plan-body");
  const started = performance.now();
  document.getElementById("show-plan").click();
  const check = () => {
    const blocks = body.querySelectorAll(".plan-object");
    const pictures = [...body.querySelectorAll("img")];
    if (blocks.length && pictures.length && pictures.every((p) => p.complete && p.naturalWidth > 0)) {
      const elapsed = performance.now() - started;
      const fetched = pictures.map((p) => performance.getEntriesByName(p.src).pop());
      performance.clearResourceTimings();
      // transferSize 0 would be the browser's cache: each timed picture must come from the server.
      resolve([elapsed, fetched.every((entry) => entry && entry.transferSize > 0)]);
    } else if (performance.now() - started > 60000) {
      reject(new Error("no picture within 60 s: " + body.textContent));
    } else {
      setTimeout(check, 1);
    }
  };
  check();
})
"""

PLAN_ONLY = """
async (rules) => {
  const url = document.getElementById("show-plan").dataset.planUrl;
  const started = performance.now();
  const response = await fetch(url, {
    method: "POST",
    headers: { "Content-Type": "application/json", Accept: "application/json" },
    body: JSON.stringify({ rules }),
    credentials: "same-origin",
  });
  await response.json();
  if (!response.ok) throw new Error("plan answered " + response.status);
  return performance.now() - started;
}
"""


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


def participant(http: httpx.Client, case: Case) -> str:
    """Make a participant of a one-condition experiment on the case's object and do step 1; return the code."""
    auth = {"Authorization": f"Bearer {TOKEN}"}
    body = {
        "name": case.name,
        "tutorial": False,
        "conditions": [{"name": "only", "training": [case.training], "tests": [case.test]}],
    }
    made = http.post("/v1/experiments", json=body, headers=auth)
    made.raise_for_status()
    linked = http.post(f"/v1/experiments/{made.json()['id']}/participants", json={"count": 1}, headers=auth)
    linked.raise_for_status()
    code: str = linked.json()["data"][0]["code"]
    form = {f"part:{part}": text for part, text in case.functions.items()}
    step1 = http.post(f"/p/{code}/step1/1", data=form, follow_redirects=False)
    assert step1.status_code == 303 and step1.headers["location"].endswith("/step2"), step1.text
    return code


def timed(result: list[Any]) -> float:
    """Return the milliseconds CLICK_TO_PICTURE measured, after checking its pictures came from the server."""
    elapsed, from_server = result
    assert from_server, "a picture came from the browser's cache: the measurement would not be the server's"
    return float(elapsed)


def open_step2(page: Page, base: str, code: str, rules: str) -> None:
    """Open step 2 afresh (a new document: Chromium keeps a document's images in memory) with the rules typed."""
    page.goto(f"{base}/p/{code}/step2")
    box = page.get_by_label("Your rules, one per line")
    if box.input_value() != rules:
        box.fill(rules)
    page.wait_for_function("() => document.getElementById('problems').classList.contains('ok')")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=5, help="timed clicks (and plan-only requests) per model")
    args = parser.parse_args()

    folder = Path(tempfile.mkdtemp(prefix="causalplan-browser-"))
    settings = Settings(database_url=f"sqlite:///{folder / 'bench.sqlite3'}", research_token=TOKEN, planning_workers=2)
    app = create_app(settings)
    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=free_port(), log_level="warning"))
    thread = threading.Thread(target=server.run, name="uvicorn", daemon=True)
    began = time.perf_counter()
    thread.start()
    while not server.started:
        time.sleep(0.01)
    up = time.perf_counter() - began
    while app.state.upkeep.drawn_ahead is None:
        time.sleep(0.05)
    ahead_seconds = time.perf_counter() - began
    base = f"http://127.0.0.1:{server.config.port}"
    drawn = app.state.upkeep.drawn_ahead
    print(f"server up in {up:.2f} s; {drawn} plan pictures drawn ahead, done {ahead_seconds:.1f} s after start")

    clicks: dict[str, list[float]] = {}
    plans: dict[str, list[float]] = {}
    cold: dict[str, float] = {}
    pages: dict[str, Page] = {}
    codes: dict[str, str] = {}
    with httpx.Client(base_url=base, timeout=60) as http, sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        context = browser.new_context()
        for case in CASES:
            page = context.new_page()
            devtools = context.new_cdp_session(page)
            devtools.send("Network.enable")
            devtools.send("Network.setCacheDisabled", {"cacheDisabled": True})
            codes[case.name] = participant(http, case)
            open_step2(page, base, codes[case.name], case.rules)
            timed(page.evaluate(CLICK_TO_PICTURE))  # a first, untimed click: the page's first script and image paths
            pages[case.name] = page
        for _ in range(args.rounds):
            for case in CASES:
                page = pages[case.name]
                open_step2(page, base, codes[case.name], case.rules)
                plans.setdefault(case.name, []).append(page.evaluate(PLAN_ONLY, case.rules))
                clicks.setdefault(case.name, []).append(timed(page.evaluate(CLICK_TO_PICTURE)))
        for case in CASES:  # the reference: a picture nobody drew ahead
            open_step2(pages[case.name], base, codes[case.name], case.rules)
            app.state.services.caches.plan_pictures.clear()
            cold[case.name] = timed(pages[case.name].evaluate(CLICK_TO_PICTURE))
        browser.close()
    server.should_exit = True
    thread.join(30)

    print(f"\n{'model':34} {'plan only':>11} {'click->picture':>15} {'not drawn ahead':>16}   (medians, ms)")
    for case in CASES:
        print(
            f"{case.name:34} {statistics.median(plans[case.name]):11.1f} "
            f"{statistics.median(clicks[case.name]):15.1f} {cold[case.name]:16.1f}"
        )
    plan_median = statistics.median(value for values in plans.values() for value in values)
    click_median = statistics.median(value for values in clicks.values() for value in values)
    cold_median = statistics.median(cold.values())
    ratio = click_median / plan_median
    print(
        f"\nall models: plan only {plan_median:.1f} ms, click to picture {click_median:.1f} ms, "
        f"not drawn ahead {cold_median:.1f} ms ({len(CASES)} models x {args.rounds} rounds)"
    )
    verdict = "PASS" if ratio <= TARGET_RATIO else "FAIL"
    print(f"target: click to picture <= {TARGET_RATIO:g}x plan only: {ratio:.2f}x  {verdict}")
    machine: dict[str, Any] = {"cpus": os.cpu_count(), "python": platform.python_version()}
    print(f"run {datetime.now(UTC):%Y-%m-%d %H:%M} UTC, {platform.machine()} {machine}")


if __name__ == "__main__":
    main()
