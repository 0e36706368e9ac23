"""The ``evolve`` task's records: every population shown (and its faces), every selection,
restart and final rating (:mod:`emogen.tasks.evolve`)."""

from __future__ import annotations

from datetime import datetime

from sqlalchemy import Boolean, Float, ForeignKey, Integer, String, Text, UniqueConstraint
from sqlalchemy.orm import Mapped, mapped_column, relationship

from emogen.tasks.records import Base, Stamp


class PopulationRow(Base):
    """One generation shown: stored before it is sent to the participant."""

    __tablename__ = "populations"
    __table_args__ = (
        UniqueConstraint("trial_id", "attempt", "generation", name="uq_populations_generation"),
    )

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    trial_id: Mapped[int] = mapped_column(ForeignKey("trials.id"), index=True)
    attempt: Mapped[int] = mapped_column(Integer)
    generation: Mapped[int] = mapped_column(Integer)
    shown_at: Mapped[datetime] = mapped_column(Stamp)

    faces: Mapped[list[FaceRow]] = relationship(order_by="FaceRow.position")


class FaceRow(Base):
    """One face of a population: engine face id, parents, operator, genes and full weights."""

    __tablename__ = "faces"
    __table_args__ = (
        UniqueConstraint("population_id", "position", name="uq_faces_position"),
        UniqueConstraint("population_id", "face_id", name="uq_faces_face_id"),
    )

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    population_id: Mapped[int] = mapped_column(ForeignKey("populations.id"), index=True)
    position: Mapped[int] = mapped_column(Integer)
    face_id: Mapped[int] = mapped_column(Integer)
    parent_a: Mapped[int] = mapped_column(Integer)
    parent_b: Mapped[int] = mapped_column(Integer)
    operator: Mapped[str] = mapped_column(String(32))
    #: JSON lists of floats (exact: shortest round-trip repr).
    genes: Mapped[str] = mapped_column(Text)
    weights: Mapped[str] = mapped_column(Text)


class FaceCurveRow(Base):
    """A dynamic face's curves (docs/ga.md, "Dynamic faces"): its genes' timing and its
    correctives at the keyframes. The face's row keeps its amplitudes as ``genes`` and its
    peak profile as ``weights``; static faces have no such row."""

    __tablename__ = "face_curves"
    __table_args__ = (UniqueConstraint("population_id", "position", name="uq_face_curves"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    population_id: Mapped[int] = mapped_column(ForeignKey("populations.id"), index=True)
    position: Mapped[int] = mapped_column(Integer)
    #: JSON (n_genes × 5): onset, acceleration, peak, deceleration, offset, each in [0, 1].
    timing: Mapped[str] = mapped_column(Text)
    #: JSON (keyframes × correctives), or null for faces shown uncorrected.
    keyframe_correctives: Mapped[str] = mapped_column(Text)


class SelectionRow(Base):
    """A participant's selection in one population (one per population, ever)."""

    __tablename__ = "selections"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    population_id: Mapped[int] = mapped_column(ForeignKey("populations.id"), unique=True)
    trial_id: Mapped[int] = mapped_column(ForeignKey("trials.id"), index=True)
    elite_face_id: Mapped[int] = mapped_column(Integer)
    #: JSON list of the other selected face ids, in the order they were told.
    other_face_ids: Mapped[str] = mapped_column(Text)
    submitted_at: Mapped[datetime] = mapped_column(Stamp)
    server_response_ms: Mapped[float] = mapped_column(Float)
    client_response_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    #: The page's load time of the population (ms), if it reported it (schema 2).
    load_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    #: The page showed the server's images, not the 3D viewer (schema 7; None: not reported).
    fallback: Mapped[bool | None] = mapped_column(Boolean, nullable=True)
    step_key: Mapped[str] = mapped_column(String(64))


class RestartRow(Base):
    """'Start again' pressed while a population was shown."""

    __tablename__ = "restarts"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    population_id: Mapped[int] = mapped_column(ForeignKey("populations.id"), unique=True)
    trial_id: Mapped[int] = mapped_column(ForeignKey("trials.id"), index=True)
    submitted_at: Mapped[datetime] = mapped_column(Stamp)
    server_response_ms: Mapped[float] = mapped_column(Float)
    client_response_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    #: The page's load time of the population (ms), if it reported it (schema 2).
    load_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    #: The page showed the server's images, not the 3D viewer (schema 7; None: not reported).
    fallback: Mapped[bool | None] = mapped_column(Boolean, nullable=True)
    step_key: Mapped[str] = mapped_column(String(64))


class RatingRow(Base):
    """The satisfaction rating of a trial's final face."""

    __tablename__ = "ratings"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    trial_id: Mapped[int] = mapped_column(ForeignKey("trials.id"), unique=True)
    face_id: Mapped[int] = mapped_column(Integer)
    value: Mapped[int] = mapped_column(Integer)
    points: Mapped[int] = mapped_column(Integer)
    submitted_at: Mapped[datetime] = mapped_column(Stamp)
    server_response_ms: Mapped[float] = mapped_column(Float)
    client_response_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    #: The page showed the server's images, not the 3D viewer (schema 7; None: not reported).
    fallback: Mapped[bool | None] = mapped_column(Boolean, nullable=True)
    step_key: Mapped[str] = mapped_column(String(64))
