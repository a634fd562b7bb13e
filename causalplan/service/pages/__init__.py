"""The participant interface and the experiment runner: the paper's three steps in a browser.

Served by the service's app (``main.create_app`` includes ``routers()``):

* ``/`` the start page and ``/try`` (a participant of the built-in demo: desk lamp, then flashlight);
* ``/s/<experiment>`` the public study link (Prolific, MTurk or none): consent, then admission
  to the emptiest open condition;
* ``/p/<code>/...`` a participant's pages: the toy-car tutorial, step 1 (functions of each
  training object's parts), step 2 (rules, checked as one types, with the graph and the robot's
  plan), step 3 (each test object's parts mapped to the model's functions, and the verdict),
  and their small JSON endpoints (saving drafts, checking rules, planning, pictures);
* ``/research/...`` the research pages (sign in with the research token): define experiments,
  make participant links, follow progress, see transfer rates and trials (and watch the robot
  carry out a trial's plan in 3D), export;

``/v1/experiments``, the same for programs (bearer token), is part of the JSON API
(``service.api.routes.experiments``).

While the app runs, a background thread purges old demo participants and draws the catalog
objects' likely plans ahead (``upkeep``). Templates and scripts ship in the package
(``templates/``, ``static/``); no build step.
"""

from __future__ import annotations

from fastapi import APIRouter


def routers() -> list[APIRouter]:
    """Return the pages' routers, in the order the app includes them."""
    from causalplan.service.pages import (
        assets,
        ending,
        participant,
        participant_api,
        participant_explain,
        research,
        research_robot,
        research_troubleshooting,
        robot_films,
        study_link,
        upkeep,
    )

    return [
        APIRouter(lifespan=upkeep.lifespan),  # no routes: the demo's limit and the background upkeep
        assets.pages,
        assets.router,
        study_link.router,
        participant.router,
        ending.router,
        participant_api.router,
        participant_explain.router,
        robot_films.router,
        research_robot.router,
        research_troubleshooting.router,
        research.router,
    ]
