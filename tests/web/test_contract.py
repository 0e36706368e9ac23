# ruff: noqa: F811  (pytest fixtures imported by name, then requested by name)
"""The browser contract: real responses, errors included, against the app's own OpenAPI schema.

Every status code an operation answers must be documented for that operation, and the body must
validate (JSON Schema, ``jsonschema_rs``) against the schema documented for that code.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Any

import jsonschema_rs
import pytest
from fastapi.testclient import TestClient
from httpx import Response

from tests.study.drive import choose, new_key, step_args
from tests.web.study_app import app, client, db_url, pg_cluster  # noqa: F401


@pytest.fixture
def openapi(client: TestClient) -> dict[str, Any]:
    return client.get("/openapi.json").json()  # type: ignore[no-any-return]


def conforms(openapi: dict[str, Any], template: str, method: str, response: Response) -> None:
    """The response's status is documented for the operation and its body fits the schema."""
    operation = openapi["paths"][template][method]
    code = str(response.status_code)
    assert code in operation["responses"], (template, method, code, sorted(operation["responses"]))
    schema = operation["responses"][code]["content"]["application/json"]["schema"]
    document = {**schema, "components": openapi["components"]}
    errors = [e.message for e in jsonschema_rs.validator_for(document).iter_errors(response.json())]
    assert not errors, (template, method, code, errors, response.text[:300])
    assert_no_undocumented_keys(document, schema, response.json())


def assert_no_undocumented_keys(
    document: dict[str, Any], schema: dict[str, Any], value: Any
) -> None:
    """Every key the server sends is a property of the schema (the JS types would miss it)."""
    if "$ref" in schema:
        name = schema["$ref"].rsplit("/", 1)[1]
        schema = document["components"]["schemas"][name]
    if "anyOf" in schema:
        for option in schema["anyOf"]:
            check = option if "$ref" not in option else None
            kind = {"object": dict, "array": list, "null": type(None)}.get(
                (check or {}).get("type", "object")
            )
            if kind is not None and isinstance(value, kind):
                assert_no_undocumented_keys(document, option, value)
                return
        return
    if isinstance(value, dict):
        extra = set(value) - set(schema.get("properties", {}))
        assert not extra, (schema.get("title"), extra)
        for key, item in value.items():
            assert_no_undocumented_keys(document, schema["properties"][key], item)
    elif isinstance(value, list) and "items" in schema:
        for item in value[:3]:
            assert_no_undocumented_keys(document, schema["items"], item)


@pytest.fixture
def session(client: TestClient) -> Iterator[tuple[str, dict[str, Any]]]:
    r = client.post("/api/sessions", json={"participant_id": "contract-1"})
    assert r.status_code == 201
    token = r.json()["token"]
    state = client.post(f"/api/s/{token}/begin", json={"key": new_key()}).json()
    yield token, state


def test_success_bodies_match_the_schema(
    client: TestClient, openapi: dict[str, Any], session: tuple[str, dict[str, Any]]
) -> None:
    token, state = session
    created = client.post("/api/sessions", json={"participant_id": "contract-2"})
    conforms(openapi, "/api/sessions", "post", created)
    r = client.get(f"/api/s/{token}/state")
    conforms(openapi, "/api/s/{token}/state", "get", r)
    assert r.json()["population"]["faces"], "a trial's state shows its population"
    elite, others = choose(state)
    body = {"key": new_key(), **step_args(state), "elite": elite, "others": others}
    r = client.post(f"/api/s/{token}/select", json=body)
    conforms(openapi, "/api/s/{token}/select", "post", r)
    replayed = client.post(f"/api/s/{token}/select", json=body)
    assert replayed.json()["replayed"] is True
    conforms(openapi, "/api/s/{token}/select", "post", replayed)


def test_every_error_code_matches_the_schema(
    client: TestClient, openapi: dict[str, Any], session: tuple[str, dict[str, Any]]
) -> None:
    token, state = session
    elite, others = choose(state)
    good = {"key": new_key(), **step_args(state), "elite": elite, "others": others}
    select = "/api/s/{token}/select"
    cases: list[tuple[str, str, Response, int]] = [
        ("/api/researcher/status", "get", client.get("/api/researcher/status"), 403),
        ("/api/s/{token}/state", "get", client.get(f"/api/s/{'x' * 20}/state"), 404),
        (
            "/api/sessions",
            "post",
            client.post("/api/sessions", json={"participant_id": "contract-1"}),
            409,
        ),
        (
            select,
            "post",
            client.post(f"/api/s/{token}/select", json={**good, "generation": 3}),
            409,
        ),
        (select, "post", client.post(f"/api/s/{token}/select", json={**good, "elite": "3"}), 422),
        (select, "post", client.post(f"/api/s/{token}/select", json={**good, "elite": 999}), 422),
        (select, "post", client.post(f"/api/s/{token}/select", content=b"{" * 70_000), 413),
    ]
    for template, method, response, status in cases:
        assert response.status_code == status, (template, response.text)
        assert isinstance(response.json()["detail"], str) and response.json()["detail"]
        conforms(openapi, template, method, response)


def test_invalid_requests_name_the_bad_field(
    client: TestClient, session: tuple[str, dict[str, Any]]
) -> None:
    token, _state = session
    r = client.post(f"/api/s/{token}/rating", json={"key": new_key(), "trial": 0, "value": 0})
    body = r.json()
    assert r.status_code == 422 and "value" in body["detail"]
    assert [e["loc"] for e in body["errors"]] == [["body", "value"]]


def test_request_bodies_over_the_limit_are_refused_unread(
    client: TestClient, app: Any, session: tuple[str, dict[str, Any]]
) -> None:
    token, state = session
    elite, others = choose(state)
    body = {"key": new_key(), **step_args(state), "elite": elite, "others": others}
    big = json.dumps(body) + " " * 70_000  # valid JSON, only too long

    def chunks() -> Iterator[bytes]:  # no Content-Length: the server counts as it reads
        for i in range(0, len(big), 8192):
            yield big[i : i + 8192].encode()

    for response in (
        client.post(f"/api/s/{token}/select", content=big.encode()),
        client.post(f"/api/s/{token}/select", content=chunks()),
    ):
        assert response.status_code == 413, response.text
        assert "65536 bytes" in response.json()["detail"]
    assert client.get(f"/api/s/{token}/state").json()["progress"]["generation"] == 0
    small = client.post(f"/api/s/{token}/select", json=body)
    assert small.status_code == 200, small.text
    assert small.json()["progress"]["generation"] == 1


def test_the_schema_documents_the_error_codes(openapi: dict[str, Any]) -> None:
    steps = [p for p in openapi["paths"] if p.startswith("/api/s/") and "faces" not in p]
    for path in steps:
        for method, operation in openapi["paths"][path].items():
            codes = set(operation["responses"])
            assert {"404", "409", "422", "503"} <= codes, (path, codes)
            if method == "post":
                assert "413" in codes, path
    invalid = openapi["components"]["schemas"]["InvalidRequest"]
    assert invalid["properties"]["detail"]["type"] == "string"
    assert "HTTPValidationError" not in openapi["components"]["schemas"]
