"""Database fixtures for the study and web tests: SQLite files and a throwaway PostgreSQL cluster.

``db_url`` is parametrised by ``tests/conftest.py``: SQLite for every test, PostgreSQL as well for
the tests of ``tests/tiers.py``'s ``BOTH_DATABASES`` (storage, concurrency, faults), marked
``postgres``; a test may pin its backends with ``@pytest.mark.parametrize("db_url", [...],
indirect=True)``. The PostgreSQL cluster is made once per test process (per pytest-xdist worker)
with Debian's ``initdb``/``pg_ctl`` (package ``postgresql``), listening only on a unix socket in
a temporary folder; as root it runs as the ``postgres`` user. Missing binaries are a failure,
not a skip: CI installs them.
"""

from __future__ import annotations

import glob
import itertools
import os
import shutil
import subprocess
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

PG_PACKAGE_HINT = "install them with `apt-get update && apt-get install -y postgresql`"


def _pg_bin(name: str) -> str | None:
    found = shutil.which(name)
    if found:
        return found
    candidates = sorted(glob.glob(f"/usr/lib/postgresql/*/bin/{name}"), reverse=True)
    return candidates[0] if candidates else None


class PgCluster:
    def __init__(self, folder: Path, port: int, user: str) -> None:
        self.folder = folder
        self.port = port
        self.user = user
        self._names = itertools.count()

    def url(self, database: str) -> str:
        return f"postgresql+psycopg://{self.user}@/{database}?host={self.folder}&port={self.port}"

    def new_database(self) -> str:
        import psycopg

        name = f"emogen_test_{os.getpid()}_{next(self._names)}"
        with psycopg.connect(
            host=str(self.folder),
            port=self.port,
            user=self.user,
            dbname="postgres",
            autocommit=True,
        ) as conn:
            conn.execute(f'CREATE DATABASE "{name}"')
        return self.url(name)


def _as_postgres(cmd: list[str]) -> list[str]:
    if os.geteuid() != 0:
        return cmd
    runuser = shutil.which("runuser")
    if runuser is None:
        pytest.fail("running the tests as root needs `runuser` (util-linux) to start PostgreSQL")
    return [runuser, "-u", "postgres", "--", *cmd]


@pytest.fixture(scope="session")
def pg_cluster() -> Iterator[PgCluster]:
    initdb, pg_ctl = _pg_bin("initdb"), _pg_bin("pg_ctl")
    if initdb is None or pg_ctl is None:
        pytest.fail(f"PostgreSQL server binaries (initdb, pg_ctl) not found: {PG_PACKAGE_HINT}")
    folder = Path(tempfile.mkdtemp(prefix="emogen-pg-", dir="/tmp"))
    user = "postgres"
    if os.geteuid() == 0:
        try:
            import pwd

            pw = pwd.getpwnam("postgres")
        except KeyError:
            pytest.fail(f"no 'postgres' user to run the test cluster: {PG_PACKAGE_HINT}")
        os.chown(folder, pw.pw_uid, pw.pw_gid)
    else:
        import getpass

        user = getpass.getuser()
    data = folder / "data"
    port = 5432
    subprocess.run(
        _as_postgres(
            [initdb, "-D", str(data), "-A", "trust", "-U", user, "-E", "UTF8", "--no-sync"]
        ),
        check=True,
        capture_output=True,
    )
    options = f"-k {folder} -c listen_addresses='' -p {port} -c fsync=off -c max_connections=200"
    subprocess.run(
        _as_postgres(
            [pg_ctl, "-D", str(data), "-o", options, "-l", str(folder / "log"), "-w", "start"]
        ),
        check=True,
        capture_output=True,
    )
    try:
        yield PgCluster(folder, port, user)
    finally:
        subprocess.run(
            _as_postgres([pg_ctl, "-D", str(data), "-m", "immediate", "-w", "stop"]),
            capture_output=True,
        )
        shutil.rmtree(folder, ignore_errors=True)


@pytest.fixture
def db_url(request: pytest.FixtureRequest, tmp_path: Path) -> str:
    """A fresh, empty database on the backend the test is parametrised with."""
    backend = getattr(request, "param", "sqlite")
    if backend == "sqlite":
        return f"sqlite:///{tmp_path / 'study.sqlite'}"
    cluster: PgCluster = request.getfixturevalue("pg_cluster")
    return cluster.new_database()
