"""The ``categorise`` task's records: the face a trial shows (fixed before it is shown) and the
answer (:mod:`emogen.tasks.categorise`)."""

from __future__ import annotations

from datetime import datetime

from sqlalchemy import Boolean, Float, ForeignKey, Integer, String, Text
from sqlalchemy.orm import Mapped, mapped_column

from emogen.tasks.records import Base, Stamp


class StimulusRow(Base):
    """The face a categorise trial shows, fixed when its block starts (before it is shown):
    where it comes from, the labels offered in their order, its identity and full weights."""

    __tablename__ = "stimuli"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    trial_id: Mapped[int] = mapped_column(ForeignKey("trials.id"), unique=True)
    #: own / other / file / random; ``fallback``: a face standing in for an other's face.
    source: Mapped[str] = mapped_column(String(16))
    fallback: Mapped[bool] = mapped_column(Boolean, default=False)
    #: An own or other face: the session, trial (position) and face id it was made in.
    source_session_id: Mapped[int | None] = mapped_column(Integer, nullable=True)
    source_trial: Mapped[int | None] = mapped_column(Integer, nullable=True)
    source_face_id: Mapped[int | None] = mapped_column(Integer, nullable=True)
    #: A file face: its row (0-based, as read); a random face: its kind (protocol label).
    source_row: Mapped[int | None] = mapped_column(Integer, nullable=True)
    source_label: Mapped[str | None] = mapped_column(String(64), nullable=True)
    #: The emotion the face was made for (own, other; a file's label column), if known.
    intended: Mapped[str | None] = mapped_column(String(64), nullable=True)
    identity: Mapped[str] = mapped_column(String(64))
    #: JSON lists: genes (random faces; own/other: the source face's), full weights, labels.
    genes: Mapped[str | None] = mapped_column(Text, nullable=True)
    weights: Mapped[str] = mapped_column(Text)
    labels: Mapped[str] = mapped_column(Text)
    shown_at: Mapped[datetime | None] = mapped_column(Stamp, nullable=True)


class ResponseRow(Base):
    """A categorisation: the label chosen (or ``none``), its position among those offered,
    the intensity and confidence ratings if asked, and the times."""

    __tablename__ = "responses"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    trial_id: Mapped[int] = mapped_column(ForeignKey("trials.id"), unique=True)
    label: Mapped[str] = mapped_column(String(64))
    label_position: Mapped[int] = mapped_column(Integer)
    intensity: Mapped[int | None] = mapped_column(Integer, nullable=True)
    confidence: Mapped[int | None] = mapped_column(Integer, nullable=True)
    submitted_at: Mapped[datetime] = mapped_column(Stamp)
    server_response_ms: Mapped[float] = mapped_column(Float)
    client_response_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    load_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    step_key: Mapped[str] = mapped_column(String(64))
