"""Reading outputs as an R user's tools would, and the data dictionary, for the output tests.

No R here (``Rscript`` is not installed and cannot be from this machine's registries), so
:func:`read_csv_like_r` imitates what ``read.csv`` and readr's ``read_csv`` do with a CSV: every
cell is text until a column's every non-missing cell reads as a number, and then the whole
column is a double (a 64-bit float) — so an integer above 2**53 comes back rounded.
"""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd

DOCS = Path(__file__).resolve().parents[1] / "docs" / "data.md"
ISO_UTC = re.compile(r"^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(\.\d+)?(Z|[+-]\d\d:\d\d)$")


def read_csv_like_r(path: Path) -> pd.DataFrame:
    """A CSV with R's type guessing: numeric-looking columns become doubles; empty and ``NA``
    cells are missing."""
    df = pd.read_csv(path, dtype=str, keep_default_na=False, na_values=["", "NA"])
    for c in df.columns:
        cells = df[c].dropna()
        try:
            [float(v) for v in cells]
        except ValueError:
            continue
        df[c] = df[c].astype("float64")
    return df


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
