"""How every output table's columns are typed and written: one set of rules for study exports,
simulation and sweep outputs and analysis tables (the data dictionary is docs/data.md).

* **Types** by column name (:func:`kind`): integers are nullable 64-bit (missing is NA, never
  −1); seeds (``seed``, ``run_seed``) are 64-bit integers, exact in Parquet;
  ``*_at`` columns are timestamps in UTC; ``g_*`` (genes) and ``w_*`` (weights) are floats.
  :func:`typed` gives a table these types (and, for an empty table, the columns it would have),
  so an empty table has the same schema as a full one.
* **Parquet** (:func:`write_parquet`): the typed table under an explicit Arrow schema (timestamps
  ``timestamp[us, UTC]``), with the provenance (schema, package version, model hash, config,
  seed, git commit when known) as JSON under the schema metadata key ``emogen``.
* **CSV** (:func:`csv_text`): timestamps as ISO 8601 with the zone (``2026-01-31T09:30:00.000000Z``),
  missing values as empty cells (NA to R and pandas), and seeds as text ``s<digits>`` — a seed
  above 2**53 read as a number by R (``read.csv``, readr) or by pandas in a column with a missing
  value becomes a rounded double; with the ``s`` no reader takes it for a number.
  :func:`read_csv` reads such a CSV back with these types; ``col_types.csv`` beside a folder's
  tables gives R's readr each table's types (:func:`readr_types`: an empty table too).
"""

from __future__ import annotations

import functools
import io
import json
import re
import subprocess
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

if TYPE_CHECKING:
    import pandas as pd
    import pyarrow as pa

Kind = Literal["int", "seed", "float", "str", "time", "bool"]

#: The text before a seed's digits in CSV (see the module docstring).
SEED_PREFIX = "s"
#: Schema metadata key of the provenance JSON in every Parquet file.
METADATA_KEY = b"emogen"

_INT = frozenset({
    "session_id", "session_number", "order_row", "trial", "condition", "repetition", "ga_stream",
    "collision_solver",
    "attempts", "generation_reached", "final_face_id", "attempt", "generation", "position",
    "face_id", "parent_a", "parent_b", "rank", "n_selected", "n_trials", "value", "points",
    "run", "slot", "appearance_generator", "cell_runs", "n_samples", "n_groups", "sample_size",
    "n", "block", "source_session_id", "source_trial", "source_face_id", "source_row",
    "label_position", "intensity", "confidence", "retest_of_session_id",
})  # fmt: skip
_SEED = frozenset(("seed", "run_seed"))
_FLOAT = frozenset({
    "server_response_ms", "load_ms", "client_response_ms", "elite_error", "elite_distance",
    "distance", "error", "estimate",
})  # fmt: skip
_STR = frozenset({
    "study", "participant_id", "participant_source", "order_kind", "stage", "user_agent",
    "emotion", "identity", "status", "operator", "role", "step_key", "schema_version",
    "package_version", "model_hash", "study_config_hash", "shape", "shape_coefficients",
    "config_json", "model_name", "group", "statistic", "unit", "block_name", "task", "source",
    "source_participant_id", "source_label", "intended", "labels", "label",
    "framing", "block_order",
})  # fmt: skip
#: Booleans by name (a study export's categorisation: a fallback face, a correct answer).
_BOOL = frozenset(("fallback", "correct"))


def kind(column: str) -> Kind | None:
    """The type rule of a column name (None: no rule, the data's own type)."""
    if column in _SEED:  # by name only: a report's "per seed" column is text
        return "seed"
    if column.endswith("_at"):
        return "time"
    if column in _INT:
        return "int"
    if column in _FLOAT or column.startswith(("g_", "w_")):
        return "float"
    if column in _STR:
        return "str"
    if column in _BOOL:
        return "bool"
    return None


_PANDAS = {"int": "Int64", "seed": "Int64", "float": "float64", "str": "string", "bool": "boolean"}


