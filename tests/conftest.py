"""Shared fixtures: the real ICT-FaceKit model from ../shared, and a tiny synthetic model folder."""

from __future__ import annotations

import fcntl
import json
import os
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from tests import tiers
from tests.r_readers import R_MISSING, r_available

REPO = Path(__file__).resolve().parents[1]
#: The model the tests use: $EMOGEN_MODEL when set (read before the tests unset it), else
#: ../shared beside the repository.
ICT_DIR = Path(
    os.environ.get("EMOGEN_MODEL") or REPO.parent / "shared" / "ict-facekit" / "FaceXModel"
)
MODEL_MISSING = (
    f"needs the ICT-FaceKit model, not found at {ICT_DIR}: put ../shared beside the repository, "
    "set EMOGEN_MODEL to its FaceXModel folder, or run `emogen model fetch` and point "
    "EMOGEN_MODEL there (CI=true turns this skip into a failure)"
)


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "model: needs the ICT-FaceKit model (skipped without it)")


def _listed(entries: dict[str, str], nodeid: str) -> bool:
    """Whether ``tests/tiers.py``'s ``entries`` name this test: by module, by function (every
    parameter) or by its whole id."""
    return bool({nodeid.split("::")[0], nodeid.split("[")[0], nodeid} & entries.keys())


def _check_entries(entries: dict[str, str], name: str, items: list[pytest.Item]) -> None:
    """Every entry of a module that was collected names a test function of that module (a
    renamed test must not leave its tier or its databases silently)."""
    modules = {item.nodeid.split("::")[0]: getattr(item, "module", None) for item in items}
    for entry in entries:
        path, _, test = entry.partition("::")
        module = modules.get(path)
        if module is not None and test and not hasattr(module, test.split("[")[0]):
            raise pytest.UsageError(f"tests/tiers.py {name} names no test of {path}: {entry}")


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    """``db_url`` (tests/study_fixtures.py): SQLite, and PostgreSQL as well for the tests of
    ``tiers.BOTH_DATABASES``, unless a test pins its backends itself."""
    if "db_url" not in metafunc.fixturenames:
        return
    for mark in metafunc.definition.iter_markers("parametrize"):
        names = mark.args[0] if mark.args else mark.kwargs.get("argnames", ())
        if isinstance(names, str):
            names = [n.strip() for n in names.split(",")]
        if "db_url" in names:
            return
    both = _listed(tiers.BOTH_DATABASES, metafunc.definition.nodeid)
    metafunc.parametrize("db_url", ["sqlite", "postgresql"] if both else ["sqlite"], indirect=True)


@pytest.hookimpl(tryfirst=True)  # marks first: `-m` deselects by them after
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Mark every test that needs the model (through the ``ict_dir`` fixture); without the
    model they are skipped with a reason that says how to get it — except in CI, where a
    missing model is an error, so that nothing passes by being skipped. Mark the tests of
    ``tiers.SLOW`` slow, and every test on PostgreSQL ``postgres``."""
    _check_entries(tiers.SLOW, "SLOW", items)
    _check_entries(tiers.BOTH_DATABASES, "BOTH_DATABASES", items)
    have = (ICT_DIR / "generic_neutral_mesh.obj").is_file()
    for item in items:
        if _listed(tiers.SLOW, item.nodeid):
            item.add_marker(pytest.mark.slow)
        callspec = getattr(item, "callspec", None)
        on_postgres = callspec is not None and callspec.params.get("db_url") == "postgresql"
        if on_postgres or "pg_cluster" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.postgres)
        if "ict_dir" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.model)
            if not have and not os.environ.get("CI"):
                item.add_marker(pytest.mark.skip(reason=MODEL_MISSING))
        # R (readr) the same way: skipped on a contributor's machine without it, failed in CI
        wants_r = "rscript" in getattr(item, "fixturenames", ())
        if wants_r and not os.environ.get("CI") and not r_available():
            item.add_marker(pytest.mark.skip(reason=R_MISSING))


@pytest.fixture(autouse=True, scope="session")
def _isolated_cache(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Keep the compiled-model cache of the test run out of the user's cache folder."""
    os.environ["EMOGEN_CACHE_DIR"] = str(tmp_path_factory.mktemp("emogen-cache"))
    os.environ.pop("EMOGEN_MODEL", None)
    os.environ.pop("EMOGEN_MODEL_URL", None)


