"""Research pages: the same research token as the JSON endpoints, as a bearer header or a sign-in cookie.

Signing in with the token sets an HttpOnly, SameSite=Strict cookie that holds an expiry time,
a random session id and an HMAC of both keyed by the token, never the token itself: it lapses
on its own, and changing the token signs everyone out. Signing out stores the session id as
revoked in the database until the cookie would have lapsed, so a copy of the cookie is refused
by every server process sharing that database.
"""

from __future__ import annotations

import hashlib
import hmac
import secrets
import time
from typing import Annotated

from fastapi import Depends, Request, Response
from sqlalchemy.orm import Session

from causalplan.service.deps import ServicesDep, SessionDep, check_research_token
from causalplan.service.errors import CrossSiteRequestError, LoginRequiredError, ResearchDisabledError
from causalplan.service.storage.revocations import is_revoked, revoke
from causalplan.settings import Settings

COOKIE_NAME = "causalplan_research"
COOKIE_PATH = "/research"
SESSION_SECONDS = 12 * 3600
_SAFE_METHODS = {"GET", "HEAD", "OPTIONS"}


def _signature(token: str, expires: int, session_id: str) -> str:
    message = f"causalplan research pages until {expires} for session {session_id}"
    return hmac.new(token.encode(), message.encode(), hashlib.sha256).hexdigest()


def session_cookie(token: str, now: float | None = None) -> str:
    """Return the cookie value of a new research session that starts now."""
    expires = int(now if now is not None else time.time()) + SESSION_SECONDS
    session_id = secrets.token_hex(16)
    return f"{expires}.{session_id}.{_signature(token, expires, session_id)}"


def cookie_session(value: str, token: str, now: float | None = None) -> tuple[str, int] | None:
    """Return the session id and expiry time of a research cookie of ``token`` that has not lapsed, else None.

    Only the signature and the time are checked here; whether the session was signed out is
    the database's to say (``is_revoked``).
    """
    expires_text, _, rest = value.partition(".")
    session_id, _, signature = rest.partition(".")
    if not expires_text.isdigit() or len(expires_text) > 12 or len(session_id) != 32:
        return None
    expires = int(expires_text)
    if expires < (now if now is not None else time.time()):
        return None
    if not secrets.compare_digest(signature.encode(), _signature(token, expires, session_id).encode()):
        return None
    return session_id, expires


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


def sign_out(response: Response, request: Request, settings: Settings, session: Session) -> None:
    """Revoke the request's session cookie (if it is one) on the server, and clear it on ``response``."""
    cookie = request.cookies.get(COOKIE_NAME)
    if cookie is not None and settings.research_token is not None:
        found = cookie_session(cookie, settings.research_token.get_secret_value())
        if found is not None:
            revoke(session, *found)
    response.delete_cookie(COOKIE_NAME, path=COOKIE_PATH, httponly=True, samesite="strict")


def _same_origin(request: Request) -> bool:
    origin = request.headers.get("origin")
    if origin is None or origin == "null":
        return origin is None  # browsers send Origin on form posts; 'null' is an opaque origin
    return origin == f"{request.url.scheme}://{request.url.netloc}"


def require_research_page(request: Request, services: ServicesDep, session: SessionDep) -> None:
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
    found = cookie_session(cookie, settings.research_token.get_secret_value()) if cookie is not None else None
    if found is None or is_revoked(session, found[0]):
        raise LoginRequiredError("Sign in with the research token to see this page.")
    # SameSite=Strict already keeps the cookie off other sites' requests; this is the second lock.
    if request.method not in _SAFE_METHODS and not _same_origin(request):
        raise CrossSiteRequestError("This form was sent from another site, so it was refused.")


ResearchPageDep = Annotated[None, Depends(require_research_page)]