def typed(
    df: pd.DataFrame, columns: Iterable[str] = (), dtypes: Mapping[str, str] | None = None
) -> pd.DataFrame:
    """``df`` with every column given its rule's type (:func:`kind`; ``dtypes`` for columns
    without a rule: pandas dtype names). An empty ``df`` gets ``columns`` (those it lacks)
    first, so an empty table keeps the schema of a full one. Values that do not fit their type
    are an error naming the column."""
    import pandas as pd

    from emogen.errors import ConfigError

    out = df.copy()
    if len(out) == 0:
        missing = [c for c in dict.fromkeys(columns) if c not in out.columns]
        out = out.reindex(columns=[*out.columns, *missing])
    for c in out.columns:
        rule = kind(str(c))
        try:
            if rule == "time":
                out[c] = pd.to_datetime(out[c], utc=True, format="ISO8601").astype(
                    "datetime64[us, UTC]"
                )
            elif rule in ("int", "seed") and not _numeric(out[c].dtype):
                out[c] = pd.array([_int(v) for v in out[c]], dtype="Int64")
            elif rule == "float" and not _numeric(out[c].dtype):
                out[c] = pd.to_numeric(out[c]).astype("float64")
            elif rule is not None:
                out[c] = out[c].astype(_PANDAS[rule])  # type: ignore[call-overload]
            elif dtypes and c in dtypes:
                out[c] = out[c].astype(dtypes[c])  # type: ignore[call-overload]
        except (TypeError, ValueError) as exc:
            raise ConfigError(f"column '{c}': values do not fit type {rule}: {exc}") from None
    return out


def frame(
    rows: list[dict[str, Any]],
    columns: Iterable[str] = (),
    dtypes: Mapping[str, str] | None = None,
) -> pd.DataFrame:
    """A typed table (:func:`typed`) from rows (dicts): integer columns are built from the
    Python ints themselves, so a seed above 2**53 beside a missing value stays exact."""
    import pandas as pd

    df = pd.DataFrame(rows)
    for c in df.columns:
        if kind(str(c)) in ("int", "seed"):
            df[c] = pd.array([_int(r.get(c)) for r in rows], dtype="Int64")
    return typed(df, columns, dtypes)


def _int(v: object) -> int | None:
    """A cell as an exact int (text digits, ``s<digits>``, ``12.0``), None when missing."""
    import pandas as pd

    if v is None or (not isinstance(v, str) and pd.isna(v)):  # type: ignore[call-overload]
        return None
    v = seed_value(v)
    if isinstance(v, str):
        v = float(v)  # a ValueError names the cell
    if isinstance(v, float) and not v.is_integer():
        raise ValueError(f"{v!r} is not an integer")
    return int(v)  # type: ignore[call-overload]


def _numeric(dtype: Any) -> bool:
    from pandas.api.types import is_numeric_dtype

    return bool(is_numeric_dtype(dtype))


def _arrow_type(column: str, dtype: Any) -> pa.DataType:
    import pandas as pd
    import pyarrow as pa

    rule = kind(column)
    if rule == "time":
        return pa.timestamp("us", tz="UTC")
    if rule in ("int", "seed"):
        return pa.int64()
    if rule == "float":
        return pa.float64()
    if rule == "str":
        return pa.string()
    for test, arrow in ((pd.api.types.is_bool_dtype, pa.bool_()),
                        (pd.api.types.is_integer_dtype, pa.int64()),
                        (pd.api.types.is_float_dtype, pa.float64())):  # fmt: skip
        if test(dtype):
            return arrow
    return pa.string()


def arrow_schema(df: pd.DataFrame) -> pa.Schema:
    """The Arrow schema of a typed table (:func:`typed`): each column's rule's type."""
    import pyarrow as pa

    return pa.schema([pa.field(str(c), _arrow_type(str(c), df[c].dtype)) for c in df.columns])


def provenance_metadata(provenance: Mapping[str, Any] | None) -> dict[bytes, bytes]:
    """The schema metadata entry that carries the provenance (and the git commit)."""
    return {
        METADATA_KEY: json.dumps(
            {**(provenance or {}), "git_commit": git_commit()}, sort_keys=True, default=str
        ).encode()
    }


def pandas_types(t: pa.DataType) -> Any:
    """``types_mapper`` for ``pyarrow.Table.to_pandas``: Arrow columns back as the typed
    tables' pandas types (nullable integers stay exact, text stays text)."""
    import pandas as pd
    import pyarrow as pa

    if pa.types.is_integer(t):
        return pd.Int64Dtype()
    text = pa.types.is_string(t) or pa.types.is_large_string(t)
    return pd.StringDtype() if text else pd.BooleanDtype() if pa.types.is_boolean(t) else None


