"""HTML pages: the Jinja2 templates shipped in the package, their headers, and errors shown as pages.

Every template is autoescaped: labels are free text typed by participants, so they are only
ever shown as text. Pages carry a strict Content-Security-Policy (scripts and styles from
this server only, nothing inline but the import map of the robot player's libraries, allowed
by its hash) and send no Referer, because participant links hold a secret.
"""

from __future__ import annotations

import base64
import hashlib
import json
import logging
from collections.abc import Callable, Coroutine, Sequence
from functools import cache
from typing import Any
from urllib.parse import quote

import jinja2
import markupsafe
from fastapi import Request, Response
from fastapi.exceptions import RequestValidationError
from fastapi.responses import HTMLResponse, RedirectResponse
from fastapi.routing import APIRoute

from causalplan.errors import CausalPlanError
from causalplan.service.errors import LoginRequiredError, http_status
from causalplan.version import __version__

logger = logging.getLogger(__name__)

IMPORT_MAP = json.dumps(
    {
        "imports": {
            "three": "/web/vendor/three/build/three.module.js",
            "three/addons/": "/web/vendor/three/examples/jsm/",
            "three/examples/jsm/": "/web/vendor/three/examples/jsm/",
            "urdf-loader": "/web/vendor/urdf-loader/URDFLoader.js",
        }
    }
)
"""Where the robot player's modules find three.js and urdf-loader: the one inline script, allowed by its hash."""
IMPORT_MAP_SOURCE = "'sha256-" + base64.b64encode(hashlib.sha256(IMPORT_MAP.encode()).digest()).decode() + "'"
CONTENT_SECURITY_POLICY = (
    "default-src 'self'; img-src 'self' data:; script-src 'self' " + IMPORT_MAP_SOURCE + "; style-src 'self'; "
    "object-src 'none'; base-uri 'none'; form-action 'self'{posts_to}; frame-ancestors {framed_by}"
)
PAGE_HEADERS = {
    "Content-Security-Policy": CONTENT_SECURITY_POLICY.format(posts_to="", framed_by="'none'"),
    "X-Content-Type-Options": "nosniff",
    "Cache-Control": "no-store",
}
"""Headers of every page (pages are personal: never cached, never framed)."""
SECRET_URL_REFERRER = "no-referrer"
"""A participant's page has their code in its address: it never goes out as a Referer."""
REFERRER = "same-origin"
"""Other pages send it only to this server (browsers then send Origin on form posts, which the research pages check)."""


@cache
def environment() -> jinja2.Environment:
    """Return the template environment (templates read from the installed package)."""
    env = jinja2.Environment(
        loader=jinja2.PackageLoader("causalplan.service.pages", "templates"),
        autoescape=True,
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    env.globals["version"] = __version__
    env.globals["import_map"] = markupsafe.Markup(IMPORT_MAP)  # JSON of fixed paths; its hash is in the CSP
    env.filters["nice"] = lambda identifier: str(identifier).replace("_", " ")
    return env


def render(
    request: Request,
    template: str,
    status_code: int = 200,
    secret_url: bool = False,
    framed_by: Sequence[str] = (),
    posts_to: Sequence[str] = (),
    **context: Any,
) -> HTMLResponse:
    """Return the page ``template`` filled with ``context`` (``secret_url``: its address holds a participant code).

    ``framed_by``: the only origins that may show the page in a frame (MTurk shows a study in
    one); ``posts_to``: origins besides this server its forms may post to (MTurk's submit host).
    Both are fixed origins chosen by the code, never taken from a request.
    """
    html = environment().get_template(template).render(request=request, **context)
    referrer = SECRET_URL_REFERRER if secret_url else REFERRER
    headers = {**PAGE_HEADERS, "Referrer-Policy": referrer}
    if framed_by or posts_to:
        headers["Content-Security-Policy"] = CONTENT_SECURITY_POLICY.format(
            posts_to="".join(f" {origin}" for origin in posts_to), framed_by=" ".join(framed_by) or "'none'"
        )
    return HTMLResponse(html, status_code=status_code, headers=headers)


def redirect(path: str) -> RedirectResponse:
    """Return a 303 redirect (after a form post, the browser gets the page with GET)."""
    return RedirectResponse(path, status_code=303, headers={"Cache-Control": "no-store"})


def error_page(request: Request, status: int, title: str, message: str) -> HTMLResponse:
    """Return an error as a page."""
    return render(request, "error.html", status_code=status, secret_url=True, title=title, message=message)


_TITLES = {
    401: "Please sign in",
    403: "Not allowed",
    404: "Not found",
    409: "This step is closed",
    422: "Please check",
    429: "Please try again shortly",
}


class PageRoute(APIRoute):
    """A route whose errors are pages, not JSON: the service's errors keep their status and message.

    A research page opened without the token sends the browser to the sign-in form instead.
    """

    def get_route_handler(self) -> Callable[[Request], Coroutine[Any, Any, Response]]:
        handler = super().get_route_handler()

        async def page_handler(request: Request) -> Response:
            try:
                return await handler(request)
            except LoginRequiredError:
                return redirect(f"/research/login?next={quote(request.url.path, safe='/')}")
            except CausalPlanError as exc:
                status = http_status(exc)
                if status >= 500:
                    logger.warning("%s: %s", exc.code, exc.message)
                page = error_page(request, status, _TITLES.get(status, "Something went wrong"), exc.message)
                page.headers.update(getattr(exc, "headers", {}))  # e.g. Retry-After, as the JSON handler sends
                return page
            except RequestValidationError as exc:
                where = "; ".join(
                    " > ".join(str(piece) for piece in error.get("loc", ())) + ": " + str(error.get("msg", ""))
                    for error in exc.errors()[:3]
                )
                return error_page(request, 422, "Please check", f"The address or form is not valid ({where}).")

        return page_handler
