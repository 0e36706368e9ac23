"""The gsp task's export tables (docs/data.md, "GSP iterations").

``gsp_iterations``: one row per slider answer — the chain and node it answered, the gene the
slider moved, where the slider started, the position and value chosen, the node's value once
complete, the whole face before (``genes_before``, and ``value_before``: the moved gene's value)
and the face chosen (the ``g_``/``w_`` columns), and the times. ``gsp_chains``: one row per
chain made by the exported sessions — its concept, seed, identity and initial face.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Any

from emogen.tasks.export import TRIAL_KEY, ExportTable, Row, iso, typed_columns
from emogen.tasks.gsp.tables import GspChainRow, GspIterationRow

Records = Any  # a read's records (emogen.study.export_rows.Records)


def _aggregation(rec: Records, trial: Any) -> int | None:
    """The trial's block's ``aggregation`` as its study's config recorded it."""
    st = rec.studies[rec.by_session[trial.session_id].study_id]
    blocks = json.loads(st.config_json).get("blocks") or []
    block = blocks[trial.block] if trial.block < len(blocks) else {}
    return int(block.get("aggregation", 1))


def iteration_rows(rec: Records) -> Iterator[Row]:
    chains = rec.by_id(GspChainRow)
    for it in rec.rows_of(GspIterationRow):
        t = rec.by_trial[it.trial_id]
        s = rec.by_session[t.session_id]
        chain = chains.get(it.chain_id)
        before = json.loads(it.genes_before)
        yield {
            **rec.key(t),
            "block": t.block,
            "block_name": rec.block_name(t),
            "emotion": t.emotion,
            "identity": t.identity,
            "chain_id": it.chain_id,
            "chain": None if chain is None else chain.chain,
            "chain_owner_session_id": None if chain is None or not chain.owner else chain.owner,
            "iteration": it.iteration,
            "member": it.member,
            "aggregation": _aggregation(rec, t),
            "applied": bool(it.applied),
            "dimension": it.dimension,
            "dimension_index": it.dimension_index,
            "slider_start": it.slider_start,
            "position": it.position,
            "slider_value": it.slider_value,
            "value_before": before[it.dimension_index],
            "node_value": it.node_value,
            "fallback": bool(it.fallback),
            "genes_before": it.genes_before,
            "assigned_at": iso(it.assigned_at),
            "submitted_at": iso(it.submitted_at),
            "server_response_ms": it.server_response_ms,
            "client_response_ms": it.client_response_ms,
            "load_ms": it.load_ms,
            "step_key": it.step_key,
            **rec.face_values(s, it.genes_after, it.weights_after),
            **rec.stamp(s),
        }


def chain_rows(rec: Records) -> Iterator[Row]:
    for c in rec.rows_of(GspChainRow):
        t = rec.by_trial[c.trial_id]
        yield {
            "study": rec.studies[rec.by_session[t.session_id].study_id].name,
            "chain_id": c.id,
            "block": c.block,
            "block_name": rec.block_name(t),
            "emotion": c.emotion,
            "chain": c.chain,
            "chain_owner_session_id": c.owner or None,
            "seed": c.seed,
            "identity": c.identity,
            "source_label": c.source_label,
            "initial_genes": c.initial_genes,
            "made_by_session_id": t.session_id,
            "created_at": iso(c.created_at),
            **rec.trial_stamp(t),
        }


GSP_ITERATIONS = ExportTable(
    "gsp_iterations",
    TRIAL_KEY
    + typed_columns(
        "block:int block_name:str emotion:str identity:str chain_id:int chain:int "
        "chain_owner_session_id:int iteration:int member:int aggregation:int applied:bool "
        "dimension:str dimension_index:int slider_start:int position:int slider_value:float "
        "value_before:float node_value:float fallback:bool genes_before:str assigned_at:time "
        "submitted_at:time server_response_ms:float client_response_ms:float load_ms:float "
        "step_key:str"
    ),
    iteration_rows,
    faces=True,
)
GSP_CHAINS = ExportTable(
    "gsp_chains",
    typed_columns(
        "study:str chain_id:int block:int block_name:str emotion:str chain:int "
        "chain_owner_session_id:int seed:seed identity:str source_label:str initial_genes:str "
        "made_by_session_id:int created_at:time"
    ),
    chain_rows,
)

#: The gsp task's tables, in export order.
GSP_TABLES = (GSP_ITERATIONS, GSP_CHAINS)
