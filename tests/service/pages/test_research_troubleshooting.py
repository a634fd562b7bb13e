"""The research page: troubleshooting with the participants' models, per condition and test object."""

from __future__ import annotations

import pytest
from fastapi.testclient import TestClient

from tests.service.fixtures import AUTH
from tests.service.pages.flows import complete, experiment, links


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


@pytest.mark.slow
def test_the_3d_player_plays_the_rebuild_of_a_repaired_lamp(client: TestClient) -> None:
    from causalplan.sim.troubleshooting import repair_in_physics
    from causalplan.troubleshoot.task import troubleshooting_task
    from tests.conftest import builtin_catalog

    lamp = builtin_catalog().get("desk_lamp")
    rebuilt = repair_in_physics(lamp, troubleshooting_task(lamp).episode("oracle", "light_bulb"))
    played = client.post("/research/playback", json={"object": "desk_lamp", "fits": list(rebuilt.fits)}, headers=AUTH)
    assert played.status_code == 200, played.text
    document = played.json()
    assert document["outcome"] == {"carried_out": True, "reason": None}
