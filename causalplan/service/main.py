"""The app factory: routes, the error handlers, the body limit, the offline docs, start-up and shutdown.

``create_app(settings)`` returns the ASGI app; ``serve`` runs it with uvicorn (what
``causalplan serve`` calls). Another ASGI server can use ``causalplan.service.main:create_app``
as a factory, with the settings from the environment.
"""

from __future__ import annotations

import gc
import json
import logging
import threading
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager, suppress
from typing import TYPE_CHECKING, Any

import anyio.to_thread
from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import RedirectResponse, Response
from fastapi.routing import APIRoute
from fastapi_offline import FastAPIOffline
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.routing import BaseRoute, Match
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from causalplan.errors import CausalPlanError
from causalplan.objects.catalog import load_catalog
from causalplan.service.api.routes import (
    experiments,
    explanations,
    health,
    jobs,
    models,
    objects,
    plans,
    research,
    simulations,
    transfers,
    troubleshooting,
)
from causalplan.service.api.schemas.common import error_responses
from causalplan.service.caches import ServiceCaches
from causalplan.service.deps import Services
from causalplan.service.documents import default_planner
from causalplan.service.errors import BodyTooLargeError, error_body, http_status
from causalplan.service.fair_share import ClientMiddleware, FairSharePool
from causalplan.service.jobs.runner import JobRunner
from causalplan.service.pages import routers as web_routers
from causalplan.service.pool.pool import PlannerPool
from causalplan.service.readiness import start_proving
from causalplan.service.responses import SafeJSONResponse
from causalplan.service.storage.migrate import upgrade
from causalplan.service.storage.session import create_database_engine
from causalplan.service.storage.throttle import FailedAttempts
from causalplan.service.work.calls import Workers, catalog_key
from causalplan.settings import Settings
from causalplan.version import __version__

if TYPE_CHECKING:
    import uvicorn

logger = logging.getLogger(__name__)

_HTTP_CODES = {404: "not_found", 405: "method_not_allowed", 413: "body_too_large"}


def start_services(settings: Settings) -> Services:
    """Prepare the database (migrations), load the catalog, start the planner pool and prove it ready."""
    catalog = load_catalog(settings.catalog_folders)
    engine = create_database_engine(settings.database_url, settings.database_connections)
    try:
        revision = upgrade(engine, settings.database_wait_seconds)
        pool = FairSharePool(settings)  # interactive requests take turns fairly, client by client
        pool.start()
    except BaseException:
        engine.dispose()
        raise
    # Long work's own workers, one per runner thread (no queue: a runner waits for its worker).
    job_pool = PlannerPool(max(settings.job_runners, 1), 0, settings.worker_memory_mb, settings.queue_wait_seconds)
    caches = ServiceCaches.of(settings)
    fingerprint = catalog_key(catalog)
    services = Services(
        settings,
        catalog,
        engine,
        pool,
        caches,
        revision,
        catalog_key=fingerprint,
        failed_attempts=FailedAttempts(
            engine,
            settings.research_max_failures,
            settings.research_failure_window_seconds,
            settings.research_max_failures_total,
        ),
        job_pool=job_pool,
        work=Workers(pool, job_pool, settings, caches.answers, fingerprint),
    )
    services.readiness = start_proving(
        services.work, catalog, default_planner()
    )  # first in the pool's line: before any drawing
    threading.Thread(target=_probe, args=(services,), name="causalplan-probe", daemon=True).start()
    services.runner = JobRunner(services)
    services.runner.start()
    return services


def check_startup(settings: Settings) -> str:
    """Load the catalog and migrate the database, so start-up problems show as plain errors.

    Returns the database URL with any password hidden.
    """
    load_catalog(settings.catalog_folders)
    engine = create_database_engine(settings.database_url)
    try:
        upgrade(engine, settings.database_wait_seconds)
        return engine.url.render_as_string()
    finally:
        engine.dispose()


_probe_lock = threading.Lock()
_probe_result: dict[str, object] | None = None


def _probe(services: Services) -> None:
    # Imports every optional backend, which slows a process's later forks: so it runs in a
    # process of its own, once per server process (what a worker can import does not change).
    global _probe_result
    try:
        with _probe_lock:
            if _probe_result is None:
                _probe_result = services.work.probe()
            services.probe = _probe_result
    except Exception:
        logger.exception("the planner probe failed")
    finally:
        services.probe_done.set()


def stop_services(services: Services) -> None:
    """Stop the job runner and the workers, and close the database connections.

    The runner puts its running jobs back in the queue; a job busy in a worker ends when the
    pool closes, and is put back then.
    """
    if services.runner is not None:
        services.runner.stop()
    services.pool.close()
    services.job_pool.close()
    if services.runner is not None:
        services.runner.join(10.0)
    services.engine.dispose()


UPLOAD_PATH = "/v1/jobs"
"""Where request bodies carry uploads (a batch of trials), so ``max_upload_bytes`` applies instead."""


