"""Replay sessions from exported files (``emogen study export``, Parquet or CSV) alone.

The export's ``study`` table carries each study's resolved config (``config_json``) and its
gene and weight column names; ``trials`` the trial seeds and GA streams; ``faces`` every face
shown; ``selections`` and ``restarts`` what the participant did. Each trial's engine is rebuilt
from its seed and driven through the exported selections and restarts; every population it makes
is compared with the exported faces (ids, parents, operators and genes exactly, weights within
floating-point rounding: :mod:`emogen.tasks.rounding`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from emogen import columns as tidy
from emogen.errors import ConfigError, EmoGenError
from emogen.ga.draws import CURRENT_STREAM
from emogen.ga.engine import Engine
from emogen.model.rig import Rig
from emogen.study.config import StudyConfig
from emogen.study.context import accepted_hashes
from emogen.study.export import FORMULA_STARTS
from emogen.study.replay import ReplayReport
from emogen.study.weights import StudyCorrectors
from emogen.tasks.evolve.replay import StoredFaces, compare_population

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

NEEDED = ("study", "sessions", "trials", "faces", "selections", "restarts")
Key = tuple[int, int, int, int]  # session_id, trial, attempt, generation


def _restore_text(v: Any) -> Any:
    """Undo the CSV export's formula neutralising (``'=…`` back to ``=…``)."""
    if isinstance(v, str) and v.startswith("'") and v[1:].startswith(FORMULA_STARTS):
        return v[1:]
    return v


def read_exported(folder: Path) -> dict[str, pd.DataFrame]:
    """The tables replay needs from an export folder (``<table>.parquet``, else ``.csv``)."""
    folder = Path(folder)
    out = {}
    for name in NEEDED:
        pq, csv = folder / f"{name}.parquet", folder / f"{name}.csv"
        if pq.is_file():
            out[name] = pd.read_parquet(pq)
        elif csv.is_file():
            df = tidy.read_csv(csv)
            for col in df.columns:
                if df[col].dtype == object or pd.api.types.is_string_dtype(df[col].dtype):
                    df[col] = df[col].map(_restore_text)
            out[name] = df
        else:
            raise ConfigError(
                f"export folder {folder} has no {name}.parquet or {name}.csv "
                "(write it with `emogen study export`; the study table needs emogen ≥ schema 2)"
            )
    return out


def _of_study(df: pd.DataFrame, study: str) -> pd.DataFrame:
    return df[df["study"].astype(str) == study]


def _key(key: Any) -> Key:
    s, t, a, g = (int(x) for x in key)
    return s, t, a, g


def _populations(faces: pd.DataFrame, genes: list[str], weights: list[str]) -> dict[Key, Any]:
    out = {}
    cols = ["session_id", "trial", "attempt", "generation"]
    for key, group in faces.sort_values([*cols, "position"]).groupby(cols, sort=True):
        out[_key(key)] = StoredFaces(
            ids=group["face_id"].to_numpy(np.int64),
            parents=group[["parent_a", "parent_b"]].fillna(-1).to_numpy(np.int64),
            operators=[str(o) for o in group["operator"]],
            genes=group[[f"g_{n}" for n in genes]].to_numpy(np.float64),
            weights=group[[f"w_{n}" for n in weights]].to_numpy(np.float64),
        )
    return out


def _selections(table: pd.DataFrame) -> dict[Key, tuple[int, list[int]]]:
    out: dict[Key, tuple[int, list[int]]] = {}
    cols = ["session_id", "trial", "attempt", "generation"]
    for key, group in table.sort_values([*cols, "rank"]).groupby(cols, sort=True):
        elite = group.loc[group["role"] == "elite", "face_id"]
        others = group.loc[group["role"] == "other", "face_id"]
        out[_key(key)] = (int(elite.iloc[0]), [int(o) for o in others])
    return out


def replay_exported(
    folder: Path,
    rig: Rig,
    model_hash: str,
    *,
    model: FaceModel | None = None,
    session_ids: list[int] | None = None,
) -> list[ReplayReport]:
    """One report per exported session (or per ``session_ids``), replayed from the files."""
    t = read_exported(folder)
    reports = []
    for study in t["study"].to_dict("records"):
        config = StudyConfig.model_validate(json.loads(study["config_json"]))
        genes, weights = json.loads(study["gene_names"]), json.loads(study["weight_names"])
        mine = {name: _of_study(df, str(study["study"])) for name, df in t.items()}
        faces = _populations(mine["faces"], genes, weights)
        sels = _selections(mine["selections"])
        restarts = {
            _key(r)
            for r in mine["restarts"][["session_id", "trial", "attempt", "generation"]].itertuples(
                index=False
            )
        }
        correctors = StudyCorrectors(config, model)
        trials = mine["trials"].sort_values(["session_id", "trial"])
        for sid in sorted(int(s) for s in mine["sessions"]["session_id"]):
            if session_ids is not None and sid not in session_ids:
                continue
            matches = study["model_hash"] in accepted_hashes(model_hash, model)
            report = ReplayReport(sid, model_hash_matches=matches)
            for row in trials[trials["session_id"] == sid].to_dict("records"):
                trial = {str(k): v for k, v in row.items()}
                _replay_trial(report, config, rig, correctors, trial, faces, sels, restarts)
            reports.append(report)
    if session_ids is not None and not reports:
        raise ConfigError(f"no session {session_ids} in the export at {folder}")
    return reports


def _replay_trial(
    report: ReplayReport,
    config: StudyConfig,
    rig: Rig,
    correctors: StudyCorrectors,
    trial: dict[str, Any],
    faces: dict[Key, Any],
    sels: dict[Key, tuple[int, list[int]]],
    restarts: set[Any],
) -> None:
    sid, pos = int(trial["session_id"]), int(trial["trial"])
    keys = sorted(k for k in faces if k[:2] == (sid, pos))
    if not keys:
        return
    stream = trial.get("ga_stream")
    solver = trial.get("collision_solver")  # NA or absent (before schema /4): solver 1
    try:
        engine = Engine(
            config.ga_for(str(trial["identity"])),
            rig,
            int(trial["seed"]),
            corrector=correctors(
                str(trial["identity"]), 1 if solver is None or pd.isna(solver) else int(solver)
            ),
            stream=CURRENT_STREAM if pd.isna(stream) else int(stream),
            genome=config.study_blocks()[int(trial["block"])].genome(),
        )
        for key in keys:
            where = f"session {sid} trial {pos + 1} attempt {key[2] + 1} generation {key[3]}"
            if (engine.attempt, engine.generation) != key[2:]:
                report.mismatches.append(
                    f"{where}: replay is at attempt {engine.attempt + 1} generation "
                    f"{engine.generation}"
                )
                return
            n, problems, deviation = compare_population(where, faces[key], engine)
            report.populations += 1
            report.faces += n
            report.add(problems, deviation)
            if key in sels:
                engine.tell(*sels[key])
            elif key in restarts:
                engine.reset()
    except EmoGenError as exc:
        report.mismatches.append(f"session {sid} trial {pos + 1}: replay failed: {exc}")
