"""Outputs as R reads them — real R (Debian's ``r-base-core`` and ``r-cran-readr``, run through
``Rscript``) — and the data dictionary, for the output tests.

:func:`read_in_r` reads CSV files with ``readr::read_csv``, with readr's defaults or with the
``col_types`` EmoGen writes beside them (``col_types.csv``), and hands back what R got: each
column's class and its values. Tests that need R request the ``rscript`` fixture
(tests/conftest.py): without R they are skipped with :data:`R_MISSING`, except in CI (``CI`` set),
where a missing R is a failure.
"""

from __future__ import annotations

import functools
import re
import shutil
import subprocess
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

DOCS = Path(__file__).resolve().parents[1] / "docs" / "data.md"
ISO_UTC = re.compile(r"^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(\.\d+)?(Z|[+-]\d\d:\d\d)$")
R_MISSING = (
    "needs R with readr (Rscript and the readr package): on Debian `apt-get install r-base-core "
    "r-cran-readr` (scripts/install-system-deps.sh does it; CI=true turns this skip into a failure)"
)
#: R's class of a column for each readr ``col_types`` letter EmoGen writes.
R_CLASS = {"d": "numeric", "c": "character", "T": "POSIXct", "l": "logical"}
#: Reads each (path, col_types) pair of the arguments after the output folder; writes, per
#: table, its columns' classes (time zone after a colon) and its values as text (full precision).
READ_TABLES = r"""
args <- commandArgs(TRUE)
out <- args[1]
pairs <- matrix(args[-1], nrow = 2)
for (i in seq_len(ncol(pairs))) {
  types <- if (nzchar(pairs[2, i])) pairs[2, i] else NULL
  d <- readr::read_csv(pairs[1, i], col_types = types, show_col_types = FALSE, progress = FALSE)
  cls <- vapply(d, function(x) {
    k <- class(x)[1]
    if (k == "POSIXct") paste0(k, ":", attr(x, "tzone")) else k
  }, "")
  text <- lapply(d, function(x) {
    if (inherits(x, "POSIXct")) format(x, "%Y-%m-%dT%H:%M:%OS6Z", tz = "UTC")
    else if (is.numeric(x)) ifelse(is.na(x), NA, sprintf("%.17g", x))
    else as.character(x)
  })
  writeLines(paste(names(d), cls, sep = "\t"), file.path(out, paste0(i, ".classes")))
  values <- as.data.frame(text, stringsAsFactors = FALSE, optional = TRUE)
  names(values) <- names(d)
  utils::write.csv(values, file.path(out, paste0(i, ".csv")), row.names = FALSE, na = "<NA>")
  writeLines(as.character(nrow(readr::problems(d))), file.path(out, paste0(i, ".problems")))
}
"""


@functools.cache
def r_available() -> bool:
    """Whether ``Rscript`` runs and has readr."""
    rscript = shutil.which("Rscript")
    if rscript is None:
        return False
    done = subprocess.run([rscript, "-e", "library(readr)"], capture_output=True, timeout=120)
    return done.returncode == 0


def run_r(code: str, cwd: Path, *args: str) -> str:
    """Runs ``code`` (an R script) with ``Rscript --vanilla`` in ``cwd``; its output, or an
    AssertionError with R's own message."""
    with tempfile.NamedTemporaryFile("w", suffix=".R", delete=False) as fh:
        fh.write(code)
    rscript = shutil.which("Rscript") or "Rscript"
    try:
        done = subprocess.run(
            [rscript, "--vanilla", fh.name, *args],
            cwd=cwd,
            capture_output=True,
            text=True,
            timeout=300,
        )
    finally:
        Path(fh.name).unlink()
    assert done.returncode == 0, f"R failed:\n{done.stderr}"
    return done.stdout


@dataclass
class RTable:
    """A CSV as R read it: each column's class (``POSIXct:UTC`` for times), its values (numbers
    as floats, logicals as bools, times as ISO 8601 text in UTC, text as text; missing: NA)
    and readr's count of parsing problems."""

    classes: dict[str, str]
    frame: pd.DataFrame
    problems: int


def read_in_r(
    paths: Sequence[Path],
    col_types: Mapping[str, str] | Sequence[Mapping[str, str]] | None = None,
) -> list[RTable]:
    """Each CSV read by ``readr::read_csv`` in one R session: with readr's defaults, or with
    ``col_types[path.stem]`` where given (one mapping for all paths, or one per path)."""
    per_path = (
        list(col_types) if isinstance(col_types, Sequence) else [col_types or {}] * len(paths)
    )
    with tempfile.TemporaryDirectory() as tmp:
        args = [
            a
            for p, types in zip(paths, per_path, strict=True)
            for a in (str(Path(p).resolve()), types.get(Path(p).stem, ""))
        ]
        run_r(READ_TABLES, Path(tmp), tmp, *args)
        return [_table(Path(tmp), i) for i in range(1, len(paths) + 1)]


def _table(folder: Path, i: int) -> RTable:
    lines = (folder / f"{i}.classes").read_text().splitlines()
    classes = dict(line.split("\t", 1) for line in lines)
    df = pd.read_csv(folder / f"{i}.csv", dtype=str, keep_default_na=False, na_values=["<NA>"])
    for c, k in classes.items():
        if k == "numeric":
            df[c] = df[c].astype("float64")
        elif k == "logical":
            df[c] = df[c].map({"TRUE": True, "FALSE": False}).astype("boolean")
    problems = int((folder / f"{i}.problems").read_text())
    return RTable(classes, df, problems)


def col_types_of(folder: Path) -> dict[str, str]:
    """The ``col_types.csv`` EmoGen writes beside CSV tables: table name → readr col_types."""
    lines = (Path(folder) / "col_types.csv").read_text().splitlines()
    assert lines[0] == "table,col_types", lines[0]
    return dict(line.split(",", 1) for line in lines[1:])


def dictionary_section(title: str) -> str:
    """The text of docs/data.md under the heading ``### <title>`` (to the next heading)."""
    text = DOCS.read_text(encoding="utf-8")
    match = re.search(rf"^### {re.escape(title)}\s*$(.*?)(?=^#{{2,3}} |\Z)", text, re.M | re.S)
    assert match, f"docs/data.md has no section '### {title}'"
    return match.group(1)


#: Column families documented once by their pattern.
FAMILIES = (("g_", "`g_<gene>`"), ("w_", "`w_<weight>`"))


def undocumented(columns: list[str], title: str, also: tuple[str, ...] = ()) -> list[str]:
    """The columns of an output that its docs/data.md section does not name."""
    section = dictionary_section(title)
    missing = []
    for c in columns:
        family = next((doc for prefix, doc in FAMILIES if c.startswith(prefix)), None)
        if family is not None and family in section:
            continue
        if f"`{c}`" not in section and c not in also:
            missing.append(c)
    return missing
