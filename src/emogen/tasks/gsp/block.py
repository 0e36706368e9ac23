"""The ``gsp`` block: Gibbs sampling with people (Harrison et al. 2020, NeurIPS)::

[[blocks]]
task = "gsp"
emotions = ["happy", "sad"]     # the concepts (default: the study's emotions)
chains = 4                      # chains per concept
iterations = 3                  # slider answers per concept per participant
aggregation = 1                 # answers averaged per chain node (1: pure Gibbs sampling)
chain_scope = "across"          # chains shared by the participants ("within": a participant's own)
release_after = 300             # seconds after which an unanswered assignment is released

Each trial moves one dimension (gene) of one chain's face with a slider; the chosen value
replaces that gene and the chain's next node moves the next dimension (in the order of
``dimensions``, cycled).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field, model_validator

from emogen.tasks.blocks import Condition, TaskBlock, check_words


class GspBlock(TaskBlock):
    """Gibbs sampling with people: ``iterations`` slider trials per concept per participant,
    each extending the furthest-behind free chain of its concept by one node."""

    task: Literal["gsp"]
    #: The concepts (default: the study's emotions); each one of the study's emotions.
    emotions: tuple[str, ...] | None = Field(default=None, min_length=1)
    #: Chains per concept, and slider answers per concept per participant (one trial each).
    chains: Annotated[int, Field(ge=1, le=200)] = 4
    iterations: Annotated[int, Field(ge=1, le=100)] = 3
    #: Answers per chain node, from different participants, averaged before the chain moves on
    #: (1: every answer moves the chain, the paper's pure Gibbs sampling).
    aggregation: Annotated[int, Field(ge=1, le=20)] = 1
    #: ``across``: chains shared by the study's participants (a chain's next node goes to the
    #: next free participant); ``within``: each participant extends chains of their own.
    chain_scope: Literal["across", "within"] = "across"
    #: The genes the slider moves, in the order the chain cycles through them (default: every
    #: core gene of the rig; ``eye_genes`` adds the eye genes, where the study moves the eyes).
    dimensions: tuple[str, ...] | None = Field(default=None, min_length=1)
    eye_genes: bool = False
    #: The slider's range (gene values) and its number of positions (both ends included).
    slider: tuple[float, float] = (0.0, 1.0)
    steps: Annotated[int, Field(ge=9, le=201)] = 41
    #: Seconds after which an assigned, unanswered chain node is given to the next participant.
    release_after: Annotated[float, Field(gt=0, le=86_400)] = 300.0
    #: Whether a participant may extend the same chain in two trials in a row.
    repeat_chain: bool = False
    #: The instruction line (default: the study's ``prompt``; ``{EMOTION}``: the concept in
    #: capitals, ``{emotion}``: as written), e.g. "Move the slider until the face looks as
    #: {emotion} as possible".
    prompt: str | None = Field(default=None, min_length=1)
    order: Literal["random", "fixed"] = "random"

    @model_validator(mode="after")
    def _fits(self) -> GspBlock:
        lo, hi = self.slider
        if not (0.0 <= lo < hi <= 1.0):
            raise ValueError(f"slider must be [lo, hi] with 0 <= lo < hi <= 1; got [{lo}, {hi}]")
        if self.dimensions is not None:
            dup = sorted({x for x in self.dimensions if self.dimensions.count(x) > 1})
            if dup:
                raise ValueError(f"dimensions must not repeat genes; got {dup} more than once")
        if self.chain_scope == "within" and self.aggregation > 1:
            raise ValueError(
                f"aggregation = {self.aggregation} averages answers of different participants: "
                'it needs chain_scope = "across"'
            )
        if self.aggregation > 1 and self.iterations > self.chains:
            raise ValueError(
                f"aggregation = {self.aggregation} with {self.chains} chains and "
                f"{self.iterations} iterations per participant: a participant answers a node "
                f"once, so after {self.chains} answers they would wait for other participants "
                "to complete nodes — the last participant of a study forever (set chains >= "
                "iterations)"
            )
        if self.chains == 1 and self.iterations > 1 and not self.repeat_chain:
            raise ValueError(
                f"one chain per concept and {self.iterations} iterations per participant: a "
                "participant would wait for the chain they have just extended (set chains >= 2 "
                "or repeat_chain = true)"
            )
        return self

    def resolved(self, study: Any) -> GspBlock:
        return self.model_copy(
            update={
                "emotions": self.emotions or study.emotions,
                "identities": self.identities or study.identities,
            }
        )

    def words(self) -> tuple[str, ...]:
        return self.emotions or ()

    def texts(self) -> dict[str, str]:
        return {} if self.prompt is None else {"prompt": self.prompt}

    def check(self, k: int, emotions: tuple[str, ...], earlier: tuple[TaskBlock, ...]) -> None:
        check_words(k, "emotions", self.emotions, emotions)

    def trials(
        self, k: int, study: Any, earlier: list[Condition], rows: int | None
    ) -> list[Condition]:
        """``iterations`` trials per concept (the identity is the chain's, fixed when the trial
        is given its chain)."""
        return [
            Condition(k, self.task, e, "", j)
            for e in self.emotions or ()
            for j in range(self.iterations)
        ]

    def check_rig(self, rig: Any, eye_motion: bool) -> None:
        self.dimension_names(rig, eye_motion)

    def dimension_names(self, rig: Any, eye_motion: bool) -> tuple[str, ...]:
        """The genes the slider moves, in chain order; a ValueError names an unknown one."""
        eye = {g.name for g in rig.genes if g.eye}
        known = rig.gene_names(eye_motion)
        if self.dimensions is None:
            return tuple(g for g in known if self.eye_genes or g not in eye)
        bad = [g for g in self.dimensions if g not in known]
        if bad:
            raise ValueError(
                f"dimensions: {bad} are not genes of rig '{rig.name}'"
                + (" (eye genes need ga.eye_motion = true)" if set(bad) & eye else "")
                + f"; genes: {', '.join(known)}"
            )
        return self.dimensions
