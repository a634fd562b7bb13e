"""The research page: troubleshooting with the participants' models, per condition and test object."""

from __future__ import annotations

import json

import pytest
from fastapi.testclient import TestClient

from causalplan.objects.reference import reference_model
from causalplan.service.pages.research_troubleshooting import json_for_script
from tests.conftest import builtin_catalog
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


def test_the_repair_page_offers_every_fault_with_the_objects_reference_models(client: TestClient) -> None:
    assert client.get("/research/troubleshooting", follow_redirects=False).status_code == 303  # to sign in
    page = client.get("/research/troubleshooting", headers=AUTH)
    assert page.status_code == 200, page.text
    assert 'value="desk_lamp/light_bulb"' in page.text and 'value="toy_car/' in page.text
    assert '<a href="/research/troubleshooting">Robot repairs</a>' in page.text  # reached from every research page
    block = page.text.split('<script type="application/json" id="reference-models">')[1].split("</script>")[0]
    models = json.loads(block)
    assert models["desk_lamp"] == reference_model(builtin_catalog().get("desk_lamp"))


def test_text_in_the_page_s_json_cannot_close_its_script_block() -> None:
    hostile = {"name": "</script><script>alert(1)</script> & <!--"}
    text = str(json_for_script(hostile))
    assert "<" not in text and ">" not in text and "&" not in text
    assert json.loads(text) == hostile


@pytest.mark.slow
def test_the_3d_player_plays_the_rebuild_of_a_repaired_lamp(client: TestClient) -> None:
    from causalplan.sim.troubleshooting import repair_in_physics
    from causalplan.troubleshoot.task import troubleshooting_task

    lamp = builtin_catalog().get("desk_lamp")
    rebuilt = repair_in_physics(lamp, troubleshooting_task(lamp).episode("oracle", "light_bulb"))
    played = client.post("/research/playback", json={"object": "desk_lamp", "fits": list(rebuilt.fits)}, headers=AUTH)
    assert played.status_code == 200, played.text
    document = played.json()
    assert document["outcome"] == {"carried_out": True, "reason": None}
