"""Reading a study export's tables for analysis, whichever schema wrote them.

* :func:`table_path`: a table's file (``.parquet`` or ``.csv``), under its name or, for an
  export written before schema ``emogen.study/6``, under its old name (``responses`` is now
  ``categorise_responses``, ``ratings`` now ``evolve_ratings``:
  :data:`emogen.study.export.FORMERLY`).
* :class:`StudyExport`: the one loaded export of an analysis — each table read once, on first
  use, and handed to every part of ``emogen analyse`` that needs it;
* :meth:`StudyExport.final_faces`: the ``final_faces`` table (one row per finished evolve
  trial: its final face's genes and weights). Exports written before it existed get it from
  :func:`derive_final_faces` — the one place the analysis derives a final face, once per
  export.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from emogen import columns as tidy
from emogen.errors import ConfigError
from emogen.study.export import FORMERLY

#: The key of a trial in every exported table.
TRIAL_KEY = ("session_id", "trial")
_OLD_NAMES = {new: old for old, new in FORMERLY.items()}


def table_path(folder: Path, name: str) -> Path | None:
    """``folder/name.parquet`` or ``.csv``, else the same under the table's old name (None when
    neither is there)."""
    for each in (name, _OLD_NAMES.get(name)):
        for suffix in (".parquet", ".csv"):
            path = Path(folder) / f"{each}{suffix}"
            if each is not None and path.is_file():
                return path
    return None


def read_table(folder: Path, name: str, required: bool = True) -> pd.DataFrame | None:
    """A study export's table (:func:`table_path`; None, or an error if ``required``, when
    absent)."""
    path = table_path(folder, name)
    if path is None:
        if required:
            raise _absent(folder, name)
        return None
    try:
        return pd.read_parquet(path) if path.suffix == ".parquet" else tidy.read_csv(path)
    except (OSError, ValueError, ConfigError) as exc:
        raise ConfigError(f"cannot read {path}: {exc}") from None


def _absent(folder: Path, name: str) -> ConfigError:
    return ConfigError(f"{folder} has no {name}.parquet or {name}.csv (a study export's table)")


def read_output(folder: Path, name: str, required: bool = True) -> pd.DataFrame | None:
    """As :func:`read_table`, but a CSV cell that does not fit its column's type is read
    untyped (the export's checks then name it, with its row)."""
    path = table_path(folder, name)
    if path is None or path.suffix == ".parquet":
        return read_table(folder, name, required)
    try:
        try:
            return tidy.read_csv(path)
        except ConfigError:  # a cell that does not fit its column's type:
            return pd.read_csv(path)  # the checks name it, with its row
    except (OSError, ValueError) as exc:
        raise ConfigError(f"cannot read {path}: {exc}") from None


class StudyExport:
    """A study export folder as the analysis reads it: each table read once, on first use
    (:func:`read_output`), the same frame for every reader — readers must not change it."""

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder)
        self._tables: dict[str, pd.DataFrame | None] = {}
        self._final: pd.DataFrame | None = None

    def table(self, name: str) -> pd.DataFrame | None:
        """The table ``name`` (None when the export has none)."""
        if name not in self._tables:
            self._tables[name] = read_output(self.folder, name, required=False)
        return self._tables[name]

    def required(self, name: str) -> pd.DataFrame:
        """The table ``name``; an error naming it when the export has none."""
        table = self.table(name)
        if table is None:
            raise _absent(self.folder, name)
        return table

    def final_faces(self) -> pd.DataFrame:
        """The export's ``final_faces``; for an export without one (written before it existed),
        :func:`derive_final_faces` of its ``trials``, ``faces`` and ``selections`` — once."""
        if self._final is None:
            table = self.table("final_faces")
            if table is None:
                trials, faces = self.required("trials"), self.required("faces")
                table = derive_final_faces(trials, faces, self.table("selections"))
            self._final = table
        return self._final


def derive_final_faces(
    trials: pd.DataFrame, faces: pd.DataFrame, selections: pd.DataFrame | None = None
) -> pd.DataFrame:
    """The ``final_faces`` rows of an old export: for every finished evolve trial (``status``
    ``done``, a ``final_face_id``), the face of the trial's last attempt whose ``face_id`` is the
    final one, in the latest generation that shows it (face ids restart in every trial: never
    join on the id alone). A finished trial whose face is not in ``faces`` has no row. A
    ``trials`` table without ``final_face_id`` (one written by hand) takes it from
    ``selections``: the elite of the last generation of the trial's last attempt."""
    key = list(TRIAL_KEY)
    if "final_face_id" not in trials.columns and selections is not None:
        trials = trials.merge(_last_elites(selections), on=key, how="left")
    done = trials[(trials["status"] == "done") & trials["final_face_id"].notna()]
    if "task" in done.columns:
        done = done[done["task"] == "evolve"]
    last = faces.groupby(key)["attempt"].max().rename("last_attempt").reset_index()
    f = faces.merge(last, on=key)
    f = f[f["attempt"] == f["last_attempt"]].drop(columns="last_attempt")
    f = f.sort_values("generation").drop_duplicates([*key, "face_id"], keep="last")
    info = ["study", *key, "participant_id", "participant_source", "block", "block_name"]
    info += ["emotion", "identity", "repetition", "finished_at"]
    trial_info = done[[c for c in info if c in done.columns] + ["final_face_id"]]
    face_cols = ["attempt", "generation", "face_id"]
    face_cols += [c for c in faces.columns if str(c).startswith(("g_", "w_"))]
    out = trial_info.merge(
        f[[*key, *face_cols]],
        left_on=[*key, "final_face_id"],
        right_on=[*key, "face_id"],
        how="inner",
    )
    return out.drop(columns="final_face_id").sort_values(key).reset_index(drop=True)


def _last_elites(selections: pd.DataFrame) -> pd.DataFrame:
    """Per trial (``session_id``, ``trial``), the ``final_face_id``: the elite selected in the
    last generation of its last attempt."""
    key = list(TRIAL_KEY)
    elite = selections[selections["role"] == "elite"].sort_values(["attempt", "generation"])
    last = elite.drop_duplicates(key, keep="last")
    return last[[*key, "face_id"]].rename(columns={"face_id": "final_face_id"})
