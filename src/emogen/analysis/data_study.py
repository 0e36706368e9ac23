"""A study export (``emogen study export``) as a :class:`~emogen.analysis.dataset.Dataset`
(see :mod:`emogen.analysis.data`)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pandas as pd

from emogen.analysis.dataset import ORDERED, Dataset
from emogen.analysis.people import sessions_of
from emogen.analysis.study_export import StudyExport
from emogen.analysis.validate import check_study
from emogen.errors import ConfigError
from emogen.metrics import cosine_distance


def _group_labels(trials: pd.DataFrame) -> pd.Series:
    emotion = trials["emotion"].astype(str)
    if "identity" in trials.columns and trials["identity"].nunique() > 1:
        return emotion + " / " + trials["identity"].astype(str)
    return emotion


class StudyTables(NamedTuple):
    trials: pd.DataFrame
    faces: pd.DataFrame
    selections: pd.DataFrame
    final: pd.DataFrame
    ratings: pd.DataFrame | None
    responses: pd.DataFrame | None


def _study_tables(export: StudyExport, exclude: frozenset[str]) -> StudyTables:
    """A study export's tables, checked, without the ``exclude``d participants' sessions."""
    folder = export.folder
    trials = export.required("trials")
    faces = export.required("faces")
    selections = export.required("selections")
    ratings = export.table("evolve_ratings")
    assert_cols = {
        "trials": (trials, ("session_id", "participant_id", "trial", "emotion", "status")),
        "faces": (faces, ("session_id", "trial", "attempt", "generation", "face_id")),
        "selections": (
            selections,
            ("session_id", "trial", "attempt", "generation", "face_id", "role"),
        ),
    }
    for name, (df, cols) in assert_cols.items():
        missing = [c for c in cols if df is None or c not in df.columns]
        if missing:
            raise ConfigError(f"{folder}/{name}: missing columns {missing} (see docs/study.md)")
    if trials is None or faces is None or selections is None:  # for the type checker
        raise ConfigError(f"{folder}: incomplete study export")
    other = bool("task" in trials.columns and (trials["task"] != "evolve").any())
    if "task" in trials.columns:  # the GA's trials; categorise trials are the responses table
        trials = trials[trials["task"] == "evolve"].reset_index(drop=True)
    check_study(folder, {"trials": trials, "faces": faces, "selections": selections}, other)
    responses = export.table("categorise_responses")
    final = export.final_faces()
    gone = sessions_of(trials, exclude) if exclude else set()
    trials, faces, selections, final = (
        t[~t["session_id"].isin(gone)] for t in (trials, faces, selections, final)
    )
    ratings, responses = (
        t if t is None else t[~t["session_id"].isin(gone)] for t in (ratings, responses)
    )
    return StudyTables(trials.reset_index(drop=True), faces, selections, final, ratings, responses)


def load_study(export: StudyExport, exclude: frozenset[str] = frozenset()) -> Dataset:
    """The study export's GA data (each table read once, by ``export``), without the
    ``exclude``d participants."""
    trials, faces, selections, final, ratings, responses = _study_tables(export, exclude)
    notes: list[str] = []
    wcols = [c for c in faces.columns if str(c).startswith("w_")]
    columns = tuple(str(c)[2:] for c in wcols)
    if not columns:
        notes.append("the faces table has no w_ (weight) columns: only errors can be analysed")
    key = ["session_id", "trial"]
    trials = trials.copy()
    trials["group"] = _group_labels(trials)
    last = faces.groupby(key)["attempt"].max().rename("last_attempt").reset_index()
    faces = faces.merge(last, on=key)
    faces = faces[faces["attempt"] == faces["last_attempt"]]
    elite_sel = selections[selections["role"] == "elite"]
    elite_sel = elite_sel.merge(last, on=key)
    elite_sel = elite_sel[elite_sel["attempt"] == elite_sel["last_attempt"]]
    keep_sel = [*key, "attempt", "generation", "face_id"]
    if "n_selected" in elite_sel.columns:
        keep_sel.append("n_selected")
    elites = elite_sel[keep_sel].merge(
        faces[[*key, "attempt", "generation", "face_id", *wcols]],
        on=[*key, "attempt", "generation", "face_id"],
        how="left",
    )
    if "n_selected" not in elites.columns:
        elites["n_selected"] = np.nan
    elites = elites.merge(trials[[*key, "participant_id", "group", "status"]], on=key, how="left")
    elites = pd.concat(  # the new columns in one block: no fragmented frame
        [
            elites.rename(columns=dict(zip(wcols, columns, strict=True))),
            pd.DataFrame(
                {
                    "sample": elites["session_id"].astype(str) + ":" + elites["trial"].astype(str),
                    "participant": elites["participant_id"].astype(str),
                    "complete": elites["status"] == "done",
                    "error": np.nan,
                },
                index=elites.index,
            ),
        ],
        axis=1,
    )
    done = trials[trials["status"] == "done"]
    if "generation_reached" in trials.columns and len(done):
        generations = int(done["generation_reached"].max())
    else:
        generations = int(elites["generation"].max()) if len(elites) else 0
    if not elites["complete"].any():
        notes.append("no trial is complete (status 'done'): there are no final faces")
    pop_size = int(faces.groupby([*key, "generation"]).size().mode().iloc[0]) if len(faces) else 10
    sel_counts = (
        elites.groupby("generation")["n_selected"].median().round().astype("Int64").tolist()
        if elites["n_selected"].notna().any()
        else []
    )
    groups = tuple(sorted(elites["group"].dropna().unique().tolist()))
    initial = faces[faces["generation"] == 0]
    initial = initial.merge(trials[[*key, "group"]], on=key, how="left")
    finals = _finals(final, trials, elites, wcols)
    bias_rows = _proxy_errors(elites, finals, initial, groups, columns, wcols)
    elites = elites[[*ORDERED, *columns]].sort_values(["group", "sample", "generation"])
    return Dataset(
        kind="study",
        source=export.folder,
        elites=elites.reset_index(drop=True),
        columns=columns,
        generations=generations,
        error_kind="CD to the group's mean final face (proxy target)",
        bias=pd.DataFrame(bias_rows, columns=["group", "sample", "best_initial_error"]),
        groups=groups,
        ratings=ratings,
        responses=responses,
        finals=finals[[*ORDERED, *columns]].reset_index(drop=True),
        population_size=pop_size,
        selections=tuple(int(s) for s in sel_counts),
        notes=notes,
        export=export,
    )


def _finals(
    final: pd.DataFrame, trials: pd.DataFrame, elites: pd.DataFrame, wcols: list[str]
) -> pd.DataFrame:
    """The export's final faces (one per finished evolve trial: ``status`` ``done`` in
    ``trials``) in the columns of ``elites`` (weights named by shape), by group and sample."""
    key = ["session_id", "trial"]
    done = trials.loc[trials["status"] == "done", [*key, "participant_id", "group"]]
    f = final[[*key, "generation", *wcols]].merge(done, on=key)
    f = f.merge(elites[[*key, "generation", "n_selected"]], on=[*key, "generation"], how="left")
    f = f.rename(columns={w: w[2:] for w in wcols})
    new = {
        "sample": f["session_id"].astype(str) + ":" + f["trial"].astype(str),
        "participant": f["participant_id"].astype(str),
        "complete": True,
        "error": np.nan,
    }
    f = pd.concat([f, pd.DataFrame(new, index=f.index)], axis=1)  # one block: not fragmented
    return f.sort_values(["group", "sample", "generation"]).reset_index(drop=True)


def _proxy_errors(
    elites: pd.DataFrame,
    finals: pd.DataFrame,
    initial: pd.DataFrame,
    groups: tuple[str, ...],
    columns: tuple[str, ...],
    wcols: list[str],
) -> list[dict[str, object]]:
    """Fill ``elites["error"]`` and ``finals["error"]`` with each face's CD to its group's proxy
    target (the mean final face); returns the bias rows: per sample, the best generation-0
    face's CD to it."""
    key = ["session_id", "trial"]
    bias_rows: list[dict[str, object]] = []
    for g in groups:
        fin = finals[finals["group"] == g]
        if not columns or fin.empty:
            continue
        proxy = fin[list(columns)].to_numpy(dtype=np.float64).mean(axis=0)
        for table in (elites, finals):
            rows = table["group"] == g
            table.loc[rows, "error"] = cosine_distance(
                table.loc[rows, list(columns)].to_numpy(dtype=np.float64), proxy
            )
        for (sid, tr), pop in initial[initial["group"] == g].groupby(key):
            w = pop[wcols].to_numpy(dtype=np.float64)
            bias_rows.append(
                {
                    "group": g,
                    "sample": f"{sid}:{tr}",
                    "best_initial_error": float(cosine_distance(w, proxy).min()),
                }
            )
    return bias_rows
