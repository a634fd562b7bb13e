"""The errors of a study's logic: children of ``CausalPlanError``, each with a stable ``code``.

The service gives each its HTTP status (``service/errors.py``); nothing here knows of HTTP.
"""

from __future__ import annotations

from causalplan.errors import CausalPlanError


class StudyError(CausalPlanError):
    """An error of a study's logic (its design, recruiting settings, or a participant's steps)."""

    code = "study_error"


class InvalidExperimentError(StudyError):
    """An experiment definition is incomplete or inconsistent; ``details['errors']`` lists each problem."""

    code = "invalid_experiment"


class InvalidRecruitmentError(StudyError):
    """Recruiting settings, quotas or a crowd platform's link are malformed (answered as ``invalid_request``)."""

    code = "invalid_request"


class StepLockedError(StudyError):
    """The participant's work on this step is finished (or not reached yet), so it cannot change."""

    code = "step_locked"


class PlatformIdRequiredError(StudyError):
    """The study takes only arrivals from a crowd platform, and the link carried no platform ids."""

    code = "platform_id_required"
