"""`emogen.model.io.fetch` against a real HTTP server on the loopback address."""

from __future__ import annotations

import hashlib
import http.server
import socket
import threading
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import pytest

from emogen.errors import ModelFileError
from emogen.model.io import fetch
from emogen.model.io.fetch import Manifest, ManifestFile, fetch_model, load_manifest

COMMIT = "0123456789abcdef0123456789abcdef01234567"
SHARED_ICT = Path(__file__).resolve().parents[2].parent / "shared" / "ict-facekit"

FAKE_FILES = {
    "FaceXModel/generic_neutral_mesh.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "FaceXModel/jawOpen.obj": b"v 0 -0.5 0\nv 1 -0.5 0\nv 0 0.5 0\nf 1 2 3\n",
    "FaceXModel/vertex_indices.json": b'{"Face": [0, 3]}\n',
    "LICENSE": b"Fake licence for tests.\n",
}


def _manifest(files: dict[str, bytes]) -> Manifest:
    return Manifest(
        repository="test/ICT-FaceKit",
        commit=COMMIT,
        files=tuple(
            ManifestFile(path=path, sha256=hashlib.sha256(data).hexdigest(), size=len(data))
            for path, data in files.items()
        ),
    )


class _CountingHandler(http.server.SimpleHTTPRequestHandler):
    requests: Counter[str]
    fail_first: set[str]  # paths answered with 503 on their first request

    def do_GET(self) -> None:
        self.requests[self.path] += 1
        if self.path in self.fail_first and self.requests[self.path] == 1:
            self.send_error(503, "try again")
            return
        super().do_GET()

    def log_message(self, format: str, *args: object) -> None:  # keep test output quiet
        pass


@dataclass
class Server:
    root: Path  # mirrors the repository layout
    url: str  # base URL, ends with "/"
    requests: Counter[str]
    fail_first: set[str]


@pytest.fixture
def server(tmp_path: Path) -> Iterator[Server]:
    root = tmp_path / "mirror"
    for path, data in FAKE_FILES.items():
        (root / path).parent.mkdir(parents=True, exist_ok=True)
        (root / path).write_bytes(data)
    requests: Counter[str] = Counter()
    fail_first: set[str] = set()
    attributes = {"requests": requests, "fail_first": fail_first}
    handler = type("Handler", (_CountingHandler,), attributes)
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), partial(handler, directory=str(root)))
    thread = threading.Thread(
        target=httpd.serve_forever, kwargs={"poll_interval": 0.02}, daemon=True
    )
    thread.start()
    try:
        yield Server(root, f"http://127.0.0.1:{httpd.server_address[1]}/", requests, fail_first)
    finally:
        httpd.shutdown()
        httpd.server_close()
        thread.join()


