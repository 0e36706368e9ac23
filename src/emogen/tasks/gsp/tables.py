"""The ``gsp`` task's records: its chains (shared by the sessions of a study, or a session's
own) and every slider answer (:mod:`emogen.tasks.gsp`).

A chain node is extended once: ``(chain_id, iteration, member)`` is unique, and a chain's row is
locked (``SELECT … FOR UPDATE`` on PostgreSQL; SQLite writes one transaction at a time) while a
trial is given it or an answer moves it.
"""

from __future__ import annotations

from datetime import datetime

from sqlalchemy import BigInteger, Boolean, Float, ForeignKey, Integer, String, Text
from sqlalchemy import UniqueConstraint as Unique
from sqlalchemy.orm import Mapped, mapped_column

from emogen.tasks.records import Base, Stamp


class GspChainRow(Base):
    """A chain: the study (its design's first study row), block and concept it belongs to, its
    index, its owner (0: shared by the study's sessions; else the session whose own chain it
    is), its seed and initial face, where it is now (``iterations`` nodes complete, ``answers``
    of the current node in, the current genes) and to whom its next node is assigned."""

    __tablename__ = "gsp_chains"
    __table_args__ = (
        Unique("study_id", "block", "emotion", "chain", "owner", name="uq_gsp_chain"),
    )

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    #: The trial whose start made the chain (chains hang from a trial in the export).
    trial_id: Mapped[int] = mapped_column(ForeignKey("trials.id"))
    study_id: Mapped[int] = mapped_column(Integer)
    block: Mapped[int] = mapped_column(Integer)
    emotion: Mapped[str] = mapped_column(String(64))
    chain: Mapped[int] = mapped_column(Integer)
    owner: Mapped[int] = mapped_column(Integer)
    seed: Mapped[int] = mapped_column(BigInteger)
    identity: Mapped[str] = mapped_column(String(64))
    #: What made the initial face (its protocol label) and its genes (JSON list).
    source_label: Mapped[str] = mapped_column(String(64))
    initial_genes: Mapped[str] = mapped_column(Text)
    genes: Mapped[str] = mapped_column(Text)
    iterations: Mapped[int] = mapped_column(Integer)
    answers: Mapped[int] = mapped_column(Integer)
    assigned_trial_id: Mapped[int | None] = mapped_column(Integer, nullable=True)
    assigned_at: Mapped[datetime | None] = mapped_column(Stamp, nullable=True)
    created_at: Mapped[datetime] = mapped_column(Stamp)


class GspIterationRow(Base):
    """A slider answer: the chain node it answered (``iteration``, and ``member`` of the node's
    ``aggregation`` answers), the gene moved, the slider's start and the chosen position and
    value, the face before the answer and the face it chose (``genes_after``: the chain's face
    with the answer's value; the chain takes ``node_value`` once its node is complete), whether it moved the chain (``applied``; a
    late answer to a node released and given to someone else is kept, not applied), and the
    times."""

    __tablename__ = "gsp_iterations"
    __table_args__ = (Unique("chain_id", "iteration", "member", "applied_key", name="uq_gsp_node"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    trial_id: Mapped[int] = mapped_column(ForeignKey("trials.id"), unique=True)
    chain_id: Mapped[int] = mapped_column(ForeignKey("gsp_chains.id"))
    iteration: Mapped[int] = mapped_column(Integer)
    member: Mapped[int] = mapped_column(Integer)
    applied: Mapped[bool] = mapped_column(Boolean)
    #: ``chain_id`` for an applied answer, the trial's id for a late one: an applied node's
    #: (chain, iteration, member) is unique in the database itself.
    applied_key: Mapped[int] = mapped_column(Integer)
    dimension: Mapped[str] = mapped_column(String(64))
    dimension_index: Mapped[int] = mapped_column(Integer)
    slider_start: Mapped[int] = mapped_column(Integer)
    position: Mapped[int] = mapped_column(Integer)
    slider_value: Mapped[float] = mapped_column(Float)
    #: The node's value (the mean of its ``aggregation`` applied answers) on the answer that
    #: completes it; NULL on the others.
    node_value: Mapped[float | None] = mapped_column(Float, nullable=True)
    fallback: Mapped[bool] = mapped_column(Boolean)
    genes_before: Mapped[str] = mapped_column(Text)
    genes_after: Mapped[str] = mapped_column(Text)
    weights_after: Mapped[str] = mapped_column(Text)
    assigned_at: Mapped[datetime | None] = mapped_column(Stamp, nullable=True)
    submitted_at: Mapped[datetime] = mapped_column(Stamp)
    server_response_ms: Mapped[float] = mapped_column(Float)
    client_response_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    load_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    step_key: Mapped[str] = mapped_column(String(64))
