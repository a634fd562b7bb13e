"""The errors of the participant and research pages; each is a ``ServiceError`` with its HTTP status.

The JSON endpoints answer them in the service's one error shape; the pages render them as
an HTML page (see ``templating.PageRoute``).
"""

from __future__ import annotations

from causalplan.service.errors import InvalidRequestError, NotFoundError, ServiceError, TryLaterError


class ParticipantNotFoundError(NotFoundError):
    """No participant has this link code."""

    code = "participant_not_found"


class ExperimentNotFoundError(NotFoundError):
    """No experiment has this id."""

    code = "experiment_not_found"


class InvalidFormError(InvalidRequestError):
    """A submitted form is malformed (a field missing, repeated, too long, or not one of the choices)."""

    code = "invalid_form"


class LoginRequiredError(ServiceError):
    """A research page was opened without the research token (cookie or bearer)."""

    code = "login_required"
    status_code = 401


class CrossSiteRequestError(ServiceError):
    """A research form was posted from another site (its Origin is not this server)."""

    code = "cross_site_request"
    status_code = 403


class TooManyDemoStartsError(TryLaterError):
    """One client started more demo participants this minute than the service allows."""

    code = "too_many_demo_starts"