@pytest.fixture(autouse=True)
def _one_download_test_at_a_time(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[None]:
    """The tests of ``tiers.DOWNLOADS`` one at a time across pytest-xdist's workers (a lock
    file in the run's temporary folder, which the workers share)."""
    if request.node.nodeid.split("::")[0] not in tiers.DOWNLOADS:
        yield
        return
    base = tmp_path_factory.getbasetemp()
    run = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base
    with open(run / "downloads.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        yield


@pytest.fixture(scope="session")
def rscript() -> None:
    """R with readr (tests/r_readers.py reads outputs with it); a failure when missing."""
    if not r_available():
        pytest.fail(R_MISSING)


@pytest.fixture(scope="session")
def ict_dir() -> Path:
    if not ICT_DIR.is_dir():
        pytest.fail(MODEL_MISSING)
    return ICT_DIR


@pytest.fixture(scope="session")
def ict_model(ict_dir: Path):  # type: ignore[no-untyped-def]
    import emogen

    return emogen.load_model(ict_dir)


def read_obj_vertices_plainly(path: Path) -> np.ndarray:
    """An independent reference: every 'v' line of an OBJ, parsed one by one in plain Python."""
    rows = []
    with open(path) as fh:
        for line in fh:
            if line.startswith("v "):
                rows.append([float(x) for x in line.split()[1:4]])
    return np.array(rows)


TINY_SHAPES = ["jawOpen", "smile_L", "smile_R"]
TINY_EXTRA = ["cheekRaiser_L", "cheekRaiser_R", "PupilDilate_L", "PupilDilate_R"]
TINY_RIG = """
name = "tiny"
[excluded]
PupilDilate_L = "test"
PupilDilate_R = "test"
[emotions.happy]
action_units = "6+12"
core = ["smile"]
optional = ["cheekRaiser"]
source = "test"
"""


def _obj(verts: np.ndarray) -> str:
    lines = ["# tiny test mesh", "mtllib x.mtl", "usemtl M_Face"]
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in verts]
    lines += ["vt 0 0", "vt 1 0", "vt 1 1", "vt 0 1", "vt 0.5 0.5"]
    lines += ["f 1/1 2/2 3/3 4/4", "f 1/1 3/3 5/5"]
    return "\n".join(lines) + "\n"


@pytest.fixture
def tiny_dir(tmp_path: Path) -> Path:
    """A five-vertex model folder laid out like ICT-FaceKit's FaceXModel (random, seeded)."""
    rng = np.random.default_rng(7)
    folder = tmp_path / "FaceXModel"
    folder.mkdir()
    neutral = rng.normal(size=(5, 3))
    (folder / "generic_neutral_mesh.obj").write_text(_obj(neutral))
    for name in TINY_SHAPES + TINY_EXTRA:
        (folder / f"{name}.obj").write_text(_obj(neutral + rng.normal(scale=0.1, size=(5, 3))))
    for i in range(2):
        (folder / f"identity{i:03d}.obj").write_text(
            _obj(neutral + rng.normal(scale=0.05, size=(5, 3)))
        )
    (folder / "vertex_indices.json").write_text(json.dumps({"expressions": TINY_SHAPES}))
    (tmp_path / "tiny_rig.toml").write_text(TINY_RIG)
    return folder


@pytest.fixture
def tiny_model(tiny_dir: Path):  # type: ignore[no-untyped-def]
    import emogen

    return emogen.load_model(tiny_dir, rig=tiny_dir.parent / "tiny_rig.toml")
