"""A launch-day participant (``launch.py``): a Locust user taking the real pages from study link to the end.

Each request goes to a live replica picked at random, and once more to the other when the
first gives no answer (killed under it, or before). What every participant did and saw goes to
the run they share (``Participant.run_state``, set by ``launch.py`` before the users start).
Imported by ``launch.py`` after gevent has patched the standard library.
"""

from __future__ import annotations

import random
import re
import subprocess
import time
import uuid
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import gevent
import requests
from gevent.event import Event
from locust import HttpUser, task
from locust.exception import StopUser

REQUEST_SECONDS = 120.0
TUTORIAL = {
    "answer:sticker": "no",
    "answer:diffuse": "no",
    "answer:and": "and",
    "rules": "store energy AND turn the axle CAUSES the axle spins\n"
    "the axle spins AND roll on the ground CAUSES motion",
}
STEP1 = {
    "part:base_with_cables": "provide electricity",
    "part:light_bulb": "turn electricity into light\nclose the circuit",
}
STEP2 = {
    "rules": "provide electricity AND close the circuit CAUSES electricity flows\n"
    "electricity flows AND turn electricity into light CAUSES light"
}
STEP3_CHOICES: dict[str, str | list[str]] = {
    "batteries": "provide electricity",
    "head": ["turn electricity into light", "close the circuit"],
    "wax": "provide electricity",
    "wick": "turn electricity into light",
    "match": "close the circuit",
}
"""What a participant maps to each test object's part (an electric model on the candle too: it transfers)."""
CHOICE_FIELD = re.compile(r'name="chosen:([a-z_]+)"')
ARRIVAL_FIELD = re.compile(r'name="arrival" value="([A-Za-z0-9]+)"')


@dataclass
class Replica:
    """One ``causalplan serve`` process and what it answered."""

    url: str
    process: subprocess.Popen[bytes]
    log: Path
    alive: bool = True
    in_flight: int = 0
    server_errors: int = 0
    answers: int = 0


@dataclass
class Run:
    """What every participant did and saw, shared by the Locust users (greenlets of one thread)."""

    replicas: list[Replica]
    study: str
    think: tuple[float, float]
    latencies: list[float] = field(default_factory=list)
    acknowledged: list[tuple[str, str]] = field(default_factory=list)
    """(participant code, what was saved) for every form the service answered with 303."""
    outcomes: Counter[str] = field(default_factory=Counter)
    retries: int = 0
    participants: int = 0
    failed_requests: int = 0
    next_participant: int = 0
    ended: int = 0
    """Participants whose journey has ended (finished, turned away, or stopped by a refusal)."""
    over: Event = field(default_factory=Event)
    """Set when the run ends: the participants who have ended wait for it."""


