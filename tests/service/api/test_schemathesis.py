"""Schemathesis against the OpenAPI document: generated requests to every route of a real server, never a 5xx.

Bounded: a few examples per route and no shrinking, so the whole module takes seconds.
"""

from __future__ import annotations

from typing import Any

import httpx
import pytest
import schemathesis
from hypothesis import HealthCheck, Phase, settings
from schemathesis.checks import (
    content_type_conformance,
    not_a_server_error,
    response_schema_conformance,
    status_code_conformance,
)

from causalplan.service.main import create_app
from tests.service.fixtures import AUTH, settings_for

pytestmark = pytest.mark.slow  # schemathesis sends thousands of generated requests

# The document of the app the server runs (building an app starts nothing: no workers, no database).
OPENAPI = create_app(settings_for("sqlite://")).openapi()
schema = schemathesis.openapi.from_dict(OPENAPI)


def test_the_server_serves_this_document(live_server: str) -> None:
    assert httpx.get(f"{live_server}/openapi.json").json() == OPENAPI


@schema.parametrize()
@settings(
    max_examples=25,
    deadline=None,
    phases=[Phase.explicit, Phase.generate],
    suppress_health_check=list(HealthCheck),
    derandomize=True,
)
def test_no_request_makes_the_service_fail(case: Any, live_server: str) -> None:
    case.call_and_validate(
        base_url=live_server,
        headers=AUTH,
        checks=[not_a_server_error, status_code_conformance, content_type_conformance, response_schema_conformance],
    )


def test_job_workflows_follow_the_links_from_post_to_get_and_delete(live_server: str) -> None:
    """Stateful: a job posted by a generated body is then read, cancelled or asked for its film by its real id."""
    posted: set[str] = set()
    followed: list[tuple[str, int]] = []
    base = schema.include(path_regex="^/v1/jobs").as_state_machine()

    class JobWorkflow(base):  # type: ignore[misc,valid-type]
        def get_call_kwargs(self, case: Any) -> dict[str, Any]:
            return {"base_url": live_server, "headers": AUTH}

        def after_call(self, response: Any, case: Any) -> None:
            if response.status_code == 202:
                posted.add(response.json()["id"])
            elif str((case.path_parameters or {}).get("job_id")) in posted:
                followed.append((f"{case.method} {case.operation.path}", response.status_code))

        def validate_response(self, response: Any, case: Any, additional_checks: Any = None, **kwargs: Any) -> None:
            case.validate_response(
                response,
                checks=[
                    not_a_server_error,
                    status_code_conformance,
                    content_type_conformance,
                    response_schema_conformance,
                ],
            )

    JobWorkflow.run(
        settings=settings(
            max_examples=20,
            stateful_step_count=4,
            deadline=None,
            suppress_health_check=list(HealthCheck),
            derandomize=True,
        )
    )
    assert posted, "no generated body was a valid job"
    assert followed, "no link from a posted job was followed"
