"""The data to share, through the app: participants who came from Prolific, their data as a Psych-DS ZIP."""

from __future__ import annotations

import csv
import io
import json
import re
import zipfile
from collections.abc import Iterator
from typing import Any

import pytest
from fastapi.testclient import TestClient

from tests.service.fixtures import AUTH, running_client, settings_for, sqlite_url
from tests.service.pages.flows import complete, experiment, post

PSYCH_DS_DATA_FILE = re.compile(r"data/([a-z]+-[a-zA-Z0-9]+_)+data\.csv")


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    with running_client(settings_for(sqlite_url(tmp_path_factory.mktemp("db")), arrivals_per_minute=0)) as running:
        yield running


def join(client: TestClient, experiment_id: str, pid: str) -> str:
    """Arrive from Prolific as ``pid`` and agree; return the participant's code."""
    params = {"PROLIFIC_PID": pid, "STUDY_ID": "study-share", "SESSION_ID": f"session-{pid}"}
    arrival = client.get(f"/s/{experiment_id}", params=params)
    found = re.search(r'name="arrival" value="([A-Za-z0-9]+)"', arrival.text)
    assert found, arrival.text
    agreed = post(client, f"/s/{experiment_id}/consent", {"arrival": found.group(1), "decision": "agree"})
    return str(agreed.headers["location"]).removeprefix("/p/")


def unzip(response: Any) -> dict[str, bytes]:
    assert response.status_code == 200, response.text
    assert response.headers["content-type"] == "application/zip"
    with zipfile.ZipFile(io.BytesIO(response.content)) as archive:
        names = archive.namelist()
        (folder,) = {name.split("/", 1)[0] for name in names}
        return {name.removeprefix(folder + "/"): archive.read(name) for name in names}


def test_the_shareable_dataset_holds_no_code_link_address_or_raw_platform_id(client: TestClient) -> None:
    created = experiment(client, description="Desk lamp to flashlight, shared.")
    study = created["id"]
    codes = [join(client, study, f"pid-share-{n}") for n in range(2)]
    complete(client, codes[0])
    private = client.get(f"/v1/experiments/{study}/export", headers=AUTH).json()
    kept = {participant["code"] for participant in private["participants"]}
    assert kept == set(codes)  # the researcher's own export keeps them, with the address and raw ids
    assert {participant["client_address"] for participant in private["participants"]} == {"testclient"}
    assert {participant["platform_participant_id"] for participant in private["participants"]} == {
        "pid-share-0",
        "pid-share-1",
    }
    links = [participant["link"] for participant in private["participants"]]

    files = unzip(
        client.get(
            f"/v1/experiments/{study}/export/shareable",
            params={"author": ["A. Researcher", "B. Researcher"], "license": "CC-BY-4.0"},
            headers=AUTH,
        )
    )
    everything = b"\n".join(files.values()).decode()
    for secret in [*codes, *links, "testclient", "pid-share-0", "session-pid-share-0", "study-share"]:
        assert secret not in everything, secret

    shared = json.loads(files["causalplan-export.json"])
    assert "link codes, links and client addresses are removed" in shared["shareable"]["note"]
    assert shared["shareable"]["removed"]["participants"] == ["code", "link", "client_address"]
    assert all(len(p["platform_participant_id"]) == 64 for p in shared["participants"])
    assert len(shared["trials"]) == 1 and "participant_code" not in shared["trials"][0]

    description = json.loads(files["dataset_description.json"])
    assert description["@context"] == "https://schema.org/" and description["@type"] == "Dataset"
    assert description["name"] == created["name"] and description["license"] == "CC-BY-4.0"
    assert [author["name"] for author in description["author"]] == ["A. Researcher", "B. Researcher"]
    assert description["schemaVersion"].startswith("Psych-DS")
    data_files = [name for name in files if name.startswith("data/")]
    assert len(data_files) == 2 and all(PSYCH_DS_DATA_FILE.fullmatch(name) for name in data_files)
    measured = {variable["name"] for variable in description["variableMeasured"]}
    dictionary = list(csv.DictReader(io.StringIO(files["data_dictionary.csv"].decode())))
    for name in data_files:
        columns = next(csv.reader(io.StringIO(files[name].decode())))
        assert set(columns) <= measured  # every column described in the metadata...
        assert columns == [row["column"] for row in dictionary if row["file"] == name]  # ...and the dictionary
    rows = list(csv.DictReader(io.StringIO(files[data_files[1]].decode())))
    assert [row["verdict"] for row in rows] == ["transfers"]


def test_the_research_page_offers_the_dataset_to_share(client: TestClient) -> None:
    created = experiment(client)
    client.post("/research/login", data={"token": AUTH["Authorization"].removeprefix("Bearer ")})
    page = client.get(f"/research/experiments/{created['id']}")
    assert f"/research/experiments/{created['id']}/export/shareable" in page.text
    files = unzip(client.get(f"/research/experiments/{created['id']}/export/shareable"))
    assert json.loads(files["dataset_description.json"])["author"] == []
