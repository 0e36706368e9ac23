"""A study export as the analyses of people need it: one row per final face, the participant
the unit.

:func:`load_people` reads a study export folder (``emogen study export``) into :class:`People`:

* ``faces``: one row per **finished** GA trial (``task = evolve``, status ``done``) — the face
  the participant ended with, as the export's ``final_faces`` table gives it (an export
  written before that table: :meth:`~emogen.analysis.study_export.StudyExport.final_faces`).
  Columns: ``participant_id``, ``session_id``, ``trial``, ``block_name``, ``emotion``,
  ``identity``, ``repetition`` (0, 1, … : the how-many-th trial of this emotion on this
  identity the participant made), ``duration_s`` (the trial's first shown face to its end),
  then the gene columns ``g_*`` (the GA's search space: one gene per left/right pair, in
  [0, 1]) and the weight columns ``w_*`` (the full, corrected shape weights the participant
  saw); plus any column of a joined participant table (e.g. ``group``);
* ``trials``: every evolve trial, finished or not (for quality checks);
* ``selections``, ``responses`` (the ``categorise_responses`` table: categorise answers, when
  the study had them), ``ratings`` (``evolve_ratings``), ``sessions``, ``identities`` and
  ``study`` as exported (an export written before schema 6 under its old table names).

A **participant table** (``--participants FILE`` of ``emogen analyse``: CSV or Parquet with a
``participant_id`` column and any others, e.g. ``group`` = clinical/control) is joined to every
face and answer; an id in it that the export lacks is reported, an id of the export missing
from it is an error (a group analysis must not silently drop people).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd

from emogen.analysis.study_export import TRIAL_KEY, StudyExport
from emogen.errors import ConfigError, DataError


@dataclass(frozen=True, eq=False)
class People:
    """A study's final faces and answers, per participant (see the module docstring)."""

    source: Path
    faces: pd.DataFrame
    trials: pd.DataFrame
    selections: pd.DataFrame
    genes: tuple[str, ...]
    weights: tuple[str, ...]
    responses: pd.DataFrame | None = None
    ratings: pd.DataFrame | None = None
    sessions: pd.DataFrame | None = None
    identities: pd.DataFrame | None = None
    #: columns joined from a participant table (empty without one)
    participant_columns: tuple[str, ...] = ()
    #: the export they were read from (its other tables, read once); None: made in memory
    export: StudyExport | None = None

    @property
    def emotions(self) -> tuple[str, ...]:
        return tuple(sorted(self.faces["emotion"].astype(str).unique()))

    @property
    def identity_names(self) -> tuple[str, ...]:
        return tuple(sorted(self.faces["identity"].astype(str).unique()))

    @property
    def n_participants(self) -> int:
        return int(self.faces["participant_id"].nunique())

    def gene_matrix(self, faces: pd.DataFrame | None = None) -> np.ndarray:
        """(n_faces, n_genes) genes of ``faces`` (default: every final face)."""
        f = self.faces if faces is None else faces
        return f[list(self.genes)].to_numpy(dtype=np.float64)

    def weight_matrix(self, faces: pd.DataFrame | None = None) -> np.ndarray:
        """(n_faces, n_weights) corrected shape weights of ``faces`` (default: every one)."""
        f = self.faces if faces is None else faces
        return f[list(self.weights)].to_numpy(dtype=np.float64)

    def with_participants(self, table: pd.DataFrame) -> People:
        """These people with ``table``'s columns joined by ``participant_id``."""
        if "participant_id" not in table.columns:
            raise ConfigError(
                "the participant table has no 'participant_id' column; it has "
                f"{list(table.columns)}"
            )
        extra = [c for c in table.columns if c != "participant_id"]
        clash = sorted(set(extra) & set(self.faces.columns))
        if clash:
            raise ConfigError(
                f"the participant table's column(s) {clash} are already in the export; rename them"
            )
        table = table.assign(participant_id=table["participant_id"].astype(str))
        dup = table["participant_id"][table["participant_id"].duplicated()]
        if len(dup):
            raise ConfigError(
                f"the participant table lists participant {dup.iloc[0]!r} more than once"
            )
        known = set(table["participant_id"])
        missing = sorted(set(self.faces["participant_id"].astype(str)) - known)
        if missing:
            shown = ", ".join(repr(m) for m in missing[:5])
            raise ConfigError(
                f"the participant table lacks {len(missing)} participant(s) of the export "
                f"({shown}{', …' if len(missing) > 5 else ''}): every participant needs a row"
            )
        faces = self.faces.merge(table, on="participant_id", how="left")
        responses = self.responses
        if responses is not None:
            responses = responses.assign(participant_id=responses["participant_id"].astype(str))
            responses = responses.merge(table, on="participant_id", how="left")
        return replace(self, faces=faces, responses=responses, participant_columns=tuple(extra))