class BodyLimitMiddleware:
    """Refuse request bodies over ``max_bytes`` with 413, before any route reads them.

    At ``UPLOAD_PATH`` the limit is ``upload_bytes`` instead.
    """

    def __init__(self, app: ASGIApp, max_bytes: int, upload_bytes: int | None = None) -> None:
        self.app = app
        self.max_bytes = max_bytes
        self.upload_bytes = upload_bytes if upload_bytes is not None else max_bytes

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        limit = self.upload_bytes if scope["path"] == UPLOAD_PATH else self.max_bytes
        declared = dict(scope["headers"]).get(b"content-length")
        if declared is not None and declared.isdigit() and int(declared) > limit:
            await self._refuse(scope, receive, send, limit)
            return
        chunks: list[bytes] = []
        size = 0
        more = True
        while more:
            message = await receive()
            if message["type"] == "http.disconnect":
                return
            chunk = message.get("body", b"")
            size += len(chunk)
            if size > limit:
                await self._refuse(scope, receive, send, limit)
                return
            chunks.append(chunk)
            more = message.get("more_body", False)
        body: Message | None = {"type": "http.request", "body": b"".join(chunks), "more_body": False}

        async def receive_body() -> Message:  # the body once, then whatever comes (a disconnect)
            nonlocal body
            if body is None:
                return await receive()
            message, body = body, None
            return message

        await self.app(scope, receive_body, send)

    async def _refuse(self, scope: Scope, receive: Receive, send: Send, limit: int) -> None:
        error = BodyTooLargeError(f"The request body is over the limit of {limit} bytes.", details={"limit": limit})
        await _error_response(error.code, error.message, error.status_code, error.details)(scope, receive, send)


class UnexpectedErrorMiddleware:
    """Answer a bug with 500 in the one error shape, and keep the connection.

    Starlette's own last resort re-raises after answering, and uvicorn then drops the kept-alive
    connection, so the client's next request on it fails too.
    """

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        started = False

        async def tracked_send(message: Message) -> None:
            nonlocal started
            started = started or message["type"] == "http.response.start"
            await send(message)

        try:
            await self.app(scope, receive, tracked_send)
        except Exception as exc:
            logger.error("unexpected error", exc_info=exc)
            if started:  # half an answer is out: nothing better can be said on this connection
                raise
            response = _error_response(
                "internal_error", "Something went wrong on the server; the log has the details.", 500
            )
            await response(scope, receive, send)


def _error_response(
    code: str,
    message: str,
    status: int,
    details: dict[str, object] | None = None,
    headers: dict[str, str] | None = None,
) -> SafeJSONResponse:
    return SafeJSONResponse(error_body(code, message, details), status_code=status, headers=headers)


async def handle_causalplan_error(_: Request, exc: Exception) -> SafeJSONResponse:
    """The one handler of every causalplan error: its code, message, details and HTTP status."""
    assert isinstance(exc, CausalPlanError)
    status = http_status(exc)
    if status >= 500:
        logger.warning("%s: %s", exc.code, exc.message)
    return _error_response(exc.code, exc.message, status, exc.details, getattr(exc, "headers", None))


def _location(loc: tuple[Any, ...]) -> str:
    return " > ".join(str(piece) for piece in loc if piece != "body") or "body"


async def handle_validation_error(_: Request, exc: Exception) -> SafeJSONResponse:
    """Turn FastAPI's request validation errors into the one error shape (a JSON error says where)."""
    assert isinstance(exc, RequestValidationError)
    cause = exc.__cause__
    if isinstance(cause, json.JSONDecodeError):
        where = {"line": cause.lineno, "column": cause.colno}
        return _error_response(
            "invalid_json",
            f"The body is not JSON this service reads: {cause.msg} (line {cause.lineno}, column {cause.colno}).",
            422,
            {"errors": [{"location": f"line {cause.lineno}, column {cause.colno}", "message": cause.msg}], **where},
        )
    errors = [
        {
            "location": _location(tuple(error.get("loc", ()))),
            "message": str(error.get("msg", "")),
            "type": error["type"],
        }
        for error in exc.errors()
    ]
    summary = "; ".join(f"{error['location']}: {error['message']}" for error in errors[:3])
    return _error_response("invalid_request", "The request is invalid: " + summary, 422, {"errors": errors})


_METHODS = ("GET", "HEAD", "POST", "PUT", "PATCH", "DELETE")


def _methods_for(routes: list[BaseRoute], path: str) -> set[str]:
    """Return the HTTP methods some route answers at ``path`` (empty: no route has this path)."""
    methods = set()
    for method in _METHODS:
        scope = {"type": "http", "path": path, "method": method, "root_path": "", "headers": []}
        if any(route.matches(scope)[0] == Match.FULL for route in routes):
            methods.add(method)
    return methods


