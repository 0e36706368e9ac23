"""The evolve task's (the GA's) export tables: each one's name, typed columns and rows.

``faces`` (every face shown, per generation), ``face_curves`` (a dynamic face's genes' time
courses, one row per face per gene shown), ``selections``, ``restarts``, ``evolve_ratings``
(the rating of a trial's final face; ``ratings`` before schema 6) and ``final_faces`` (one row
per finished evolve trial: the face the participant ended with, with its genes and weights).
Face ids are unique only within a trial (see docs/data.md, "Joining the tables").
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Any

import numpy as np

from emogen.ga.genome import TIMING, DynamicGenome
from emogen.ga.state import genome_of_state
from emogen.tasks.evolve.tables import (
    FaceCurveRow,
    FaceRow,
    PopulationRow,
    RatingRow,
    RestartRow,
    SelectionRow,
)
from emogen.tasks.export import TRIAL_KEY, ExportTable, Row, iso, typed_columns

Records = Any  # a read's records (emogen.study.export_rows.Records: emogen.tasks.export says)

#: The response times and the idempotency key of a participant's step.
_TIMING = "submitted_at:time server_response_ms:float load_ms:float client_response_ms:float"


def face_rows(rec: Records) -> Iterator[Row]:
    for f in rec.rows_of(FaceRow):
        p = rec.by_id(PopulationRow)[f.population_id]
        t = rec.by_trial[p.trial_id]
        s = rec.by_session[t.session_id]
        yield {
            **rec.key(t),
            "attempt": p.attempt,
            "generation": p.generation,
            "position": f.position,
            "face_id": f.face_id,
            "parent_a": None if f.parent_a < 0 else f.parent_a,
            "parent_b": None if f.parent_b < 0 else f.parent_b,
            "operator": f.operator,
            "shown_at": iso(p.shown_at),
            **rec.face_values(s, f.genes, f.weights),
            **rec.stamp(s),
        }


def face_curve_rows(rec: Records) -> Iterator[Row]:
    """One row per dynamic face per gene it shows (amplitude > 0): the gene's amplitude, its
    five timing parameters in [0, 1] and its onset, peak and offset latencies in seconds."""
    faces = {(f.population_id, f.position): f for f in rec.rows_of(FaceRow)}
    genomes: dict[int, DynamicGenome] = {}
    for c in rec.rows_of(FaceCurveRow):
        p = rec.by_id(PopulationRow)[c.population_id]
        t = rec.by_trial[p.trial_id]
        if t.id not in genomes:
            genomes[t.id] = genome_of_state(t.engine_state)
        f = faces[(c.population_id, c.position)]
        amplitude = json.loads(f.genes)
        timing = json.loads(c.timing)
        names = [g[2:] for g in rec.face_columns(rec.by_session[t.session_id])[0]]
        genes = [[a, *tm] for a, tm in zip(amplitude, timing, strict=True)]
        onset, peak, offset = genomes[t.id].times(np.array(genes))
        for k, gene in enumerate(names):
            if amplitude[k] > 0:
                yield {
                    **rec.key(t),
                    "attempt": p.attempt,
                    "generation": p.generation,
                    "position": c.position,
                    "face_id": f.face_id,
                    "gene": gene,
                    "amplitude": amplitude[k],
                    **dict(zip(TIMING, timing[k], strict=True)),
                    "onset_s": float(onset[k]),
                    "peak_s": float(peak[k]),
                    "offset_s": float(offset[k]),
                    "clip_s": genomes[t.id].clip_s,
                    **rec.trial_stamp(t),
                }


def selection_rows(rec: Records) -> Iterator[Row]:
    for sel in rec.rows_of(SelectionRow):
        p = rec.by_id(PopulationRow)[sel.population_id]
        t = rec.by_trial[p.trial_id]
        others = json.loads(sel.other_face_ids)
        chosen = [(sel.elite_face_id, "elite")] + [(o, "other") for o in others]
        for rank, (face, role) in enumerate(chosen):
            yield {
                **rec.key(t),
                "attempt": p.attempt,
                "generation": p.generation,
                "face_id": face,
                "role": role,
                "rank": rank,
                "n_selected": 1 + len(others),
                "shown_at": iso(p.shown_at),
                "submitted_at": iso(sel.submitted_at),
                "server_response_ms": sel.server_response_ms,
                "load_ms": sel.load_ms,
                "client_response_ms": sel.client_response_ms,
                "fallback": sel.fallback,
                "step_key": sel.step_key,
                **rec.trial_stamp(t),
            }


def restart_rows(rec: Records) -> Iterator[Row]:
    for r in rec.rows_of(RestartRow):
        p = rec.by_id(PopulationRow)[r.population_id]
        t = rec.by_trial[p.trial_id]
        yield {
            **rec.key(t),
            "attempt": p.attempt,
            "generation": p.generation,
            "shown_at": iso(p.shown_at),
            "submitted_at": iso(r.submitted_at),
            "server_response_ms": r.server_response_ms,
            "load_ms": r.load_ms,
            "client_response_ms": r.client_response_ms,
            "fallback": r.fallback,
            "step_key": r.step_key,
            **rec.trial_stamp(t),
        }


def rating_rows(rec: Records) -> Iterator[Row]:
    for rt in rec.rows_of(RatingRow):
        t = rec.by_trial[rt.trial_id]
        yield {
            **rec.key(t),
            "emotion": t.emotion,
            "identity": t.identity,
            "face_id": rt.face_id,
            "value": rt.value,
            "points": rt.points,
            "submitted_at": iso(rt.submitted_at),
            "server_response_ms": rt.server_response_ms,
            "client_response_ms": rt.client_response_ms,
            "fallback": rt.fallback,
            "step_key": rt.step_key,
            **rec.trial_stamp(t),
        }


def final_face_rows(rec: Records) -> Iterator[Row]:
    """One row per finished evolve trial: its final face (``trials.final_face_id``) as found in
    the trial's last attempt, in the latest generation that shows it, with that face's genes
    and weights."""
    latest: dict[tuple[int, int, int], tuple[int, FaceRow]] = {}
    for f in rec.rows_of(FaceRow):
        p = rec.by_id(PopulationRow)[f.population_id]
        k = (p.trial_id, p.attempt, f.face_id)
        if k not in latest or p.generation > latest[k][0]:
            latest[k] = (p.generation, f)
    for t in rec.trials:
        if t.task != "evolve" or t.status != "done" or t.final_face_id is None:
            continue
        found = latest.get((t.id, t.attempt, t.final_face_id))
        if found is None:  # not stored: the analysis reports the finished trial without it
            continue
        generation, f = found
        s = rec.by_session[t.session_id]
        yield {
            **rec.key(t),
            "block": t.block,
            "block_name": rec.block_name(t),
            "emotion": t.emotion,
            "identity": t.identity,
            "repetition": t.repetition,
            "attempt": t.attempt,
            "generation": generation,
            "face_id": f.face_id,
            "finished_at": iso(t.finished_at),
            **rec.face_values(s, f.genes, f.weights),
            **rec.stamp(s),
        }


FACES = ExportTable(
    "faces",
    TRIAL_KEY
    + typed_columns(
        "attempt:int generation:int position:int face_id:int parent_a:int parent_b:int "
        "operator:str shown_at:time"
    ),
    face_rows,
    faces=True,
)
FACE_CURVES = ExportTable(
    "face_curves",
    TRIAL_KEY
    + typed_columns(
        "attempt:int generation:int position:int face_id:int gene:str amplitude:float "
        + " ".join(f"{name}:float" for name in TIMING)
        + " onset_s:float peak_s:float offset_s:float clip_s:float"
    ),
    face_curve_rows,
)
SELECTIONS = ExportTable(
    "selections",
    TRIAL_KEY
    + typed_columns(
        "attempt:int generation:int face_id:int role:str rank:int n_selected:int shown_at:time "
        f"{_TIMING} fallback:bool step_key:str"
    ),
    selection_rows,
)
RESTARTS = ExportTable(
    "restarts",
    TRIAL_KEY
    + typed_columns(
        f"attempt:int generation:int shown_at:time {_TIMING} fallback:bool step_key:str"
    ),
    restart_rows,
)
EVOLVE_RATINGS = ExportTable(
    "evolve_ratings",
    TRIAL_KEY
    + typed_columns(
        "emotion:str identity:str face_id:int value:int points:int submitted_at:time "
        "server_response_ms:float client_response_ms:float fallback:bool step_key:str"
    ),
    rating_rows,
    formerly="ratings",
)
FINAL_FACES = ExportTable(
    "final_faces",
    TRIAL_KEY
    + typed_columns(
        "block:int block_name:str emotion:str identity:str repetition:int attempt:int "
        "generation:int face_id:int finished_at:time"
    ),
    final_face_rows,
    faces=True,
)

#: The evolve task's tables, in export order.
EVOLVE_TABLES = (FACES, FACE_CURVES, SELECTIONS, RESTARTS, EVOLVE_RATINGS, FINAL_FACES)
