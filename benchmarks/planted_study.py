"""Planted-answer studies written independently of EmoGen's simulator, exported in EmoGen's study
export format (docs/data.md, "Study export", schema ``emogen.study/6``), for checking
``emogen analyse`` and its categorisation models on a known answer.

The generating assumptions differ on purpose from those the analysis makes:

* **faces**: each emotion's population prototype has a few active genes (Uniform 0.4–0.9) over a
  Beta(1, 12) floor; a participant's prototype adds heavy-tailed (Student t, 3 df) deviations
  scaled by ``spread``; a final face adds uniform noise ±``noise``; all clipped to [0, 1]. No GA
  is run: each trial's generations walk linearly from a random face to its final face;
* **labels** (``labelling``):

  - ``"prototype"``: a Gaussian kernel on the *squared* gene distance to a centre (not a logit
    linear in distance): P(label e) ∝ exp(−d²(face, c_e) / (2 width²)) with
    c_e = own_weight · (the labeller's own prototype of e) + (1 − own_weight) · (the population
    prototype of e); a lapse (probability ``lapse``) answers uniformly among the labels offered.
    ``own_weight = 0`` is the null of the own-distance model (nobody labels by their own
    faces); ``own_weight > 0`` plants the effect;
  - ``"ignore_faces"``: the face plays no part: the intended label with probability
    ``accuracy``, else one of the others uniformly (random faces: uniformly);

* **distinctness** (``distinctness_sd`` > 0): participant i's prototypes are
  c + s_i (p_e − c) + deviation, with c the mean of the population prototypes over emotions and
  log s_i ~ N(0, distinctness_sd²): some people's emotions lie closer together than others'.
  Labelling by one's own prototypes (``own_weight`` 1), a participant whose prototypes are
  less distinct confuses more labels — the fields ↔ accuracy relation, planted;
* **categorise block**: ``n_other`` faces of other participants (drawn from everyone else's
  final faces), ``n_random`` random faces (Beta(0.6, 1.2) genes) and ``n_own`` of the
  participant's own final faces, all labels offered in a shuffled order.

    from benchmarks.planted_study import PlantedDesign, write_planted_study
    write_planted_study(PlantedDesign(participants=16), folder, seed=1)          # 10 genes
    write_planted_study(PlantedDesign(), folder, seed=1, rig=emogen.load_model().rig)

With a ``rig`` the genes are the rig's (``g_*``) and the weights its expansion (``w_*`` per
shape, no correctives), so that ``emogen analyse`` with the face model reads the study;
without one, ``genes`` generic genes whose weights are themselves.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

if TYPE_CHECKING:
    from emogen.model.rig import Rig

SCHEMA = "emogen.study/6"
STUDY = "planted"
START = pd.Timestamp("2026-01-01T09:00:00Z")


@dataclass(frozen=True)
class PlantedDesign:
    participants: int = 16
    emotions: tuple[str, ...] = ("anger", "fear", "happy", "sad")
    identities: tuple[str, ...] = ("id1", "id2")
    repetitions: int = 1
    genes: int = 10
    active_genes: int = 3
    spread: float = 0.12
    noise: float = 0.05
    generations: int = 4
    population: int = 10
    labelling: str = "prototype"
    own_weight: float = 0.0
    width: float = 0.35
    lapse: float = 0.1
    accuracy: float = 0.7
    n_other: int = 16
    n_random: int = 6
    n_own: int = 2
    distinctness_sd: float = 0.0


@dataclass(frozen=True)
class Space:
    """Gene names, weight names and the map from genes (n, G) to weights (n, W)."""

    genes: tuple[str, ...]
    weights: tuple[str, ...]
    expand: Callable[[np.ndarray], np.ndarray]

    def columns(self, g: np.ndarray) -> dict[str, float]:
        """One face's ``g_*`` and ``w_*`` columns."""
        w = self.expand(g[None])[0]
        out = {f"g_{n}": float(v) for n, v in zip(self.genes, g, strict=True)}
        return out | {f"w_{n}": float(v) for n, v in zip(self.weights, w, strict=True)}


