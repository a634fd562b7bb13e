"""The research pages, at ``/research``: sign in, define experiments, make links, see results, export.

They need the research token: as a bearer header, or typed once into the sign-in form, which
sets an HttpOnly cookie (see ``auth``).
"""

from __future__ import annotations

import uuid
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Query, Request, Response
from pydantic import Field, ValidationError

from causalplan.errors import CausalPlanError
from causalplan.service import experiments
from causalplan.service.api.schemas.experiments import ExperimentIn, RecruitmentIn
from causalplan.service.deps import CatalogDep, ServicesDep, SessionDep, SettingsDep, check_research_token
from causalplan.service.errors import InvalidRequestError, TooManyAttemptsError
from causalplan.service.pages.auth import ResearchPageDep, sign_in, sign_out
from causalplan.service.pages.drawings import fresh_svg
from causalplan.service.pages.forms import Form, read_form
from causalplan.service.pages.templating import PageRoute, redirect, render
from causalplan.service.sharing import shareable_zip
from causalplan.service.storage import experiments as store
from causalplan.service.storage.records import ExperimentRecord
from causalplan.settings import Settings
from causalplan.studies.errors import InvalidExperimentError, InvalidRecruitmentError
from causalplan.studies.rates import rates_chart
from causalplan.studies.recruitment import DEMOGRAPHICS
from causalplan.studies.sharing import DEFAULT_LICENSE

router = APIRouter(prefix="/research", route_class=PageRoute, include_in_schema=False)

CODE_FIELDS = ("completion_code", "screened_out_code", "no_consent_code")
FORM_CONDITIONS = 4
"""Condition rows on the new-experiment form (empty rows are ignored)."""


def _local_next(target: str) -> str:
    # Only pages of this server's research area: never an open redirect to another site.
    return (
        target if target.startswith("/research") and not target.startswith("//") and "\\" not in target else "/research"
    )


def _login_page(
    request: Request, settings: Settings, target: str, *, failed: bool = False, retry_after: int | None = None
) -> Response:
    """Return the sign-in form: after a wrong token (401), or refused without a check until ``retry_after`` (429)."""
    response = render(
        request,
        "login.html",
        status_code=429 if retry_after is not None else 401 if failed else 200,
        enabled=settings.research_token is not None,
        next=target,
        failed=failed,
        retry_after=retry_after,
    )
    if retry_after is not None:
        response.headers["Retry-After"] = str(retry_after)
    return response


@router.get("/login")
def login_form(
    request: Request, settings: SettingsDep, target: Annotated[str, Query(alias="next", max_length=500)] = "/research"
) -> Response:
    return _login_page(request, settings, _local_next(target))


@router.post("/login")
async def login(request: Request, services: ServicesDep) -> Response:
    settings = services.settings
    form = await read_form(request)
    token = form.text("token", "", max_length=1000)
    target = _local_next(form.text("next", "/research", max_length=500))
    try:
        # Disabled, there is no token to guess: nothing is compared or counted.
        accepted = settings.research_token is not None and check_research_token(token, request, services)
    except TooManyAttemptsError as exc:
        return _login_page(request, settings, target, retry_after=exc.retry_after)
    if not accepted:
        return _login_page(request, settings, target, failed=True)
    response = redirect(target)
    sign_in(response, request, settings)
    return response


@router.post("/logout")
def logout(request: Request, _: ResearchPageDep, settings: SettingsDep, session: SessionDep) -> Response:
    response = redirect("/research/login")
    sign_out(response, request, settings, session)
    return response


@router.get("")
def experiments_page(request: Request, _: ResearchPageDep, session: SessionDep) -> Response:
    return render(request, "research_index.html", experiments=store.list_experiments(session))


def _new_form(
    request: Request, catalog: CatalogDep, values: dict[str, Any] | None = None, errors: list[str] | None = None
) -> Response:
    return render(
        request,
        "research_new.html",
        status_code=422 if errors else 200,
        objects=sorted(catalog.objects.values(), key=lambda obj: (obj.goal != "light", obj.category, obj.id)),
        rows=range(FORM_CONDITIONS),
        values=values or {},
        errors=errors or [],
    )


@router.get("/experiments/new")
def new_experiment(request: Request, _: ResearchPageDep, catalog: CatalogDep) -> Response:
    defaults = {
        "counterbalance_training": True,
        "counterbalance_tests": True,
        "show_verdict": True,
        "tutorial": True,
        "robot_verdict": False,
        "conditions": [],
    }
    return _new_form(request, catalog, defaults)


