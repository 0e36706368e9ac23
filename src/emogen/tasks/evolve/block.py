"""The ``evolve`` block: the GA (paper Algorithm 1), one trial per emotion × identity ×
repetition. Keys a block leaves out take the study's top-level values (``emotions``,
``identities``, ``repetitions``, ``order``)."""

from __future__ import annotations

from typing import Annotated, Any, ClassVar, Literal

from pydantic import Field

from emogen.tasks.blocks import Condition, Order, TaskBlock, check_words


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
