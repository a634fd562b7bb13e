"""Research pages: the same research token as the JSON endpoints, as a bearer header or a sign-in cookie.

Signing in with the token sets an HttpOnly, SameSite=Strict cookie that holds an expiry time
and an HMAC of it keyed by the token, never the token itself: it lapses on its own, and
changing the token signs everyone out.
"""

from __future__ import annotations

import hashlib
import hmac
import secrets
import time
from typing import Annotated

from fastapi import Depends, Request, Response

from causalplan.service.deps import ServicesDep, check_research_token
from causalplan.service.errors import ResearchDisabledError
from causalplan.service.web.errors import CrossSiteRequestError, LoginRequiredError
from causalplan.settings import Settings

COOKIE_NAME = "causalplan_research"
COOKIE_PATH = "/research"
SESSION_SECONDS = 12 * 3600
_SAFE_METHODS = {"GET", "HEAD", "OPTIONS"}


def _signature(token: str, expires: int) -> str:
    return hmac.new(token.encode(), f"causalplan research pages until {expires}".encode(), hashlib.sha256).hexdigest()


def session_cookie(token: str, now: float | None = None) -> str:
    """Return the cookie value of a research session that starts now."""
    expires = int(now if now is not None else time.time()) + SESSION_SECONDS
    return f"{expires}.{_signature(token, expires)}"


def is_valid_cookie(value: str, token: str, now: float | None = None) -> bool:
    """Return whether ``value`` is a research session cookie of ``token`` that has not expired."""
    expires_text, _, signature = value.partition(".")
    if not expires_text.isdigit() or len(expires_text) > 12:
        return False
    expires = int(expires_text)
    if expires < (now if now is not None else time.time()):
        return False
    return secrets.compare_digest(signature.encode(), _signature(token, expires).encode())


def sign_in(response: Response, request: Request, settings: Settings) -> None:
    """Set the session cookie on ``response``."""
    assert settings.research_token is not None
    response.set_cookie(
        COOKIE_NAME,
        session_cookie(settings.research_token.get_secret_value()),
        max_age=SESSION_SECONDS,
        path=COOKIE_PATH,
        httponly=True,
        samesite="strict",
        secure=request.url.scheme == "https",
    )


def sign_out(response: Response) -> None:
    """Clear the session cookie on ``response``."""
    response.delete_cookie(COOKIE_NAME, path=COOKIE_PATH, httponly=True, samesite="strict")


def _same_origin(request: Request) -> bool:
    origin = request.headers.get("origin")
    if origin is None or origin == "null":
        return origin is None  # browsers send Origin on form posts; 'null' is an opaque origin
    return origin == f"{request.url.scheme}://{request.url.netloc}"


def require_research_page(request: Request, services: ServicesDep) -> None:
    """Let a research page through with the bearer token or a valid session cookie.

    A bearer token counts against the client's failed attempts (``TooManyAttemptsError``); a cookie
    does not: it is an HMAC that cannot be guessed, and a lockout must not sign out researchers.
    """
    settings = services.settings
    if settings.research_token is None:
        raise ResearchDisabledError(
            "The research pages are disabled: start the service with CAUSALPLAN_RESEARCH_TOKEN set."
        )
    scheme, _, credentials = request.headers.get("authorization", "").partition(" ")
    if scheme.lower() == "bearer" and check_research_token(credentials.strip(), request, services):
        return
    cookie = request.cookies.get(COOKIE_NAME)
    if cookie is None or not is_valid_cookie(cookie, settings.research_token.get_secret_value()):
        raise LoginRequiredError("Sign in with the research token to see this page.")
    # SameSite=Strict already keeps the cookie off other sites' requests; this is the second lock.
    if request.method not in _SAFE_METHODS and not _same_origin(request):
        raise CrossSiteRequestError("This form was sent from another site, so it was refused.")


ResearchPageDep = Annotated[None, Depends(require_research_page)]