def _experiment_values(form: Form) -> dict[str, Any]:
    conditions = []
    for row in range(FORM_CONDITIONS):
        name = form.text(f"condition:{row}:name", "", max_length=100).strip()
        training = [
            value for value in (form.text(f"condition:{row}:training:{i}", "", max_length=200) for i in (0, 1)) if value
        ]
        tests = form.texts(f"condition:{row}:tests", max_count=50, max_length=200)
        if name or training or tests:
            conditions.append({"name": name, "training": training, "tests": tests})
    return {
        "name": form.text("name", "", max_length=200),
        "description": form.text("description", "", max_length=2000),
        "conditions": conditions,
        "counterbalance_training": form.flag("counterbalance_training"),
        "counterbalance_tests": form.flag("counterbalance_tests"),
        "show_verdict": form.flag("show_verdict"),
        "tutorial": form.flag("tutorial"),
        "robot_verdict": form.flag("robot_verdict"),
        "template": form.text("template", "", max_length=50) or None,
    }


def _problems(exc: ValidationError | CausalPlanError) -> list[str]:
    """Return what is wrong with a submitted research form, one sentence a problem, as the page lists them."""
    if isinstance(exc, ValidationError):
        return [" > ".join(str(piece) for piece in e["loc"]) + f": {e['msg']}" for e in exc.errors()]
    errors = exc.details.get("errors")
    return [str(e) for e in errors] if isinstance(errors, list) else [exc.message]


@router.post("/experiments")
async def create_experiment(request: Request, _: ResearchPageDep, session: SessionDep, catalog: CatalogDep) -> Response:
    values = _experiment_values(await read_form(request))
    problems: list[str] = []
    if not values["name"].strip():
        problems.append("Give the experiment a name.")
    for number, condition in enumerate(values["conditions"], start=1):
        if not condition["training"]:
            problems.append(f"Condition {number} ('{condition['name']}') has no training object.")
        if not condition["tests"]:
            problems.append(f"Condition {number} ('{condition['name']}') has no test object.")
    if not values["conditions"] and not values["template"]:
        problems.append("Fill in at least one condition: a name, a training object and a test object.")
    if problems:
        return _new_form(request, catalog, values, problems)
    try:
        record = experiments.create(session, catalog, ExperimentIn.model_validate(values))
    except (ValidationError, InvalidExperimentError) as exc:
        return _new_form(request, catalog, values, _problems(exc))
    return redirect(f"/research/experiments/{record.id}")


def _experiment_page(
    request: Request,
    session: SessionDep,
    catalog: CatalogDep,
    experiment: ExperimentRecord,
    recruitment_errors: list[str] | None = None,
    saved: str | None = None,
) -> Response:
    view = experiments.study_view(session, catalog, experiment, request)
    analysis = view.analysis
    return render(
        request,
        "research_experiment.html",
        status_code=422 if recruitment_errors else 200,
        record=experiment,
        recruitment=experiments.recruitment_out(session, experiment, request),
        recruitment_errors=recruitment_errors or [],
        recruitment_saved=saved == "recruitment",
        demographics=DEMOGRAPHICS,
        analysis=None if isinstance(analysis, str) else analysis.as_dict(),
        crowd_size=view.crowd_size,
        troubleshooting=view.troubleshooting,
        analysis_problem=analysis if isinstance(analysis, str) else None,
        misconception_words={
            participant: [found.says() for found in items]
            for participant, items in ({} if isinstance(analysis, str) else analysis.misconceptions).items()
        },
        **view.results,
    )


@router.get("/experiments/{experiment_id}")
def experiment_page(
    request: Request,
    experiment_id: uuid.UUID,
    _: ResearchPageDep,
    session: SessionDep,
    catalog: CatalogDep,
    saved: Annotated[str | None, Query(max_length=20, description="What was just saved, to confirm it.")] = None,
) -> Response:
    return _experiment_page(request, session, catalog, store.get_experiment(session, experiment_id), saved=saved)


def _whole_number(form: Form, name: str, label: str) -> int | None:
    """Return a number field ('' : None); InvalidRequestError names the field when it is not a whole number."""
    text = form.text(name, "", max_length=12).strip()
    if not text:
        return None
    if not text.isdigit():
        raise InvalidRequestError(f"{label} must be a whole number or empty.", details={"field": name})
    return int(text)


