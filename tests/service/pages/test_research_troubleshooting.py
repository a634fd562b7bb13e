"""The research page: troubleshooting with the participants' models, per condition and test object."""

from __future__ import annotations

from fastapi.testclient import TestClient

from tests.service_fixtures import AUTH
from tests.web_flows import complete, experiment, links


def test_the_research_page_scores_the_models_as_a_robot_s_prior(storage_client: TestClient) -> None:
    created = experiment(storage_client)
    first, second, _ = links(storage_client, created["id"], count=3)
    complete(storage_client, first["code"])
    failing = {"chosen:batteries": "provide electricity", "added:case": "=hold things together"}
    complete(storage_client, second["code"], failing)
    page = storage_client.get(f"/research/experiments/{created['id']}", headers=AUTH).text
    assert "<h3>Troubleshooting with the participants' models</h3>" in page
    section = page[page.index('<ul id="troubleshooting">') :]
    row = section[: section.index("</ul>")]
    assert "near on the flashlight: the participants&#39; models need" in row
    assert "(1 not scored)" in row  # the failing mapping reaches no light on the flashlight
