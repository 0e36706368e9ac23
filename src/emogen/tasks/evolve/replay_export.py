"""Replay of evolve trials from exported files alone (``emogen study replay --from-export``).

The export's ``trials`` table carries each trial's seed and GA stream, ``faces`` every face
shown, ``selections`` and ``restarts`` what the participant did. Each trial's engine is rebuilt
from its seed and driven through the exported selections and restarts; every population it makes
is compared with the exported faces (ids, parents, operators and genes exactly, weights within
floating-point rounding: :mod:`emogen.tasks.rounding`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from emogen.errors import EmoGenError
from emogen.ga.draws import CURRENT_STREAM
from emogen.ga.engine import Engine
from emogen.tasks.evolve.replay import StoredFaces, compare_population
from emogen.tasks.protocol import ExportedStudy, Replayed, TaskEnv

#: the export tables an evolve replay reads
TABLES = ("faces", "selections", "restarts")
_KEY = ["session_id", "trial", "attempt", "generation"]
Key = tuple[int, int, int, int]  # session_id, trial, attempt, generation


def _key(key: Any) -> Key:
    s, t, a, g = (int(x) for x in key)
    return s, t, a, g


def _populations(faces: pd.DataFrame, genes: list[str], weights: list[str]) -> dict[Key, Any]:
    out = {}
    for key, group in faces.sort_values([*_KEY, "position"]).groupby(_KEY, sort=True):
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
    for key, group in table.sort_values([*_KEY, "rank"]).groupby(_KEY, sort=True):
        elite = group.loc[group["role"] == "elite", "face_id"]
        others = group.loc[group["role"] == "other", "face_id"]
        out[_key(key)] = (int(elite.iloc[0]), [int(o) for o in others])
    return out


def replay_exported(env: TaskEnv, study: ExportedStudy) -> dict[int, list[Replayed]]:
    """Every exported evolve trial of ``study.sessions``, replayed: by session id, in trial
    order (a trial with no exported faces is not an evolve trial and is passed over)."""
    lacking = study.missing("evolve", TABLES)
    if lacking is not None:
        return lacking
    t = study.tables
    faces = _populations(t["faces"], study.genes, study.weights)
    sels = _selections(t["selections"])
    restarts = {_key(r) for r in t["restarts"][_KEY].itertuples(index=False)}
    out: dict[int, list[Replayed]] = {}
    for row in t["trials"].sort_values(["session_id", "trial"]).to_dict("records"):
        trial = {str(k): v for k, v in row.items()}
        sid, pos = int(trial["session_id"]), int(trial["trial"])
        keys = sorted(k for k in faces if k[:2] == (sid, pos))
        if sid in study.sessions and keys:
            out.setdefault(sid, []).append(
                _replay_trial(env, study, trial, keys, faces, sels, restarts)
            )
    return out


def _replay_trial(
    env: TaskEnv,
    study: ExportedStudy,
    trial: dict[str, Any],
    keys: list[Key],
    faces: dict[Key, Any],
    sels: dict[Key, tuple[int, list[int]]],
    restarts: set[Key],
) -> Replayed:
    done = Replayed()
    sid, pos = int(trial["session_id"]), int(trial["trial"])
    stream = trial.get("ga_stream")
    solver = trial.get("collision_solver")  # NA or absent (before schema /4): solver 1
    try:
        engine = Engine(
            study.config.ga_for(str(trial["identity"])),
            study.rig,
            int(trial["seed"]),
            corrector=env.correctors(
                str(trial["identity"]), 1 if solver is None or pd.isna(solver) else int(solver)
            ),
            stream=CURRENT_STREAM if stream is None or pd.isna(stream) else int(stream),
            genome=study.config.study_blocks()[int(trial.get("block", 0))].genome(),
        )
        for key in keys:
            where = f"session {sid} trial {pos + 1} attempt {key[2] + 1} generation {key[3]}"
            if (engine.attempt, engine.generation) != key[2:]:
                done.problems.append(
                    f"{where}: replay is at attempt {engine.attempt + 1} generation "
                    f"{engine.generation}"
                )
                return done
            n, problems, deviation = compare_population(where, faces[key], engine)
            done.populations += 1
            done.faces += n
            done.problems += problems
            done.deviation = max(done.deviation, deviation)
            if key in sels:
                engine.tell(*sels[key])
            elif key in restarts:
                engine.reset()
    except EmoGenError as exc:
        done.problems.append(f"session {sid} trial {pos + 1}: replay failed: {exc}")
    return done