@router.post("/experiments/{experiment_id}/recruitment")
async def set_recruitment(
    request: Request, experiment_id: uuid.UUID, _: ResearchPageDep, session: SessionDep, catalog: CatalogDep
) -> Response:
    experiment = store.get_experiment(session, experiment_id)
    form = await read_form(request)
    conditions = [condition["name"] for condition in experiment.design["conditions"]]
    try:
        body = RecruitmentIn.model_validate(
            {
                "consent_text": form.text("consent_text", "", max_length=10_000),
                **{name: form.text(name, "", max_length=32).strip() for name in CODE_FIELDS},
                "comprehension_tries": _whole_number(form, "comprehension_tries", "The number of tries"),
                "too_fast_seconds": _whole_number(form, "too_fast_seconds", "The too-fast threshold"),
                "require_platform_id": form.text("require_platform_id", "", max_length=8) == "yes",
                "places_per_client": _whole_number(form, "places_per_client", "The places per client address"),
                "demographics": form.texts("demographics", max_count=len(DEMOGRAPHICS), max_length=40),
                "quotas": {
                    name: _whole_number(form, f"quota:{index}", f"The quota of condition '{name}'")
                    for index, name in enumerate(conditions)
                },
            }
        )
        experiments.set_recruitment(session, experiment, body)
    except (ValidationError, InvalidRequestError, InvalidRecruitmentError) as exc:
        return _experiment_page(request, session, catalog, experiment, _problems(exc))
    return redirect(f"/research/experiments/{experiment_id}?saved=recruitment#recruiting")


@router.get("/experiments/{experiment_id}/rates.svg")
def rates_svg(
    request: Request, experiment_id: uuid.UUID, _: ResearchPageDep, session: SessionDep, catalog: CatalogDep
) -> Response:
    """The chart of the rates table: ``causalplan analyze``'s rates.svg of the experiment's export."""
    experiment = store.get_experiment(session, experiment_id)
    table = experiments.rates_of(session, catalog, experiment, request)
    if isinstance(table, str):
        raise InvalidRequestError(f"The rates cannot be drawn: {table}")
    return fresh_svg(rates_chart(table))


@router.get("/experiments/{experiment_id}/consensus.svg")
def consensus_graph(
    request: Request, experiment_id: uuid.UUID, _: ResearchPageDep, session: SessionDep, catalog: CatalogDep
) -> Response:
    """The crowd's consensus model (arrow width: how many participants hold the rule) beside their own models."""
    experiment = store.get_experiment(session, experiment_id)
    svg = experiments.consensus_svg(session, catalog, experiment, request)
    if isinstance(svg, str):
        raise InvalidRequestError(f"There is no consensus to draw: {svg}")
    return fresh_svg(svg)


@router.post("/experiments/{experiment_id}/participants")
async def make_links(request: Request, experiment_id: uuid.UUID, _: ResearchPageDep, session: SessionDep) -> Response:
    experiment = store.get_experiment(session, experiment_id)
    form = await read_form(request)
    count_text = form.text("count", "1", max_length=6).strip()
    condition = form.text("condition", "", max_length=100)
    count = int(count_text) if count_text.isdigit() else 0
    store.add_participants(session, experiment, count, condition or None)
    return redirect(f"/research/experiments/{experiment_id}#participants")


@router.get("/experiments/{experiment_id}/export/shareable")
def export_shareable(
    request: Request,
    experiment_id: uuid.UUID,
    _: ResearchPageDep,
    session: SessionDep,
    catalog: CatalogDep,
    author: Annotated[list[Annotated[str, Field(min_length=1, max_length=200)]], Query(max_length=50)] = [],  # noqa: B006
    license: Annotated[str, Query(min_length=1, max_length=300)] = DEFAULT_LICENSE,
) -> Response:
    """The data to share: the Psych-DS dataset without link codes, links, addresses or raw platform ids."""
    experiment = store.get_experiment(session, experiment_id)
    return shareable_zip(session, catalog, experiment, request, author, license)


@router.get("/experiments/{experiment_id}/export")
def export(
    request: Request,
    experiment_id: uuid.UUID,
    _: ResearchPageDep,
    session: SessionDep,
    catalog: CatalogDep,
    format: Annotated[Literal["json", "csv"], Query()] = "json",
    table: Annotated[Literal["trials", "participants"], Query()] = "trials",
    platform_ids: Annotated[Literal["plain", "hashed", "omit"], Query()] = "plain",
) -> Response:
    experiment = store.get_experiment(session, experiment_id)
    return experiments.export(session, catalog, experiment, request, format, table, platform_ids)
