"""`emogen --help` starts fast because it imports no heavy library: checked by what a fresh
process imports (``-X importtime``), not by a timer (the time is in benchmarks/bench_cli.py)."""

from __future__ import annotations

import subprocess
import sys

import pytest

HEAVY = ("numba", "scipy", "sklearn", "matplotlib", "pandas", "numpy", "sqlalchemy", "moderngl")


def _imported(*args: str) -> set[str]:
    proc = subprocess.run(
        [sys.executable, "-X", "importtime", *args],
        capture_output=True,
        text=True,
        check=True,
    )
    return {line.rsplit("|", 1)[-1].strip() for line in proc.stderr.splitlines() if "|" in line}


@pytest.mark.parametrize(
    "argv",
    [["--help"], ["simulate", "--help"], ["analyse", "--help"], ["study", "export", "--help"]],
)
def test_help_imports_no_heavy_library(argv: list[str]) -> None:
    names = _imported("-m", "emogen", *argv)
    assert "emogen.cli.app" in names  # the measurement sees the CLI's own imports
    assert [h for h in HEAVY if h in names] == []


def test_importing_the_cli_app_imports_no_heavy_library() -> None:
    code = f"import sys, emogen.cli.app; print(','.join(m for m in {HEAVY!r} if m in sys.modules))"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == ""


def test_reading_a_trials_solver_and_exporting_load_no_compiled_correction() -> None:
    """The solver number of a recorded state is read (exports, replay checks) without importing
    the compiled eq. 5 code (numba costs over a second to import)."""
    code = (
        "import sys, json\n"
        "from emogen.ga.state import collision_solver_of_state\n"
        "import emogen.study.export_rows\n"
        "s = collision_solver_of_state(json.dumps({'schema': 'emogen.ga.engine/4', 'collision_solver': 2}))\n"
        "print(s, 'numba' in sys.modules, 'emogen.correct.solve' in sys.modules)\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stdout.split() == ["2", "False", "False"]