def arrow_table(df: pd.DataFrame, provenance: Mapping[str, Any] | None = None) -> pa.Table:
    """A typed table (:func:`typed`) as Arrow, with an explicit schema and the provenance."""
    import pyarrow as pa

    df = typed(df)
    schema = arrow_schema(df)
    table = pa.Table.from_pandas(df, schema=schema, preserve_index=False)
    meta = dict(table.schema.metadata or {})
    meta.update(provenance_metadata(provenance))
    return table.replace_schema_metadata(meta)


def write_parquet(
    df: pd.DataFrame, path: Path, provenance: Mapping[str, Any] | None = None
) -> Path:
    """``df`` as Parquet at ``path`` (see the module docstring); returns the path."""
    import pyarrow.parquet as pq

    pq.write_table(arrow_table(df, provenance), path)
    return Path(path)


def provenance(path: Path) -> dict[str, Any]:
    """The provenance JSON of a Parquet file written here ({} when it has none)."""
    import pyarrow.parquet as pq

    meta = pq.read_schema(path).metadata or {}
    raw = meta.get(METADATA_KEY)
    return dict(json.loads(raw)) if raw else {}


def csv_frame(df: pd.DataFrame) -> pd.DataFrame:
    """``df`` typed, then as the text CSV cells hold: seeds ``s<digits>``, ISO 8601 times."""
    import pandas as pd

    out = typed(df)
    for c in out.columns:
        rule = kind(str(c))
        if rule == "seed":
            out[c] = out[c].map(lambda v: pd.NA if pd.isna(v) else f"{SEED_PREFIX}{int(v)}")
        elif rule == "time":
            out[c] = out[c].dt.strftime("%Y-%m-%dT%H:%M:%S.%fZ")
    return out


def csv_text(df: pd.DataFrame) -> str:
    """``df`` as CSV text (:func:`csv_frame`; missing values as empty cells)."""
    return str(csv_frame(df).to_csv(index=False))


#: readr's one-letter ``col_types`` of each rule: integers ``d`` (as readr's own guess: a double
#: holds them exactly to 2**53), seeds ``c`` (``s<digits>``), times ``T``, booleans ``l``.
_READR = {"int": "d", "seed": "c", "float": "d", "str": "c", "time": "T", "bool": "l"}
#: The file beside a folder's CSV tables that gives each table its readr ``col_types``.
COL_TYPES = "col_types.csv"


def readr_types(df: pd.DataFrame) -> str:
    """``df``'s columns as a readr ``col_types`` string (:data:`_READR`; a column without a rule
    by its data's type), so R reads the table with the same types whether it has rows or not."""
    import pandas as pd

    out, letters = typed(df), []
    for c in out.columns:
        rule, dt = kind(str(c)), out[c].dtype
        if rule is None:
            rule = "bool" if pd.api.types.is_bool_dtype(dt) else "float" if _numeric(dt) else "str"
        letters.append(_READR[rule])
    return "".join(letters)


def write_col_types(folder: Path, types: Mapping[str, str]) -> Path:
    """Add ``types`` (table name → :func:`readr_types`) to ``folder``'s :data:`COL_TYPES`."""
    path = Path(folder) / COL_TYPES
    lines = path.read_text().splitlines()[1:] if path.is_file() else []
    rows = {**dict(line.split(",", 1) for line in lines), **types}
    path.write_text("table,col_types\n" + "".join(f"{t},{rows[t]}\n" for t in sorted(rows)))
    return path


def write_csv(df: pd.DataFrame, path: Path, *, col_types: bool = False) -> Path:
    """``df`` as CSV (:func:`csv_text`); ``col_types``: also its readr types (:data:`COL_TYPES`)."""
    Path(path).write_text(csv_text(df), encoding="utf-8")
    if col_types:
        write_col_types(Path(path).parent, {Path(path).stem: readr_types(df)})
    return Path(path)


def read_csv(source: Path | str, **kwargs: Any) -> pd.DataFrame:
    """A CSV written by :func:`csv_text` (or by an older EmoGen, with plain seeds) read back
    with the rules' types. ``source``: a path, or CSV text when it holds a newline."""
    import pandas as pd

    text = str(source)
    src: Any = io.StringIO(text) if "\n" in text else source
    df = pd.read_csv(src, keep_default_na=False, na_values=[""], dtype=str, **kwargs)
    for c in df.columns:
        if kind(str(c)) == "seed":
            df[c] = df[c].map(lambda v: v[len(SEED_PREFIX) :] if _prefixed(v) else v)
        elif kind(str(c)) in (None, "bool"):  # booleans are written True/False
            df[c] = _guess(df[c])
    return typed(df)