class Participant(HttpUser):
    """A Prolific participant: study link, consent, tutorial, steps 1-3, the end; then gone."""

    host = "http://127.0.0.1"  # every request names its replica in full
    run_state: ClassVar[Run]
    """The run every participant reports to (set before the users start)."""

    def on_start(self) -> None:
        number = self.run_state.next_participant
        self.run_state.next_participant += 1
        self.number = number
        self.address = f"10.{(number >> 16) & 255}.{(number >> 8) & 255}.{number & 255}"
        self.ids = {
            "PROLIFIC_PID": uuid.uuid4().hex[:24],
            "STUDY_ID": "launchday0000000000000001",
            "SESSION_ID": uuid.uuid4().hex,
        }

    def _replica(self, avoid: Replica | None = None) -> Replica | None:
        live = [replica for replica in self.run_state.replicas if replica.alive and replica is not avoid]
        return random.choice(live) if live else None

    def send(self, method: str, path: str, name: str, data: dict[str, Any] | None = None) -> requests.Response | None:
        """Send one page request to a random live replica; once more to another if that one is gone."""
        started = time.perf_counter()
        tried: Replica | None = None
        for attempt in range(2):
            replica = self._replica(avoid=tried)
            if replica is None:
                break
            tried = replica
            replica.in_flight += 1
            with self.client.request(
                method,
                replica.url + path,
                name=name,
                data=data,
                headers={"X-Forwarded-For": self.address},
                allow_redirects=False,
                timeout=REQUEST_SECONDS,
                catch_response=True,
            ) as response:
                replica.in_flight -= 1
                if response.status_code == 0:  # no answer: the replica died under it, or before
                    response.success()  # counted below as a retry, not as the page's failure
                    if attempt == 0:
                        self.run_state.retries += 1
                    continue
                replica.answers += 1
                if response.status_code >= 500:
                    replica.server_errors += 1
                    response.failure(f"{response.status_code}")
                else:
                    response.success()
                self.run_state.latencies.append(time.perf_counter() - started)
                return response
        self.run_state.failed_requests += 1
        return None

    def think(self) -> None:
        gevent.sleep(random.uniform(*self.run_state.think))

    def form(self, path: str, name: str, data: dict[str, Any], saved: str, code: str) -> str:
        """Post a form; return where it sends the participant (StopUser when it was not accepted)."""
        self.think()
        answer = self.send("POST", path, name, data)
        if answer is None or answer.status_code != 303:
            self.run_state.outcomes[
                f"refused at {name}: {answer.status_code if answer is not None else 'no answer'}"
            ] += 1
            raise StopUser
        if saved:
            self.run_state.acknowledged.append((code, saved))
        return str(answer.headers["location"])

    def page(self, path: str, name: str) -> str:
        answer = self.send("GET", path, name)
        if answer is None or answer.status_code not in (200, 303):
            self.run_state.outcomes[
                f"no page at {name}: {answer.status_code if answer is not None else 'no answer'}"
            ] += 1
            raise StopUser
        return answer.text

    @task
    def take_part(self) -> None:
        """Take part once, then wait for the run's end (a user that stopped would be replaced by a new one)."""
        if self.number >= self.run_state.participants:  # a replacement Locust started: not a participant
            self.run_state.over.wait()
            raise StopUser
        try:
            self.journey()
        except StopUser:
            pass
        finally:
            self.run_state.ended += 1
        self.run_state.over.wait()
        raise StopUser

    def journey(self) -> None:
        study = self.run_state.study
        query = "&".join(f"{key}={value}" for key, value in self.ids.items())
        consent = self.page(f"/s/{study}?{query}", "/s/[study]")
        found = ARRIVAL_FIELD.search(consent)
        if found is None:
            self.run_state.outcomes["turned away: study full" if "study is full" in consent else "no consent form"] += 1
            return
        self.think()
        agreed = self.send(
            "POST", f"/s/{study}/consent", "/s/[study]/consent", {"arrival": found.group(1), "decision": "agree"}
        )
        if agreed is None or agreed.status_code != 303:
            full = agreed is not None and "study is full" in agreed.text
            self.run_state.outcomes[
                "turned away at consent: study full" if full else f"consent: {_status(agreed)}"
            ] += 1
            return
        code = str(agreed.headers["location"]).removeprefix("/p/")
        self.run_state.acknowledged.append((code, "consent"))
        base = f"/p/{code}"
        self.page(f"{base}/tutorial", "/p/[code]/tutorial")
        self.form(f"{base}/tutorial", "/p/[code]/tutorial", TUTORIAL, "tutorial", code)
        self.page(f"{base}/step1/1", "/p/[code]/step1/1")
        self.form(f"{base}/step1/1", "/p/[code]/step1/1", STEP1, "step1", code)
        self.page(f"{base}/step2", "/p/[code]/step2")
        self.form(f"{base}/step2", "/p/[code]/step2", STEP2, "step2", code)
        step3 = self.page(f"{base}/step3/1", "/p/[code]/step3/1")
        choices = {
            f"chosen:{part}": STEP3_CHOICES[part] for part in CHOICE_FIELD.findall(step3) if part in STEP3_CHOICES
        }
        self.form(f"{base}/step3/1", "/p/[code]/step3/1", choices, "step3", code)
        self.page(f"{base}/step3/1", "/p/[code]/step3/1 (verdict)")
        after = self.form(f"{base}/step3/1/next", "/p/[code]/step3/1/next", {}, "", code)
        if after.endswith("/about"):
            self.page(after, "/p/[code]/about")
            after = self.form(after, "/p/[code]/about", {}, "", code)
        self.page(after, "/p/[code]/done")
        self.run_state.acknowledged.append((code, "finished"))
        self.run_state.outcomes["completed the journey"] += 1


def _status(answer: requests.Response | None) -> str:
    return str(answer.status_code) if answer is not None else "no answer"
