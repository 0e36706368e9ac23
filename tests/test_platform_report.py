"""`make test` (and so `.ci/run`) first says which CPU and BLAS kernel it runs on: replayed
weights may differ from recorded ones in the last bits between them (docs/study.md)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_info

ROOT = Path(__file__).parents[1]


def test_the_report_names_this_cpu_and_the_blas_kernel() -> None:
    out = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "platform_report.py")],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    cpuinfo = Path("/proc/cpuinfo").read_text()
    model = re.search(r"^model name\s*:\s*(.+)$", cpuinfo, re.MULTILINE)
    assert model is not None  # x86-64 Linux
    assert out.splitlines()[0].startswith(f"CPU: {model.group(1).strip()} (")
    np.dot(np.ones(2), np.ones(2))  # BLAS loaded
    # this process may have loaded other BLAS libraries too (scipy's): numpy's is one of them
    loaded = [i for i in threadpool_info() if i["user_api"] == "blas"]
    built = np.show_config(mode="dicts")["Build Dependencies"]["blas"]
    line = out.splitlines()[1]
    assert line.startswith("BLAS: ") and built["version"] in line
    assert any(
        f"{i['internal_api']} {built['version']} kernel {i['architecture']}," in line
        for i in loaded
        if i["internal_api"] in built["name"]
    )


def test_make_test_prints_it_before_any_test() -> None:
    recipe = re.search(r"^test:.*\n((?:\t.*\n)+)", (ROOT / "Makefile").read_text(), re.MULTILINE)
    assert recipe is not None
    lines = recipe.group(1).splitlines()
    assert "scripts/platform_report.py" in lines[0]
    assert any("pytest" in line for line in lines[1:])
    assert "make test" in (ROOT / ".ci" / "run").read_text()