def seed_value(v: object) -> object:
    """A seed cell as an int, whether read as a number or as CSV text (``s<digits>``, or the
    plain digits of older exports); anything else unchanged (validation names it)."""
    if isinstance(v, str):
        digits = v[len(SEED_PREFIX) :] if _prefixed(v) else v
        return int(digits) if digits.isdigit() else v
    return v


def _prefixed(v: object) -> bool:
    return isinstance(v, str) and v.startswith(SEED_PREFIX)


def _guess(column: pd.Series) -> pd.Series:
    """A column without a rule: booleans or numbers when every cell is one, else text."""
    import pandas as pd

    cells = set(column.dropna())
    if cells and cells <= {"True", "False"}:
        return column.map({"True": True, "False": False}).astype("boolean")
    try:
        return pd.to_numeric(column)
    except (TypeError, ValueError):
        return column


_SYMBOLS = {"%": " pct ", "μ": " mean ", "σ": " sd ", "±": " pm ", "τ": " tau ", "≤": " le ",
            "≥": " ge ", "<": " lt ", ">": " gt ", "#": " n "}  # fmt: skip
#: Cells that a report shows for "no value": NA in a table written for machines.
_DISPLAY_MISSING = ("–", "—", "-", "")


def machine_name(header: object) -> str:
    """A column header as an identifier R and pandas take as it is (identifiers stay; else lower
    case ``[a-z0-9_]``, units and symbols spelt out (``"bias mean"`` → ``bias_mean``, ``"max [cm]"`` → ``max_cm``,
    ``"[0.25, 0.5) %"`` → ``x0_25_0_5_pct``)."""
    text = str(header)
    if re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", text):
        return text  # an identifier already (shape names keep their case: w_jawOpen)
    for sym, word in _SYMBOLS.items():
        text = text.replace(sym, word)
    text = re.sub(r"[^0-9a-zA-Z]+", "_", text.replace(".", "_")).strip("_").lower()
    text = re.sub(r"_+", "_", text) or "value"
    return "x" + text if text[0].isdigit() else text


def machine_table(df: pd.DataFrame, *, index: bool = False) -> pd.DataFrame:
    """A report table as a file for machines: one value per cell, long format, identifier
    headers (:func:`machine_name`). ``index``: the frame is a matrix (rows × columns, e.g. a
    confusion table or a pivot), written long as (row label, column label, value); display
    placeholders (``–``) become NA; headers must stay distinct."""
    import pandas as pd

    out = df.copy()
    if index:
        rows = machine_name(out.index.name or "row")
        cols = machine_name(out.columns.name or "column")
        out.index.name, out.columns.name = rows, None
        out = out.reset_index().melt(id_vars=[rows], var_name=cols, value_name="entry")
    names = [machine_name(c) for c in out.columns]
    if len(set(names)) != len(names):
        from emogen.errors import EmoGenError

        raise EmoGenError(f"table headers {list(out.columns)} are not distinct as {names}")
    out.columns = pd.Index(names)
    for c in out.columns:
        if out[c].dtype == object or pd.api.types.is_string_dtype(out[c].dtype):
            text = out[c].map(
                lambda v: pd.NA if isinstance(v, str) and v in _DISPLAY_MISSING else v
            )
            numbers = pd.to_numeric(text, errors="coerce")
            out[c] = numbers if numbers.notna().sum() == text.notna().sum() else text
    return out


@functools.cache
def git_commit() -> str | None:
    """The commit of the checkout this package runs from (None when not a git checkout)."""
    here = Path(__file__).resolve().parent
    try:
        command = ["git", "-C", str(here), "rev-parse", "--show-toplevel", "HEAD"]
        done = subprocess.run(command, capture_output=True, text=True, timeout=5, check=False)
    except (OSError, subprocess.SubprocessError):
        return None
    lines = done.stdout.split()
    if done.returncode != 0 or len(lines) != 2 or len(lines[1]) != 40:
        return None
    # an installed copy inside some other repository (a venv in a checkout) is not that commit
    return lines[1] if here == Path(lines[0]).resolve() / "src" / "emogen" else None
