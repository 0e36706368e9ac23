"""The ``categorise`` block: one face per trial, answered with an emotion label::

[[blocks]]
task = "categorise"
own = true                     # the participant's own finished faces of earlier blocks
others = 16                    # finished faces of other participants of this study
random = 8                     # draws from the face space
none_option = true
intensity = true
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import Field, model_validator

from emogen.tasks.blocks import Condition, TaskBlock, check_words

#: Where a categorised face comes from.
Source = Literal["own", "other", "file", "random"]
SOURCES: tuple[Source, ...] = ("own", "other", "file", "random")
#: The answer of a categorisation that picks none of the labels (when the block offers it).
NONE_LABEL = "none"
QUESTIONS = ("question", "intensity_question", "confidence_question")
#: The keys naming face tables (read when the server starts).
FILE_KEYS = ("file", "others_fallback", "others_pool")


class CategoriseBlock(TaskBlock):
    """One face per trial, answered with one of ``labels`` (offered in an order drawn per trial
    and recorded), optionally an intensity and a confidence rating."""

    task: Literal["categorise"]
    #: The labels offered (default: the study's emotions); each must be one of them.
    labels: tuple[str, ...] | None = Field(default=None, min_length=2)
    #: Offer "none of these" (answer ``none``).
    none_option: bool = False
    #: Ask how intense the expression is, and how confident the participant is (1 … points).
    intensity: bool = False
    confidence: bool = False
    points: Annotated[int, Field(ge=2, le=11)] = 7
    question: str = Field(default="Which emotion does this face show?", min_length=1)
    #: The rating questions and the words at their ends (1 and ``points``), as shown.
    intensity_question: str = Field(default="How intense is the expression?", min_length=1)
    intensity_labels: tuple[str, str] = ("very weak", "very strong")
    confidence_question: str = Field(default="How sure are you?", min_length=1)
    confidence_labels: tuple[str, str] = ("guessing", "certain")
    #: The participant's own finished faces of the evolve blocks before this one (one trial each).
    own: bool = False
    #: Finished faces of other participants of this study (drawn when the block starts, from
    #: the sessions completed by then, balanced over the labels); too few: ``others_fallback``.
    others: Annotated[int, Field(ge=0, le=500)] = 0
    #: A face table standing in for others' faces while too few sessions are complete (without
    #: it: random draws, ``random_kind``); recorded as a fallback face.
    others_fallback: Path | None = None
    #: Others' faces from before the study (a face table with a ``label``/``emotion`` column,
    #: or a study export's folder: its ``final_faces``, e.g. the pilot's): drawn as other
    #: participants' faces from the first participant on, the live study's completed faces
    #: joining them as they arrive (recorded with ``source_row``, not as fallback faces).
    others_pool: Path | None = None
    #: A face table (CSV or Parquet: shape/gene columns, optional ``identity`` and ``label`` or
    #: ``emotion`` columns) and how many of its rows each participant sees (default: all).
    file: Path | None = None
    file_faces: Annotated[int, Field(ge=1, le=500)] | None = None
    #: Random faces: ``protocol`` (the GA's protocol initialisation, its emotion and arbitrary
    #: faces) or ``uniform`` (U{lo..hi} genes active, values U(0, 1): reverse correlation).
    random: Annotated[int, Field(ge=0, le=500)] = 0
    random_kind: Literal["protocol", "uniform"] = "protocol"
    random_genes: tuple[Annotated[int, Field(ge=1)], Annotated[int, Field(ge=1)]] = (3, 8)
    #: Identities of random faces and of file rows without one (cycled; default: the study's).
    identities: tuple[str, ...] | None = Field(default=None, min_length=1)
    order: Literal["random", "fixed"] = "random"

    @model_validator(mode="after")
    def _has_faces(self) -> CategoriseBlock:
        if not (self.own or self.others or self.file is not None or self.random):
            raise ValueError(
                "a categorise block needs faces: set own = true, others = N, file = PATH "
                "or random = N"
            )
        if self.file_faces is not None and self.file is None:
            raise ValueError("file_faces is set but file is not: name the face table (file = …)")
        for key in ("others_fallback", "others_pool"):
            if getattr(self, key) is not None and not self.others:
                raise ValueError(f"{key} is set but others is 0")
        lo, hi = self.random_genes
        if lo > hi:
            raise ValueError(f"random_genes must be [lo, hi] with lo <= hi; got [{lo}, {hi}]")
        if self.labels is not None:
            dup = sorted({x for x in self.labels if self.labels.count(x) > 1})
            if dup:
                raise ValueError(f"labels must not repeat entries; got {dup} more than once")
            if NONE_LABEL in self.labels:
                raise ValueError(f"'{NONE_LABEL}' is the answer of none_option = true, not a label")
        return self

    def resolved(self, study: Any) -> CategoriseBlock:
        """Labels default to the study's emotions; identities to those of the blocks before
        it that make faces (else the study's)."""
        made = [
            getattr(b, "identities", None) or study.identities
            for b in study.blocks
            if b.makes_faces
        ]
        shown = tuple(dict.fromkeys(i for ids in made for i in ids)) or study.identities
        return self.model_copy(
            update={"labels": self.labels or study.emotions, "identities": self.identities or shown}
        )

    def words(self) -> tuple[str, ...]:
        return self.labels or ()

    def texts(self) -> dict[str, str]:
        out = {key: getattr(self, key) for key in QUESTIONS}
        for key in ("intensity_labels", "confidence_labels"):
            out.update({f"{key}[{j}]": t for j, t in enumerate(getattr(self, key))})
        return out

    def warnings(self, k: int, n_trials: int) -> dict[str, str]:
        if not self.others or self.others_pool is not None:
            return {}
        stand_in = "rows of others_fallback" if self.others_fallback else "random faces"
        return {
            f"blocks[{k}].others": (
                f"until a session is complete nobody has others' faces to see: everyone who "
                f"reaches this block before then gets {stand_in} instead — expected fallback "
                f"share 100% of the {self.others} others' faces ({self.others} of {n_trials} "
                "faces) for the whole first wave, e.g. every participant of a panel opened to "
                "50 at once; they drop out of the own-vs-others comparison. Set others_pool = "
                "a face table or a pilot's export folder to draw others' faces from the first "
                "participant on (`emogen study simulate … --arrivals concurrent N` shows it)"
            )
        }

    def files(self) -> dict[str, Path]:
        return {key: Path(p) for key in FILE_KEYS if (p := getattr(self, key)) is not None}

    def check(self, k: int, emotions: tuple[str, ...], earlier: tuple[TaskBlock, ...]) -> None:
        check_words(k, "labels", self.labels, emotions)
        if self.own and not any(b.makes_faces for b in earlier):
            raise ValueError(
                f"blocks[{k}]: own = true, but no block that makes faces (evolve) comes before "
                "it: the participant has no faces of their own yet (move the block after an "
                "evolve block, or draw others' / file / random faces)"
            )

    def trials(
        self, k: int, study: Any, earlier: list[Condition], rows: int | None
    ) -> list[Condition]:
        """Its faces by source: own (one per earlier face-making trial), others, the face
        table's rows (``file_faces``, else all ``rows``), random."""
        made = {c.task for c in earlier} & {b.task for b in study.blocks if b.makes_faces}
        counts = {
            "own": sum(c.task in made for c in earlier) if self.own else 0,
            "other": self.others,
            "file": (self.file_faces or rows or 0) if self.file else 0,
            "random": self.random,
        }
        return [
            Condition(k, self.task, "", "", j, source)
            for source, n in counts.items()
            for j in range(n)
        ]
