"""Reading what EmoGen records into one shape for analysis: study exports and simulation output.

:func:`load_dataset` accepts

* a **study export** folder (``emogen study export``): ``trials``, ``faces`` and ``selections``
  tables (``.parquet`` or ``.csv``; ``ratings`` optional; schema in docs/study.md). Groups are
  emotions (``emotion / identity`` when a study has several identities); a sample is one trial
  (its last attempt, after any restarts); the final face is the elite of the last generation
  of a trial whose status is ``done``. Errors are CDs to the group's mean final face (the proxy
  target: participants' targets are latent);
* a **simulation** folder (``emogen simulate``: ``simulation.json`` + ``simulation.parquet``,
  ``faces.parquet`` with ``--all-weights`` for anything that needs faces), a **sweep** folder
  (``cells/*/``) or a folder of simulation folders: each simulation is a group, named after its
  folder; a sample is a run; errors are the recorded CDs to the target.

The result, :class:`Dataset`, holds one row per elite (sample × generation) with its error and,
when recorded, its full weights.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from emogen import columns as tidy
from emogen.analysis.people import sessions_of
from emogen.analysis.validate import check_simulation, check_study
from emogen.errors import ConfigError, DataError, did_you_mean_path
from emogen.metrics import cosine_distance

STUDY_TABLES = ("trials", "faces", "selections")
SIM_FACE_COLUMNS = ("run", "generation", "slot", "operator", "distance", "error", "rank")


@dataclass(frozen=True, eq=False)
class Dataset:
    """Elites of every sample and generation, ready for analysis.

    elites : one row per (group, sample, generation): ``group``, ``participant``, ``sample``,
    ``generation``, ``n_selected``, ``error`` (CD to the target or proxy target) and the weight
    ``columns`` (when recorded). bias : one row per sample, ``best_initial_error`` (CD of the
    closest generation-0 face to the (proxy) target). targets : known target weights per group
    (simulations). configs : the resolved simulation config per group (simulations).
    """

    kind: str
    source: Path
    elites: pd.DataFrame
    columns: tuple[str, ...]
    generations: int
    error_kind: str
    bias: pd.DataFrame
    groups: tuple[str, ...]
    targets: dict[str, np.ndarray] = field(default_factory=dict)
    configs: dict[str, dict[str, Any]] = field(default_factory=dict)
    ratings: pd.DataFrame | None = None
    #: a study's categorise answers (the export's ``responses`` table), when it has one
    responses: pd.DataFrame | None = None
    population_size: int = 10
    selections: tuple[int, ...] = ()
    notes: list[str] = field(default_factory=list)

    @property
    def has_weights(self) -> bool:
        return bool(self.columns)

    @property
    def final(self) -> pd.DataFrame:
        """Final faces: the elites of generation G of completed samples."""
        e = self.elites
        return e[(e["generation"] == self.generations) & e["complete"]]

    def final_weights(self, group: str, one_per_participant: bool = False) -> np.ndarray:
        """(n, S) the group's final faces; ``one_per_participant``: one of each participant's
        (independent samples where participants repeated the group)."""
        f = self.final
        f = f[f["group"] == group]
        if one_per_participant:
            f = f.drop_duplicates("participant", keep="first")
        return f[list(self.columns)].to_numpy(dtype=np.float64)

    def errors(self, group: str) -> np.ndarray:
        """(n_samples, G + 1) elite errors of a group (NaN where a sample stopped early)."""
        e = self.elites[self.elites["group"] == group]
        wide = e.pivot_table(index="sample", columns="generation", values="error", aggfunc="first")
        wide = wide.reindex(columns=range(self.generations + 1))
        return wide.to_numpy(dtype=np.float64)


# ---- reading tables ------------------------------------------------------------------------
def _read(folder: Path, name: str, required: bool = True) -> pd.DataFrame | None:
    for suffix in (".parquet", ".csv"):
        path = folder / f"{name}{suffix}"
        if path.is_file():
            try:
                if suffix == ".parquet":
                    return pd.read_parquet(path)
                try:
                    return tidy.read_csv(path)
                except ConfigError:  # a cell that does not fit its column's type:
                    return pd.read_csv(path)  # the checks name it, with its row
            except (OSError, ValueError) as exc:
                raise ConfigError(f"cannot read {path}: {exc}") from None
    if required:
        raise ConfigError(f"{folder} has no {name}.parquet or {name}.csv")
    return None


def load_dataset(path: Path, exclude: frozenset[str] = frozenset()) -> Dataset:
    """A study export or simulation output folder (see the module docstring); ``exclude``: ids
    of a study's participants left out of everything (an exclusion rule's verdict)."""
    folder = Path(path)
    if not folder.exists():
        raise ConfigError(f"DATA folder {folder} does not exist{did_you_mean_path(folder)}")
    if not folder.is_dir():
        raise ConfigError(f"DATA must be a folder (a study export or simulation output): {folder}")
    if all(any((folder / f"{t}{s}").is_file() for s in (".parquet", ".csv")) for t in STUDY_TABLES):
        return load_study(folder, exclude)
    sims = simulation_folders(folder)
    if sims:
        return load_simulations(folder, sims)
    raise ConfigError(
        f"{folder} is neither a study export (trials, faces, selections tables) nor simulation "
        "output (simulation.json, or cells/*/simulation.json of a sweep)"
    )


# ---- study exports -------------------------------------------------------------------------
def _group_labels(trials: pd.DataFrame) -> pd.Series:
    emotion = trials["emotion"].astype(str)
    if "identity" in trials.columns and trials["identity"].nunique() > 1:
        return emotion + " / " + trials["identity"].astype(str)
    return emotion


def _study_tables(
    folder: Path, exclude: frozenset[str]
) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame, pd.DataFrame | None, pd.DataFrame | None]:
    """A study export's tables, checked, without the ``exclude``d participants' sessions."""
    trials = _read(folder, "trials")
    faces = _read(folder, "faces")
    selections = _read(folder, "selections")
    ratings = _read(folder, "ratings", required=False)
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
    responses = _read(folder, "responses", required=False)
    gone = sessions_of(trials, exclude) if exclude else set()
    trials, faces, selections = (
        t[~t["session_id"].isin(gone)] for t in (trials, faces, selections)
    )
    ratings, responses = (
        t if t is None else t[~t["session_id"].isin(gone)] for t in (ratings, responses)
    )
    return trials.reset_index(drop=True), faces, selections, ratings, responses


def load_study(folder: Path, exclude: frozenset[str] = frozenset()) -> Dataset:
    trials, faces, selections, ratings, responses = _study_tables(folder, exclude)
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
    bias_rows = _proxy_errors(elites, initial, groups, columns, wcols, generations)
    ordered = ["group", "participant", "sample", "generation", "n_selected", "error", "complete"]
    elites = elites[[*ordered, *columns]].sort_values(["group", "sample", "generation"])
    return Dataset(
        kind="study",
        source=folder,
        elites=elites.reset_index(drop=True),
        columns=columns,
        generations=generations,
        error_kind="CD to the group's mean final face (proxy target)",
        bias=pd.DataFrame(bias_rows, columns=["group", "sample", "best_initial_error"]),
        groups=groups,
        ratings=ratings,
        responses=responses,
        population_size=pop_size,
        selections=tuple(int(s) for s in sel_counts),
        notes=notes,
    )


def _proxy_errors(
    elites: pd.DataFrame,
    initial: pd.DataFrame,
    groups: tuple[str, ...],
    columns: tuple[str, ...],
    wcols: list[str],
    generations: int,
) -> list[dict[str, object]]:
    """Fill ``elites["error"]`` with each elite's CD to its group's proxy target (the mean
    final face); returns the bias rows: per sample, the best generation-0 face's CD to it."""
    key = ["session_id", "trial"]
    bias_rows: list[dict[str, object]] = []
    for g in groups:
        fin = elites[
            (elites["group"] == g) & elites["complete"] & (elites["generation"] == generations)
        ]
        if not columns or fin.empty:
            continue
        proxy = fin[list(columns)].to_numpy(dtype=np.float64).mean(axis=0)
        rows = elites["group"] == g
        elites.loc[rows, "error"] = cosine_distance(
            elites.loc[rows, list(columns)].to_numpy(dtype=np.float64), proxy
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


# ---- simulation output ---------------------------------------------------------------------
def simulation_folders(folder: Path) -> list[Path]:
    """The simulation folders under ``folder``: itself, a sweep's cells, or its subfolders."""
    if (folder / "simulation.json").is_file():
        return [folder]
    cells = folder / "cells"
    base = cells if cells.is_dir() else folder
    return sorted(p for p in base.iterdir() if p.is_dir() and (p / "simulation.json").is_file())


def _record(sim: Path) -> dict[str, Any]:
    try:
        record: dict[str, Any] = json.loads((sim / "simulation.json").read_text())
    except ValueError as exc:
        raise DataError(f"{sim / 'simulation.json'} is not valid JSON: {exc}") from None
    return record


def _sim_weights(faces: pd.DataFrame) -> tuple[pd.DataFrame, list[str]]:
    """A simulation's faces with its weight columns named by shape, and those names: they are
    ``w_<shape>`` (``emogen.simulate/4``) or bare shape names (older outputs)."""
    faces = faces.rename(columns=lambda c: str(c)[2:] if str(c).startswith("w_") else c)
    return faces, [str(c) for c in faces.columns if c not in SIM_FACE_COLUMNS]


def _with_elite_weights(
    elites: pd.DataFrame, faces: pd.DataFrame, wcols: list[str]
) -> pd.DataFrame:
    """Each generation's elite row with the elite's weights (from the faces table)."""
    if not wcols:
        return elites
    elite = faces["rank"].fillna(-1) == 0  # NA (schema 4) or −1: not selected
    ew = faces.loc[elite, ["run", "generation", *wcols]]
    return elites.merge(ew, on=["run", "generation"], how="left")


def load_simulations(folder: Path, sims: list[Path]) -> Dataset:
    parts, bias_parts, targets, configs = [], [], {}, {}
    notes: list[str] = []
    columns: tuple[str, ...] | None = None
    generations = None
    for sim in sims:
        group = sim.name
        record = _record(sim)
        table = _read(sim, "simulation")
        faces = _read(sim, "faces", required=False)
        if table is None:  # pragma: no cover - _read raises
            continue
        g_max = int(table["generation"].max())
        if generations is not None and g_max != generations:
            raise ConfigError(
                f"simulations under {folder} differ in generations ({generations} and {g_max})"
            )
        generations = g_max
        elites = table.rename(columns={"elite_error": "error"})[
            ["run", "generation", "error", "n_selected"]
        ].copy()
        wcols: list[str] = []
        if faces is not None:
            faces, wcols = _sim_weights(faces)
        check_simulation(sim, table, faces, wcols)
        if faces is not None:
            elites = _with_elite_weights(elites, faces, wcols)
            first = faces[faces["generation"] == 0].groupby("run")["error"].min()
            bias_parts.append(
                pd.DataFrame({"group": group, "sample": first.index.astype(str),
                              "best_initial_error": first.to_numpy()})
            )  # fmt: skip
        if not wcols:
            notes.append(f"{group}: no face weights recorded (simulate with --all-weights)")
        these = tuple(wcols)
        if columns is None:
            columns = these
        elif these != columns:
            columns = ()
            notes.append("the simulations record different weight columns: weights not compared")
        elites["group"] = group
        elites["sample"] = elites["run"].astype(str)
        elites["participant"] = elites["sample"]
        elites["complete"] = True
        parts.append(elites)
        tw = record.get("target_weights", {})
        if these:
            targets[group] = np.array([float(tw.get(c, 0.0)) for c in these])
        configs[group] = record.get("config", {})
    if not parts or generations is None:
        raise ConfigError(f"no simulation found under {folder}")
    cols = columns or ()
    elites = pd.concat(parts, ignore_index=True)
    ordered = ["group", "participant", "sample", "generation", "n_selected", "error", "complete"]
    elites = elites[[*ordered, *cols]]
    first_cfg: dict[str, Any] = next(iter(configs.values()), {})
    sel = tuple(first_cfg.get("selections", ()))
    return Dataset(
        kind="simulation",
        source=folder,
        elites=elites,
        columns=cols,
        generations=generations,
        error_kind="CD to the simulation's target",
        bias=pd.concat(bias_parts, ignore_index=True)
        if bias_parts
        else pd.DataFrame(columns=["group", "sample", "best_initial_error"]),
        groups=tuple(p.name for p in sims),
        targets=targets if cols else {},
        configs=configs,
        population_size=int(first_cfg.get("ga", {}).get("population_size", 10)),
        selections=sel,
        notes=notes,
    )