def write_planted_study(
    design: PlantedDesign, folder: Path, *, seed: int, rig: Rig | None = None
) -> Path:
    """Draw a planted study from ``seed`` and write its export tables (Parquet) to ``folder``;
    with ``rig``, in its genes and weights (module docstring)."""
    if design.labelling not in ("prototype", "ignore_faces"):
        raise ValueError(
            f"labelling must be 'prototype' or 'ignore_faces'; got {design.labelling!r}"
        )
    rng = np.random.default_rng(seed)
    if rig is None:
        names = tuple(f"gene{k:02d}" for k in range(design.genes))
        space = Space(names, names, lambda g: g)
    else:
        space = Space(rig.gene_names(), tuple(rig.shape_names), rig.expand)
        design = replace(design, genes=len(space.genes))
    pop, own = _prototypes(design, rng)
    final = _final_faces(design, own, rng)
    evolve = _evolve_tables(design, final, space, rng)
    responses = _categorise(design, pop, own, final, space, rng)
    sessions = _sessions(design, final, responses, seed)
    trials = pd.concat([evolve["trials"], _categorise_trials(responses)], ignore_index=True)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    tables = {
        "sessions": sessions,
        "trials": trials,
        "faces": evolve["faces"],
        "selections": evolve["selections"],
        "final_faces": evolve["final_faces"],
        "categorise_responses": responses,
        "study": _study_table(design, space, seed),
    }
    for name, table in tables.items():
        _stamped(table).to_parquet(folder / f"{name}.parquet", index=False)
    return folder


def _with_genes(design: PlantedDesign, genes: int) -> PlantedDesign:
    from dataclasses import replace

    return replace(design, genes=genes)


