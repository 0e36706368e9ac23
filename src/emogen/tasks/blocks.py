"""The blocks of a study config: ``[[blocks]]`` tables, each running one task over its trials.

::

    [[blocks]]                     # the GA: emotions × identities × repetitions trials
    task = "evolve"
    identities = ["female-medium"]

    [[blocks]]                     # one face per trial, answered with an emotion label
    task = "categorise"
    own = true                     # the participant's own finished faces of earlier blocks
    others = 16                    # finished faces of other participants of this study
    random = 8                     # draws from the face space
    none_option = true
    intensity = true

A study without ``[[blocks]]`` is one evolve block made of its top-level keys (the config and
its hash are those of before blocks existed). Keys an evolve block leaves out take the study's
top-level values (``emotions``, ``identities``, ``repetitions``, ``order``).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Annotated, Literal, NamedTuple

from pydantic import Field, field_validator, model_validator

from emogen.config import _Strict

#: Where a categorised face comes from.
Source = Literal["own", "other", "file", "random"]
SOURCES: tuple[Source, ...] = ("own", "other", "file", "random")
#: The answer of a categorisation that picks none of the labels (when the block offers it).
NONE_LABEL = "none"
_BLOCK_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]{0,63}$")
Order = Literal["random", "latin_square", "fixed"]


class Condition(NamedTuple):
    """One trial of a study in config order: its block and task; an evolve trial's emotion,
    identity and repetition; a categorise trial's face source and its index in that source."""

    block: int
    task: str
    emotion: str
    identity: str
    repetition: int
    source: str = ""


class _Block(_Strict):
    #: A name for the block in the exports (default ``block<k>``, k counting from 1).
    name: str | None = None

    @field_validator("name")
    @classmethod
    def _name(cls, v: str | None) -> str | None:
        if v is not None and not _BLOCK_NAME.fullmatch(v):
            raise ValueError(f"block name must be 1-64 letters, digits, '_' or '-'; got {v!r}")
        return v


class EvolveBlock(_Block):
    """The GA (paper Algorithm 1): one trial per emotion × identity × repetition; left-out keys
    take the study's top-level values."""

    task: Literal["evolve"] = "evolve"
    emotions: tuple[str, ...] | None = Field(default=None, min_length=1)
    identities: tuple[str, ...] | None = Field(default=None, min_length=1)
    repetitions: Annotated[int, Field(ge=1, le=100)] | None = None
    order: Order | None = None


class CategoriseBlock(_Block):
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
        if self.others_fallback is not None and not self.others:
            raise ValueError("others_fallback is set but others is 0")
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


Block = Annotated[EvolveBlock | CategoriseBlock, Field(discriminator="task")]


def check_blocks(
    emotions: tuple[str, ...], blocks: tuple[EvolveBlock | CategoriseBlock, ...]
) -> None:
    """The blocks fit the study: an evolve block's emotions and a categorise block's labels are
    among the study's ``emotions``; ``own`` faces come from an evolve block before it.
    Raises ValueError naming the block (``blocks[k]``, counting from 1) and the key."""
    known = set(emotions)
    seen_evolve = False
    for k, b in enumerate(blocks, start=1):
        words = b.emotions if isinstance(b, EvolveBlock) else b.labels
        key = "emotions" if isinstance(b, EvolveBlock) else "labels"
        bad = [w for w in words or () if w not in known]
        if bad:
            raise ValueError(
                f"blocks[{k}].{key}: {bad} not among the study's emotions "
                f"({', '.join(emotions)}); add them to 'emotions' or correct the spelling"
            )
        if isinstance(b, EvolveBlock):
            seen_evolve = True
        elif b.own and not seen_evolve:
            raise ValueError(
                f"blocks[{k}]: own = true, but no evolve block comes before it: the "
                "participant has no faces of their own yet (move the block after an evolve "
                "block, or draw others' / file / random faces)"
            )