@pytest.fixture(autouse=True)
def _no_env_mirror(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(fetch.ENV_BASE_URL, raising=False)


def _final_files(dest: Path) -> set[str]:
    return {p.relative_to(dest).as_posix() for p in dest.rglob("*") if p.is_file()}


def test_fetch_downloads_every_file_with_layout_and_checksums(
    server: Server, tmp_path: Path
) -> None:
    dest = tmp_path / "model"
    model_dir = fetch_model(dest, base_url=server.url, manifest=_manifest(FAKE_FILES))
    assert model_dir == dest / "FaceXModel"
    assert _final_files(dest) == set(FAKE_FILES)
    for path, data in FAKE_FILES.items():
        assert (dest / path).read_bytes() == data
    assert set(server.requests) == {"/" + p for p in FAKE_FILES}


def test_fetch_shows_progress_without_error(
    server: Server, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fetch_model(tmp_path / "m", base_url=server.url, manifest=_manifest(FAKE_FILES), progress=True)
    assert capsys.readouterr().out == ""  # the bar goes to stderr, never stdout


def test_fetch_resumes_skipping_verified_files(server: Server, tmp_path: Path) -> None:
    dest = tmp_path / "model"
    manifest = _manifest(FAKE_FILES)
    fetch_model(dest, base_url=server.url, manifest=manifest, progress=False)
    server.requests.clear()

    (dest / "FaceXModel/jawOpen.obj").unlink()
    (dest / "LICENSE").write_bytes(b"damaged")
    fetch_model(dest, base_url=server.url, manifest=manifest, progress=False)

    assert server.requests == Counter({"/FaceXModel/jawOpen.obj": 1, "/LICENSE": 1})
    for path, data in FAKE_FILES.items():
        assert (dest / path).read_bytes() == data

    server.requests.clear()
    fetch_model(dest, base_url=server.url, manifest=manifest, progress=False)
    assert not server.requests


def test_corrupted_file_names_file_and_both_hashes_and_leaves_no_file(
    server: Server, tmp_path: Path
) -> None:
    good = FAKE_FILES["FaceXModel/jawOpen.obj"]
    bad = good.replace(b"0.5", b"0.6")  # same size, different content
    (server.root / "FaceXModel/jawOpen.obj").write_bytes(bad)
    dest = tmp_path / "model"
    with pytest.raises(ModelFileError, match=r"jawOpen\.obj") as info:
        fetch_model(dest, base_url=server.url, manifest=_manifest(FAKE_FILES), progress=False)
    message = str(info.value)
    assert "checksum mismatch" in message
    assert hashlib.sha256(good).hexdigest() in message
    assert hashlib.sha256(bad).hexdigest() in message
    assert f"{server.url}FaceXModel/jawOpen.obj" in message
    assert not (dest / "FaceXModel/jawOpen.obj").exists()
    assert not any(p.name.endswith(".part") for p in dest.rglob("*"))
    assert server.requests["/FaceXModel/jawOpen.obj"] == 1  # corruption is not retried


def test_wrong_size_is_reported_and_discarded(server: Server, tmp_path: Path) -> None:
    (server.root / "LICENSE").write_bytes(b"short\n")
    dest = tmp_path / "model"
    with pytest.raises(ModelFileError, match=r"LICENSE: .* sent 6 bytes, expected 24"):
        fetch_model(dest, base_url=server.url, manifest=_manifest(FAKE_FILES), progress=False)
    assert not (dest / "LICENSE").exists()


def test_transient_http_error_is_retried(server: Server, tmp_path: Path) -> None:
    server.fail_first.add("/FaceXModel/jawOpen.obj")
    dest = tmp_path / "model"
    fetch_model(
        dest, base_url=server.url, manifest=_manifest(FAKE_FILES), progress=False, retry_delay=0
    )
    assert server.requests["/FaceXModel/jawOpen.obj"] == 2
    assert _final_files(dest) == set(FAKE_FILES)


def test_http_404_names_the_url(server: Server, tmp_path: Path) -> None:
    (server.root / "LICENSE").unlink()
    dest = tmp_path / "model"
    url = f"{server.url}LICENSE"
    with pytest.raises(ModelFileError, match="404") as info:
        fetch_model(dest, base_url=server.url, manifest=_manifest(FAKE_FILES), progress=False)
    assert url in str(info.value)
    assert not (dest / "LICENSE").exists()
    assert server.requests["/LICENSE"] == 1  # 404 is not retried


def _closed_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def test_unreachable_server_says_could_not_reach(tmp_path: Path) -> None:
    base = f"http://127.0.0.1:{_closed_port()}/"
    dest = tmp_path / "model"
    with pytest.raises(ModelFileError, match="could not reach") as info:
        fetch_model(
            dest,
            base_url=base,
            manifest=_manifest(FAKE_FILES),
            progress=False,
            timeout=5,
            retries=2,
            retry_delay=0,
        )
    message = str(info.value)
    assert base in message
    assert "EMOGEN_MODEL_URL" in message
    assert "3 attempts" in message
    assert not _final_files(dest)


def test_env_var_is_used_and_argument_wins(
    server: Server, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    manifest = _manifest(FAKE_FILES)
    monkeypatch.setenv(fetch.ENV_BASE_URL, server.url)
    fetch_model(tmp_path / "a", manifest=manifest, progress=False)
    assert _final_files(tmp_path / "a") == set(FAKE_FILES)

    monkeypatch.setenv(fetch.ENV_BASE_URL, f"http://127.0.0.1:{_closed_port()}/")
    fetch_model(tmp_path / "b", base_url=server.url, manifest=manifest, progress=False)
    assert _final_files(tmp_path / "b") == set(FAKE_FILES)


def test_commit_placeholder_and_local_folder_mirror(tmp_path: Path, server: Server) -> None:
    manifest = _manifest(FAKE_FILES)
    assert fetch.resolve_base_url("http://m/{commit}", COMMIT) == f"http://m/{COMMIT}/"
    assert fetch.resolve_base_url(None, COMMIT) == fetch.DEFAULT_BASE_URL.format(commit=COMMIT)
    fetch_model(tmp_path / "m", base_url=str(server.root), manifest=manifest, progress=False)
    assert _final_files(tmp_path / "m") == set(FAKE_FILES)


def test_default_dest_is_the_cache_dir(
    server: Server, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv(fetch.ENV_CACHE_DIR, str(tmp_path / "cache"))
    expected = tmp_path / "cache" / "ict-facekit" / COMMIT[:8]
    assert fetch.default_model_dir(COMMIT) == expected
    model_dir = fetch_model(base_url=server.url, manifest=_manifest(FAKE_FILES), progress=False)
    assert model_dir == expected / "FaceXModel"
    assert _final_files(expected) == set(FAKE_FILES)


@pytest.mark.parametrize("path", ["../evil", "/etc/passwd", "FaceXModel/../../x", ""])
def test_manifest_rejects_paths_outside_dest(path: str) -> None:
    with pytest.raises(ModelFileError, match="relative POSIX path"):
        ManifestFile(path=path, sha256="0" * 64, size=1)


def test_packaged_manifest_matches_shared_ict_facekit() -> None:
    manifest = load_manifest()
    assert manifest.repository == "ICT-VGL/ICT-FaceKit"
    assert manifest.commit == "da5f95a607f5e6b37755b38d3385d7f2853732e5"
    paths = {entry.path for entry in manifest.files}
    assert {"LICENSE", "FaceXModel/generic_neutral_mesh.obj", "FaceXModel/jawOpen.obj"} <= paths
    on_disk = {
        p.relative_to(SHARED_ICT).as_posix() for p in (SHARED_ICT / "FaceXModel").iterdir()
    } | {"LICENSE"}
    assert paths == on_disk
    by_path = {entry.path: entry for entry in manifest.files}
    for path in ("FaceXModel/jawOpen.obj", "FaceXModel/vertex_indices.json", "LICENSE"):
        data = (SHARED_ICT / path).read_bytes()
        assert by_path[path].size == len(data)
        assert by_path[path].sha256 == hashlib.sha256(data).hexdigest()
