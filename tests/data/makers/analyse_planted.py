"""Writes ``tests/data/analyse_planted.json`` and ``analyse_planted.md``: ``emogen analyse``'s
``analysis.json`` and ``README.md`` of one planted study (``benchmarks/planted_study.py``), the
export's path written as ``EXPORT``. Run from the repository root at the commit named in
tests/data/README.md: ``PYTHONPATH=. .venv/bin/python tests/data/makers/analyse_planted.py``.

The design and options are those of ``tests/analysis/test_results.py`` (copy it in when the
commit lacks it)."""

from __future__ import annotations

import tempfile
from pathlib import Path

from benchmarks.planted_study import write_planted_study
from tests.analysis.test_results import DESIGN, OPTIONS, SEED

from emogen.analysis.analyse import analyse


def main() -> None:
    data = Path(__file__).resolve().parents[1]
    with tempfile.TemporaryDirectory() as tmp:
        export = write_planted_study(DESIGN, Path(tmp) / "export", seed=SEED)
        result = analyse(export, Path(tmp) / "report", options=OPTIONS)
        for path, name in ((result.out / "analysis.json", "json"), (result.markdown, "md")):
            text = path.read_text().replace(str(export), "EXPORT")
            (data / f"analyse_planted.{name}").write_text(text)


if __name__ == "__main__":
    main()
