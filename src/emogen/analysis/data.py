"""Reading what EmoGen records into one shape for analysis: study exports and simulation output.

:func:`load_dataset` accepts

* a **study export** folder (``emogen study export``): ``trials``, ``faces`` and ``selections``
  tables (``.parquet`` or ``.csv``; ``evolve_ratings`` optional; schema in docs/data.md).
  Groups are emotions (``emotion / identity`` when a study has several identities); a sample
  is one trial (its last attempt, after any restarts); the final faces are the export's
  ``final_faces`` table (an export written before it: derived once, by
  :meth:`~emogen.analysis.study_export.StudyExport.final_faces`); every table is read once.
  Errors are CDs to the group's mean final face (the proxy target: participants' targets are
  latent);
* a **simulation** folder (``emogen simulate``: ``simulation.json`` + ``simulation.parquet``,
  ``faces.parquet`` with ``--all-weights`` for anything that needs faces), a **sweep** folder
  (``cells/*/``) or a folder of simulation folders: each simulation is a group, named after its
  folder; a sample is a run; errors are the recorded CDs to the target.

The result, :class:`Dataset`, holds one row per elite (sample × generation) with its error and,
when recorded, its full weights.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from emogen.analysis.data_study import load_study
from emogen.analysis.dataset import Dataset as Dataset
from emogen.analysis.dataset import read_output as _read
from emogen.analysis.study_export import StudyExport
from emogen.analysis.validate import check_simulation
from emogen.errors import ConfigError, DataError, did_you_mean_path

STUDY_TABLES = ("trials", "faces", "selections")
SIM_FACE_COLUMNS = ("run", "generation", "slot", "operator", "distance", "error", "rank")


def load_dataset(path: Path | StudyExport, exclude: frozenset[str] = frozenset()) -> Dataset:
    """A study export or simulation output folder (see the module docstring); ``exclude``: ids
    of a study's participants left out of everything (an exclusion rule's verdict). A study's
    tables are read once (its :attr:`Dataset.export`; pass that again to reuse them)."""
    if isinstance(path, StudyExport):
        return load_study(path, exclude)
    folder = Path(path)
    if not folder.exists():
        raise ConfigError(f"DATA folder {folder} does not exist{did_you_mean_path(folder)}")
    if not folder.is_dir():
        raise ConfigError(f"DATA must be a folder (a study export or simulation output): {folder}")
    if all(any((folder / f"{t}{s}").is_file() for s in (".parquet", ".csv")) for t in STUDY_TABLES):
        return load_study(StudyExport(folder), exclude)
    sims = simulation_folders(folder)
    if sims:
        return load_simulations(folder, sims)
    raise ConfigError(
        f"{folder} is neither a study export (trials, faces, selections tables) nor simulation "
        "output (simulation.json, or cells/*/simulation.json of a sweep)"
    )


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