async def handle_http_error(request: Request, exc: Exception) -> Response:
    """Turn Starlette's HTTP errors (unknown route, wrong method) into the one error shape."""
    assert isinstance(exc, StarletteHTTPException)
    if exc.status_code == 400:  # a body FastAPI could not read that is not a JSON error (see documents)
        return _error_response("invalid_json", "The body could not be read as JSON.", 422)
    headers = dict(getattr(exc, "headers", None) or {})
    message = str(exc.detail)
    path = request.url.path
    if exc.status_code == 404:
        message = "There is no such route; the API is described at /docs."
        stripped = path.rstrip("/")
        if stripped and stripped != path and _methods_for(request.app.routes, stripped):
            if not path.startswith("/v1/") and request.method in ("GET", "HEAD"):  # a page: take the reader there
                return RedirectResponse(request.url.replace(path=stripped), status_code=307)
            message = f"There is no such route; did you mean {stripped} (without the trailing slash)?"
    if exc.status_code == 405:
        # Starlette names the methods of the first route with this path; several routes may share it.
        headers["Allow"] = ", ".join(sorted(_methods_for(request.app.routes, path)))
        message = f"This route does not accept {request.method}; it accepts {headers['Allow']}."
    code = _HTTP_CODES.get(exc.status_code, "http_error")
    return _error_response(code, message, exc.status_code, headers=headers)


def operation_id(route: APIRoute) -> str:
    """Return a route's OpenAPI operation id: its name (``create_plan``), the method name a generated client gets.

    FastAPI's default adds the path and method (``create_plan_v1_plans_post``), which changes when
    a path does; names are stable and ``tests/service/api/test_openapi.py`` checks they are unique.
    """
    return route.name


def create_app(settings: Settings | None = None) -> FastAPI:
    """Return the service's ASGI app (settings from the environment when none are given)."""
    settings = settings or Settings()

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        services = await anyio.to_thread.run_sync(start_services, settings)
        # Each waiting solve holds one of anyio's worker threads; leave room for the other routes.
        limiter = anyio.to_thread.current_default_thread_limiter()
        limiter.total_tokens = max(limiter.total_tokens, settings.request_threads)  # the database pool's size too
        app.state.services = services
        # What start-up made lives as long as the app: out of the collector's full passes.
        gc.collect()
        gc.freeze()
        try:
            yield
        finally:
            gc.unfreeze()
            await anyio.to_thread.run_sync(stop_services, services)

    # FastAPIOffline: /docs and /redoc load Swagger UI and ReDoc from the package, not a CDN.
    app = FastAPIOffline(
        title="causalplan",
        version=__version__,
        summary="Teach a robot why an object works, then plan with that knowledge.",
        description=(
            "Post a causal model (which parts carry which functions, and keyword rules that produce "
            "the goal); get its validation report, a replayed assembly plan from Fast Downward, and "
            "transfer verdicts for other objects. Errors always have the shape "
            '`{"error": {"code", "message", "details"}}`.'
        ),
        lifespan=lifespan,
        default_response_class=SafeJSONResponse,
        responses=error_responses(413, 422),
        redirect_slashes=False,
        generate_unique_id_function=operation_id,
    )
    app.add_exception_handler(CausalPlanError, handle_causalplan_error)
    app.add_exception_handler(RequestValidationError, handle_validation_error)
    app.add_exception_handler(StarletteHTTPException, handle_http_error)
    app.add_middleware(ClientMiddleware, settings=settings)
    app.add_middleware(UnexpectedErrorMiddleware)
    app.add_middleware(BodyLimitMiddleware, max_bytes=settings.max_body_bytes, upload_bytes=settings.max_upload_bytes)
    routers = (models, plans, simulations, transfers, troubleshooting, explanations, jobs, objects, research, health)
    for module in (*routers, experiments):
        app.include_router(module.router)
    for router in web_routers():  # the participant and research pages
        app.include_router(router)
    return app


def uvicorn_config(settings: Settings, host: str, port: int, log_level: str = "info") -> uvicorn.Config:
    """Return how ``serve`` runs the app with uvicorn.

    uvicorn's own reading of X-Forwarded-For is off: ``deps.client_address`` trusts it only
    from the proxies the settings name.
    """
    import uvicorn

    return uvicorn.Config(
        create_app(settings),
        host=host,
        port=port,
        log_level=log_level,
        access_log=settings.access_log,
        proxy_headers=False,
        timeout_graceful_shutdown=10,
    )


def serve(settings: Settings, host: str, port: int, log_level: str = "info") -> None:
    """Run the service with uvicorn until interrupted (what ``causalplan serve`` does)."""
    import uvicorn

    with suppress(KeyboardInterrupt):  # uvicorn raises Ctrl-C again once it has shut down (as uvicorn.run does)
        uvicorn.Server(uvicorn_config(settings, host, port, log_level)).run()
