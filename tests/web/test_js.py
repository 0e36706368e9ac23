# ruff: noqa: F811  (pytest fixtures imported by name, then requested by name)
"""The participant JS against the server: its types are generated from the app's OpenAPI schema.

``src/emogen/web/static/api-types.d.ts`` is ``openapi-typescript`` run on ``/openapi.json``; a
change to the API without regenerating it fails here. Regenerate with
``EMOGEN_UPDATE_API_TYPES=1 python -m pytest tests/web/test_js.py``. (``tsc``, eslint and the JS
unit tests run from ``make lint`` / ``make test``.)
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from tests.web.study_app import app, client, db_url, pg_cluster  # noqa: F401

REPO = Path(__file__).resolve().parents[2]
TYPES = REPO / "src" / "emogen" / "web" / "static" / "api-types.d.ts"
GENERATOR = REPO / "node_modules" / "openapi-typescript" / "bin" / "cli.js"


def generated_types(client: TestClient, tmp_path: Path) -> str:
    node = shutil.which("node")
    if node is None or not GENERATOR.is_file():
        pytest.fail("the JS types need Node.js and `npm ci` (openapi-typescript)")
    schema = client.get("/openapi.json").json()
    schema["info"] = {"title": "EmoGen study API", "version": "0"}  # not the study's name
    source = tmp_path / "openapi.json"
    source.write_text(json.dumps(schema, indent=1, sort_keys=True))
    out = tmp_path / "api-types.d.ts"
    proc = subprocess.run(
        [node, str(GENERATOR), str(source), "-o", str(out)], capture_output=True, text=True
    )
    if proc.returncode != 0:
        pytest.fail(f"openapi-typescript failed:\n{proc.stdout}\n{proc.stderr}")
    header = "// Generated from the study server's OpenAPI schema: see tests/web/test_js.py.\n"
    return header + out.read_text()


def test_js_types_match_the_openapi_schema(client: TestClient, tmp_path: Path) -> None:
    fresh = generated_types(client, tmp_path)
    if os.environ.get("EMOGEN_UPDATE_API_TYPES") == "1":
        TYPES.write_text(fresh)
    assert TYPES.is_file(), f"{TYPES} is missing; generate it (see this module's docstring)"
    assert TYPES.read_text() == fresh, (
        f"{TYPES.name} is stale: the API changed; regenerate it with "
        "EMOGEN_UPDATE_API_TYPES=1 python -m pytest tests/web/test_js.py"
    )
    for name in ("SessionState", "Select", "InvalidRequest", "Problem"):
        assert f"        {name}: {{" in fresh, name
