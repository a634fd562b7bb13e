"""The shareable export as a file: the Psych-DS dataset (``studies.sharing``) zipped, ready to publish as it is.

Made from the researcher's export with the platform ids as stored, so each one is hashed once
(``studies.sharing.shareable``); nothing that opens a participant's pages or names them is in it.
"""

from __future__ import annotations

import io
import json
import zipfile
from datetime import UTC, datetime

from fastapi import Request, Response
from sqlalchemy.orm import Session

from causalplan.objects.catalog import Catalog
from causalplan.service.experiments import export_data
from causalplan.service.responses import csv_bytes, render_json
from causalplan.service.storage.records import ExperimentRecord
from causalplan.studies import sharing
from causalplan.version import __version__

README = """# {name}

A causalplan study's data in the Psych-DS layout:

- `dataset_description.json`: what the dataset is, its license and authors, and every variable (`variableMeasured`);
- `data_dictionary.csv`: every column of every CSV, with its type and meaning;
- `data/`: the participants and the step-3 trials, one row each;
- `causalplan-export.json`: the same records as JSON, which `causalplan analyze causalplan-export.json --out results/`
  reads to recompute the analysis.

{note}
"""


def shareable_files(
    session: Session,
    catalog: Catalog,
    experiment: ExperimentRecord,
    request: Request,
    authors: list[str],
    license_url: str,
) -> dict[str, bytes]:
    """Return the files of the experiment's shareable dataset, by their path inside it."""
    shared = sharing.shareable(export_data(session, catalog, experiment, request, platform_ids="plain"))
    description = sharing.dataset_description(shared, authors, license_url, __version__)
    files = {
        "dataset_description.json": json.dumps(description, indent=1, ensure_ascii=False).encode("utf-8", "replace"),
        "data_dictionary.csv": csv_bytes(("file", "column", "type", "description"), sharing.dictionary_rows(shared)),
        "causalplan-export.json": render_json(shared),
        "README.md": README.format(name=description["name"], note=sharing.SHAREABLE_NOTE).encode("utf-8", "replace"),
    }
    for data_file in sharing.data_files(shared):
        files[data_file.path] = csv_bytes(data_file.columns, data_file.rows)
    return files


def shareable_zip(
    session: Session,
    catalog: Catalog,
    experiment: ExperimentRecord,
    request: Request,
    authors: list[str],
    license_url: str,
) -> Response:
    """Return the shareable dataset as a ZIP download (its folder named for the experiment and the moment)."""
    files = shareable_files(session, catalog, experiment, request, authors, license_url)
    folder = f"causalplan-study-{experiment.id.hex[:8]}-{datetime.now(UTC):%Y%m%dT%H%M%SZ}"
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        for path, content in files.items():
            archive.writestr(f"{folder}/{path}", content)
    return Response(
        buffer.getvalue(),
        media_type="application/zip",
        headers={"Content-Disposition": f'attachment; filename="{folder}.zip"'},
    )