def _prototypes(design: PlantedDesign, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(emotions, genes) population prototypes and (participants, emotions, genes) own ones."""
    e, g = len(design.emotions), design.genes
    pop = rng.beta(1.0, 12.0, size=(e, g))
    for k in range(e):
        active = rng.choice(g, size=design.active_genes, replace=False)
        pop[k, active] = rng.uniform(0.4, 0.9, size=design.active_genes)
    dev = design.spread * rng.standard_t(3, size=(design.participants, e, g))
    own = pop[None] + dev
    if design.distinctness_sd > 0:  # each participant's emotions pulled together or apart
        s = np.exp(design.distinctness_sd * rng.standard_normal(design.participants))
        centre = pop.mean(axis=0)
        own = centre + s[:, None, None] * (pop[None] - centre) + dev
    return pop, np.clip(own, 0.0, 1.0)


def _final_faces(design: PlantedDesign, own: np.ndarray, rng: np.random.Generator) -> pd.DataFrame:
    """One row per evolve trial: participant, trial, emotion, identity, repetition, genes."""
    rows, genes = [], []
    for p in range(design.participants):
        trial = 0
        for rep in range(design.repetitions):
            for ident in design.identities:
                for k, emotion in enumerate(design.emotions):
                    jitter = rng.uniform(-design.noise, design.noise, design.genes)
                    genes.append(np.clip(own[p, k] + jitter, 0.0, 1.0))
                    rows.append((p, trial, emotion, ident, rep))
                    trial += 1
    table = pd.DataFrame(rows, columns=["p", "trial", "emotion", "identity", "repetition"])
    table["genes"] = genes
    return table


def _ids(p: int) -> tuple[int, str]:
    return 1000 + p, f"P{p:03d}"


def _evolve_tables(
    design: PlantedDesign, final: pd.DataFrame, names: Space, rng: np.random.Generator
) -> dict[str, pd.DataFrame]:
    """trials, faces (a linear walk from a random face to the final one), selections (the
    walk's face is each generation's elite) and final_faces of the evolve trials."""
    trials, faces, selections, finals = [], [], [], []
    n_gen, pop = design.generations, design.population
    for row in final.itertuples():
        session, pid = _ids(row.p)
        start = rng.uniform(0, 1, design.genes)
        key = {"study": STUDY, "session_id": session, "participant_id": pid, "trial": row.trial}
        key["participant_source"] = "url"
        at = START + pd.Timedelta(minutes=row.p * 60 + row.trial * 2)
        clock = at
        for gen in range(n_gen):
            walk = start + (row.genes - start) * gen / (n_gen - 1)
            elite = int(rng.integers(pop)) if gen == 0 else 0  # later: the carried elite's tile
            other = int(rng.choice([k for k in range(pop) if k != elite]))
            for pos in range(pop):
                near = np.clip(walk + rng.normal(0, 0.1, design.genes), 0, 1)
                face = {**key, "attempt": 0, "generation": gen, "position": pos}
                face |= {"face_id": gen * pop + pos, "parent_a": pd.NA, "parent_b": pd.NA}
                face |= {"operator": "elite" if gen and pos == 0 else "mutation"}
                face |= {"shown_at": clock}
                faces.append(face | names.columns(walk if pos == elite else near))
            rt = float(rng.gamma(4.0, 1500.0))  # ms, a right-skewed response time
            for rank, pos in enumerate((elite, other)):
                selections.append(
                    {**key, "attempt": 0, "generation": gen, "face_id": gen * pop + pos}
                    | {"role": "elite" if rank == 0 else "other", "rank": rank}
                    | {"n_selected": 2, "shown_at": clock, "client_response_ms": rt}
                    | {"submitted_at": clock + pd.Timedelta(milliseconds=rt + 200)}
                )
            clock += pd.Timedelta(milliseconds=rt + 1000)
        last = (n_gen - 1) * pop
        info = {"block": 0, "block_name": "make", "emotion": row.emotion}
        info |= {"identity": row.identity, "repetition": row.repetition}
        done = clock
        trials.append(
            {**key, **info, "task": "evolve", "condition": row.trial, "seed": row.trial}
            | {"status": "done", "attempts": 1, "generation_reached": n_gen - 1}
            | {"final_face_id": last, "started_at": at, "finished_at": done}
        )
        finals.append(
            {**key, **info, "attempt": 0, "generation": n_gen - 1, "face_id": last}
            | {"finished_at": done}
            | names.columns(row.genes)
        )
    return {
        "trials": pd.DataFrame(trials),
        "faces": pd.DataFrame(faces),
        "selections": pd.DataFrame(selections),
        "final_faces": pd.DataFrame(finals),
    }


def _categorise(
    design: PlantedDesign,
    pop: np.ndarray,
    own: np.ndarray,
    final: pd.DataFrame,
    names: Space,
    rng: np.random.Generator,
) -> pd.DataFrame:
    """The categorise_responses rows: every participant's answers to others', random and own
    faces."""
    emotions = list(design.emotions)
    first = len(design.emotions) * len(design.identities) * design.repetitions
    rows = []
    for p in range(design.participants):
        session, pid = _ids(p)
        mine = final[final["p"] == p]
        others = final[final["p"] != p]
        shown = [("other", r) for r in others.sample(design.n_other, random_state=rng).itertuples()]
        shown += [("own", r) for r in mine.sample(design.n_own, random_state=rng).itertuples()]
        shown += [("random", None)] * design.n_random
        order = rng.permutation(len(shown))
        for t, i in enumerate(order):
            source, face = shown[i]
            genes = face.genes if face is not None else rng.beta(0.6, 1.2, design.genes)
            intended = face.emotion if face is not None else None
            offered = list(rng.permutation(emotions))
            label = _answer(design, genes, intended, own[p], pop, offered, rng)
            at = START + pd.Timedelta(minutes=p * 60 + 30, seconds=5 * t)
            row = {"study": STUDY, "session_id": session, "participant_id": pid}
            row |= {"participant_source": "url", "trial": first + t, "block": 1}
            row |= {"block_name": "label", "source": source, "fallback": False}
            src = _ids(face.p) if face is not None else (None, None)
            row |= {"source_session_id": src[0], "source_participant_id": src[1]}
            row |= {"source_trial": face.trial if face is not None else None}
            row |= {
                "source_face_id": (design.generations - 1) * design.population
                if face is not None
                else None
            }
            row |= {"source_row": None, "source_label": "random_uniform" if face is None else None}
            row |= {"intended": intended, "identity": design.identities[t % len(design.identities)]}
            row |= {"labels": "|".join(offered), "label": label}
            row |= {"label_position": offered.index(label)}
            row |= {"correct": None if intended is None else label == intended}
            row |= {"shown_at": at, "submitted_at": at + pd.Timedelta(seconds=3)}
            rows.append(row | names.columns(genes))
    table = pd.DataFrame(rows)
    for c in ("source_session_id", "source_trial", "source_face_id", "source_row"):
        table[c] = table[c].astype("Int64")
    table["correct"] = table["correct"].astype("boolean")
    return table


def _answer(
    design: PlantedDesign,
    genes: np.ndarray,
    intended: str | None,
    own: np.ndarray,
    pop: np.ndarray,
    offered: list[str],
    rng: np.random.Generator,
) -> str:
    """One label (see the module docstring)."""
    emotions = list(design.emotions)
    if design.labelling == "ignore_faces":
        if intended is None:
            return str(rng.choice(offered))
        if rng.random() < design.accuracy:
            return intended
        return str(rng.choice([e for e in offered if e != intended]))
    if rng.random() < design.lapse:
        return str(rng.choice(offered))
    idx = [emotions.index(e) for e in offered]
    centres = design.own_weight * own[idx] + (1 - design.own_weight) * pop[idx]
    d2 = ((genes[None] - centres) ** 2).sum(axis=1)
    logits = -d2 / (2 * design.width**2)
    prob = np.exp(logits - logits.max())
    return offered[int(rng.choice(len(offered), p=prob / prob.sum()))]


def _categorise_trials(responses: pd.DataFrame) -> pd.DataFrame:
    t = responses[["study", "session_id", "participant_id", "participant_source", "trial"]].copy()
    t["block"], t["block_name"], t["task"] = 1, "label", "categorise"
    t["condition"], t["emotion"] = t["trial"], None
    t["identity"], t["repetition"] = responses["identity"], 0
    t["seed"], t["status"], t["attempts"] = t["trial"], "done", 1
    t["generation_reached"], t["final_face_id"] = pd.NA, pd.NA
    t["started_at"], t["finished_at"] = responses["shown_at"], responses["submitted_at"]
    return t


def _sessions(
    design: PlantedDesign, final: pd.DataFrame, responses: pd.DataFrame, seed: int
) -> pd.DataFrame:
    rows = []
    for p in range(design.participants):
        session, pid = _ids(p)
        n = int((final["p"] == p).sum() + (responses["session_id"] == session).sum())
        at = START + pd.Timedelta(minutes=p * 60)
        rows.append(
            {"study": STUDY, "session_id": session, "participant_id": pid}
            | {"participant_source": "url", "session_number": p + 1, "seed": seed * 1000 + p}
            | {"order_kind": "fixed", "order_row": pd.NA, "stage": "done", "n_trials": n}
            | {"created_at": at, "consented_at": at, "started_at": at}
            | {"completed_at": at + pd.Timedelta(minutes=50)}
        )
    return pd.DataFrame(rows)


def _study_table(design: PlantedDesign, space: Space, seed: int) -> pd.DataFrame:
    return pd.DataFrame(
        [
            {
                "study": STUDY,
                "config_json": json.dumps({"planted": asdict(design), "seed": seed}),
                "model_name": "planted",
                "gene_names": json.dumps(list(space.genes)),
                "weight_names": json.dumps(list(space.weights)),
                "framing": "face",
                "created_at": START,
            }
        ]
    )


def _stamped(table: pd.DataFrame) -> pd.DataFrame:
    return table.assign(
        schema_version=SCHEMA,
        package_version="planted",
        model_hash="planted",
        study_config_hash="planted",
    )