def read_participant_table(path: Path) -> pd.DataFrame:
    """A participant table (CSV or Parquet) with a ``participant_id`` column."""
    if not path.is_file():
        raise ConfigError(f"participant table {path} does not exist")
    try:
        table = pd.read_parquet(path) if path.suffix == ".parquet" else pd.read_csv(path)
    except (OSError, ValueError) as exc:
        raise ConfigError(f"cannot read participant table {path}: {exc}") from None
    if table.empty:
        raise ConfigError(f"participant table {path} has no rows")
    return table


def load_people(source: Path | StudyExport) -> People:
    """The final faces and answers of a study export (a folder, or one loaded already: its
    tables are read once; see the module docstring)."""
    export = source if isinstance(source, StudyExport) else StudyExport(source)
    folder = export.folder
    trials, faces, selections = (export.required(n) for n in ("trials", "faces", "selections"))
    need = {"session_id", "participant_id", "trial", "emotion", "status", "final_face_id"}
    missing = sorted(need - set(trials.columns))
    if missing:
        raise DataError(f"{folder}/trials lacks column(s) {missing}: is it a study export?")
    if "task" in trials.columns:
        trials = trials[trials["task"] == "evolve"]
    trials = _typed_trials(trials.reset_index(drop=True))
    genes = tuple(c for c in faces.columns if str(c).startswith("g_"))
    weights = tuple(c for c in faces.columns if str(c).startswith("w_"))
    if not genes and len(faces):
        raise DataError(f"{folder}/faces has no gene (g_*) columns: export the study again")
    final = _final_faces(trials, export.final_faces(), faces, genes, weights)
    return People(
        source=folder,
        faces=final,
        trials=trials,
        selections=selections,
        genes=genes,
        weights=weights,
        responses=export.table("categorise_responses"),
        ratings=export.table("evolve_ratings"),
        sessions=export.table("sessions"),
        identities=export.table("identities"),
        export=export,
    )


def _typed_trials(trials: pd.DataFrame) -> pd.DataFrame:
    """Evolve trials with string ids, an ``identity`` (``-`` where none) and a ``repetition``
    (the order of the participant's trials of one emotion on one identity, from 0)."""
    t = trials.assign(
        participant_id=trials["participant_id"].astype(str),
        emotion=trials["emotion"].astype(str),
        identity=trials["identity"].astype(str) if "identity" in trials.columns else "-",
    )
    if "block_name" not in t.columns:
        t["block_name"] = "block1"
    t = t.sort_values(["participant_id", "session_id", "trial"]).reset_index(drop=True)
    # numbered over all the participant's sessions (the export's own column counts within one)
    t["repetition"] = t.groupby(["participant_id", "emotion", "identity"]).cumcount()
    return t


def _final_faces(
    trials: pd.DataFrame,
    final: pd.DataFrame,
    faces: pd.DataFrame,
    genes: tuple[str, ...],
    weights: tuple[str, ...],
) -> pd.DataFrame:
    """One row per finished trial: its final face's genes and weights (from the export's
    ``final_faces`` table), and its duration."""
    key = list(TRIAL_KEY)
    done = trials[(trials["status"] == "done") & trials["final_face_id"].notna()]
    done = done.assign(duration_s=_durations(done, faces))
    info = [*key, "participant_id", "block_name", "emotion", "identity", "repetition"]
    out = done[[*info, "duration_s"]].merge(final[[*key, *genes, *weights]], on=key, how="inner")
    lost = len(done) - len(out)
    if lost:
        raise DataError(
            f"{lost} finished trial(s) have no final face in the export (its final_faces table, "
            "or for an older export its faces table): the export is incomplete (export the "
            "study again)"
        )
    return out.reset_index(drop=True)


def _durations(done: pd.DataFrame, faces: pd.DataFrame) -> pd.Series:
    """Seconds from a trial's first shown face to its end (NaN where not recorded)."""
    if "finished_at" not in done.columns or "shown_at" not in faces.columns:
        return pd.Series(np.nan, index=done.index)
    first = faces.groupby(list(TRIAL_KEY))["shown_at"].min().rename("first_shown")
    d = done.join(first, on=list(TRIAL_KEY))
    end = pd.to_datetime(d["finished_at"], utc=True, errors="coerce")
    start = pd.to_datetime(d["first_shown"], utc=True, errors="coerce")
    return (end - start).dt.total_seconds()


def sessions_of(trials: pd.DataFrame, participants: frozenset[str]) -> set[object]:
    """The session ids of ``participants`` in a trials table (to drop them from every table)."""
    mine = trials["participant_id"].astype(str).isin(participants)
    return set(trials.loc[mine, "session_id"])
