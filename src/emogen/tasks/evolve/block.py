"""The ``evolve`` block: the GA (paper Algorithm 1), one trial per emotion × identity ×
repetition. Keys a block leaves out take the study's top-level values (``emotions``,
``identities``, ``repetitions``, ``order``)."""

from __future__ import annotations

from typing import Annotated, Any, ClassVar, Literal

from pydantic import Field, SerializerFunctionWrapHandler, model_serializer, model_validator

from emogen.config import _Strict
from emogen.ga.genome import STATIC, DynamicGenome, Genome
from emogen.tasks.blocks import Condition, Order, TaskBlock, check_words


class Dynamic(_Strict):
    """``dynamic = {…}`` of an evolve block: faces that move (docs/ga.md, "Dynamic faces"):
    the clip's length, the hold at rest before it loops, the shortest rise or fall, and the
    keyframes at which faces are corrected."""

    clip_s: Annotated[float, Field(ge=0.2, le=10)] = 1.25
    hold_s: Annotated[float, Field(ge=0, le=10)] = 0.75
    min_segment_s: Annotated[float, Field(gt=0, le=2.5)] = 0.08
    keyframes: Annotated[int, Field(ge=2, le=200)] = 21

    @model_validator(mode="after")
    def _consistent(self) -> Dynamic:
        self.genome()  # min_segment_s at most a quarter of the clip
        return self

    def genome(self) -> DynamicGenome:
        return DynamicGenome(**self.model_dump())


class EvolveBlock(TaskBlock):
    """The GA: one trial per emotion × identity × repetition; left-out keys take the study's
    top-level values."""

    counterbalanced: ClassVar[bool] = True
    makes_faces: ClassVar[bool] = True

    task: Literal["evolve"] = "evolve"
    emotions: tuple[str, ...] | None = Field(default=None, min_length=1)
    identities: tuple[str, ...] | None = Field(default=None, min_length=1)
    repetitions: Annotated[int, Field(ge=1, le=100)] | None = None
    order: Order | None = None
    #: Faces that move: each gene's curve evolves with its amplitude (None: static faces).
    dynamic: Dynamic | None = None

    @model_serializer(mode="wrap")
    def _static_as_before(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        """A static block serialises as before dynamic faces (its study keeps its hash)."""
        data: dict[str, Any] = handler(self)
        if data.get("dynamic") is None:
            data.pop("dynamic", None)
        return data

    @property
    def works_ahead(self) -> bool:
        """Faces that move are worked ahead (``EvolveTask.ahead``): correcting a selection's
        next generation at its keyframes is most of the step (docs/study.md, "Corrected
        ahead"); a still face's step is not (its figures hold without it)."""
        return self.dynamic is not None

    def genome(self) -> Genome:
        """What its trials' genes are (:mod:`emogen.ga.genome`): static, or dynamic."""
        return STATIC if self.dynamic is None else self.dynamic.genome()

    def resolved(self, study: Any) -> EvolveBlock:
        return self.model_copy(
            update={
                "emotions": self.emotions or study.emotions,
                "identities": self.identities or study.identities,
                "repetitions": self.repetitions or study.repetitions,
                "order": self.order or study.order,
            }
        )

    def words(self) -> tuple[str, ...]:
        return self.emotions or ()

    def check(self, k: int, emotions: tuple[str, ...], earlier: tuple[TaskBlock, ...]) -> None:
        check_words(k, "emotions", self.emotions, emotions)

    def trials(
        self, k: int, study: Any, earlier: list[Condition], rows: int | None
    ) -> list[Condition]:
        return [
            Condition(k, self.task, e, i, r)
            for e in self.emotions or ()
            for i in self.identities or ()
            for r in range(self.repetitions or 1)
        ]
