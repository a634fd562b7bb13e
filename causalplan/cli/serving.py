"""The serve command: the HTTP planning service."""

from __future__ import annotations

import click

from causalplan.cli.common import exit_on_error, fail, say


@click.command(short_help="Run the HTTP planning service (JSON API and participant pages).")
@click.option("--host", default="127.0.0.1", help="Address to listen on (0.0.0.0: every interface).")
@click.option("--port", type=click.IntRange(1, 65535), default=8000, help="Port to listen on.")
@click.option(
    "--workers",
    type=click.IntRange(1, 64),
    show_default=False,
    help="Planner worker processes (default: CAUSALPLAN_PLANNING_WORKERS, else 2).",
)
@click.option(
    "--database-url",
    show_default=False,
    help="SQLAlchemy URL, e.g. postgresql://user:password@host/db (default: CAUSALPLAN_DATABASE_URL, "
    "else a SQLite file in the user's data folder, ~/.local/share/causalplan on Linux, created on first start).",
)
@click.option(
    "--access-log/--no-access-log",
    default=None,
    help="Log one line per request (default: CAUSALPLAN_ACCESS_LOG, else on). Errors are logged either way.",
)
def serve(host: str, port: int, workers: int | None, database_url: str | None, access_log: bool | None) -> None:
    """Run the HTTP planning service: JSON API under /v1, OpenAPI docs at /docs, /health.

    Other settings come from CAUSALPLAN_* environment variables (see causalplan/settings.py and
    docs/service.md), e.g. CAUSALPLAN_RESEARCH_TOKEN to turn on the research endpoints and pages,
    CAUSALPLAN_TRUSTED_PROXIES='["127.0.0.1"]' behind a reverse proxy on the same machine.
    The database is migrated to the newest schema on start. Stop with Ctrl-C.
    """
    from pydantic import ValidationError

    from causalplan.settings import Settings

    overrides: dict[str, object] = {}
    if workers is not None:
        overrides["planning_workers"] = workers
    if database_url is not None:
        overrides["database_url"] = database_url
    if access_log is not None:
        overrides["access_log"] = access_log
    try:
        settings = Settings(**overrides)  # type: ignore[arg-type]  # the rest from the environment
    except ValidationError as exc:
        problems = "; ".join(f"{'.'.join(map(str, e['loc'])) or 'settings'}: {e['msg']}" for e in exc.errors())
        fail("invalid_settings", f"The service settings are invalid: {problems}.")
    from causalplan.service.main import check_startup
    from causalplan.service.main import serve as run_service

    with exit_on_error():
        database = check_startup(settings)
    say(
        f"causalplan service on http://{host}:{port} (API docs: /docs), database {database}, "
        f"{settings.planning_workers} planner worker(s)",
        err=True,
    )
    run_service(settings, host, port)
