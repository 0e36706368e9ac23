"""The categorise task's export table: its name, typed columns and rows.

``categorise_responses`` (``responses`` before schema 6): one row per categorise trial whose
face was drawn — the face shown (where it came from, the emotion it was made for as
``intended``, its identity, genes and weights), the labels offered and the answer. A face made
in an evolve trial names that trial (``source_session_id``, ``source_trial``): join it to
``final_faces`` on those (docs/data.md, "Joining the tables").
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Any

from emogen.tasks.categorise.tables import ResponseRow, StimulusRow
from emogen.tasks.export import (
    TRIAL_KEY,
    ExportTable,
    Row,
    iso,
    record_columns,
    record_values,
    typed_columns,
)

Records = Any  # a read's records (emogen.study.export_rows.Records: emogen.tasks.export says)

#: The answer's columns: the record's own (:class:`ResponseRow`, where they are named).
ANSWER = record_columns(ResponseRow)


def response_rows(rec: Records) -> Iterator[Row]:
    """One row per categorise trial whose face was drawn: the face (source, identity, genes
    and full weights), the labels offered in their order, the answer (NA until answered)."""
    answers = {r.trial_id: r for r in rec.rows_of(ResponseRow)}
    for stim in rec.rows_of(StimulusRow):  # in trial id order: sessions, then positions
        t = rec.by_trial[stim.trial_id]
        s = rec.by_session[t.session_id]
        r = answers.get(t.id)
        yield {
            **rec.key(t),
            "block": t.block,
            "block_name": rec.block_name(t),
            "source": stim.source,
            "fallback": bool(stim.fallback),
            "source_session_id": stim.source_session_id,
            "source_participant_id": rec.participants.get(stim.source_session_id or -1),
            "source_trial": stim.source_trial,
            "source_face_id": stim.source_face_id,
            "source_row": stim.source_row,
            "source_label": stim.source_label,
            "intended": stim.intended,
            "identity": stim.identity,
            "labels": "|".join(json.loads(stim.labels)),
            "shown_at": iso(stim.shown_at),
            "correct": None if r is None or stim.intended is None else r.label == stim.intended,
            **record_values(r, ANSWER),
            **rec.face_values(s, stim.genes, stim.weights),
            **rec.stamp(s),
        }


CATEGORISE_RESPONSES = ExportTable(
    "categorise_responses",
    TRIAL_KEY
    + typed_columns(
        "block:int block_name:str source:str fallback:bool source_session_id:int "
        "source_participant_id:str source_trial:int source_face_id:int source_row:int "
        "source_label:str intended:str identity:str labels:str shown_at:time correct:bool"
    )
    + ANSWER,
    response_rows,
    faces=True,
    formerly="responses",
)

#: The categorise task's tables, in export order.
CATEGORISE_TABLES = (CATEGORISE_RESPONSES,)
