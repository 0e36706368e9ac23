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
from typing import Any, ClassVar, Literal, NamedTuple, Self

from pydantic import Field, field_validator

from emogen.config import _Strict

_BLOCK_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]{0,63}$")
Order = Literal["random", "latin_square", "fixed"]


class Condition(NamedTuple):
    """One trial of a study in config order: its block and task, the emotion and identity it
    is for (where its task says), its repetition (or index), and where its stimulus comes from
    (where its task draws one)."""

    block: int
    task: str
    emotion: str
    identity: str
    repetition: int
    source: str = ""


class TaskBlock(_Strict):
    """A block of a study: one task over its trials. A task's block config subclasses it with
    ``task: Literal[<its name>]`` and its own keys (:mod:`emogen.tasks.registry` finds the
    class by the ``task`` key of a ``[[blocks]]`` table)."""

    #: Its blocks' trial order can be counterbalanced across participants (a Latin square):
    #: the first such block's row is the session's recorded ``order_row``.
    counterbalanced: ClassVar[bool] = False
    #: Its trials make a face of the participant's own (a later block may show it to them).
    makes_faces: ClassVar[bool] = False

    task: str
    #: The identities its faces are shown with (None: as its task says, e.g. the study's).
    identities: tuple[str, ...] | None = Field(default=None, min_length=1)
    #: The order of its trials (None: random; ``latin_square`` only where it is counterbalanced).
    order: Order | None = None
    #: A name for the block in the exports (default ``block<k>``, k counting from 1).
    name: str | None = None

    @field_validator("name")
    @classmethod
    def _name(cls, v: str | None) -> str | None:
        if v is not None and not _BLOCK_NAME.fullmatch(v):
            raise ValueError(f"block name must be 1-64 letters, digits, '_' or '-'; got {v!r}")
        return v

    @property
    def works_ahead(self) -> bool:
        """Its trials' steps are worked ahead of the write transaction (the task's optional
        ``ahead``, :mod:`emogen.tasks.protocol`): only where a benchmark shows the step's work
        holds up the one writer; default no."""
        return False

    def resolved(self, study: Any) -> Self:
        """The block with the study's defaults filled in (``study``: the StudyConfig)."""
        return self

    def words(self) -> tuple[str, ...]:
        """The emotion words the block names (checked against the known emotions)."""
        return ()

    def texts(self) -> dict[str, str]:
        """The block's texts participants read, by key (``key[j]`` for a list's entries)."""
        return {}

    def warnings(self, k: int, n_trials: int) -> dict[str, str]:
        """What ``emogen study check`` warns of block ``k`` (with ``n_trials`` trials), by key:
        what a launch would see that a quiet pilot does not."""
        return {}

    def files(self) -> dict[str, Path]:
        """The files the block reads when the server starts, by key (``emogen study check``
        says where one is missing)."""
        return {}

    def check(self, k: int, emotions: tuple[str, ...], earlier: tuple[TaskBlock, ...]) -> None:
        """Raise ValueError naming ``blocks[k]`` and the key where the block does not fit the
        study (its ``emotions``, the blocks before it)."""

    def unservable(self) -> str | None:
        """Why participants cannot yet be shown this block (``emogen serve`` refuses to start
        and ``emogen study check`` warns), None when they can."""
        return None

    def check_rig(self, rig: Any, eye_motion: bool) -> None:
        """Raise ValueError naming the key where the block asks for what ``rig`` lacks (genes
        it moves); ``emogen study check`` and the server's start both ask."""

    def trials(
        self, k: int, study: Any, earlier: list[Condition], rows: int | None
    ) -> list[Condition]:
        """The block's trials in config order (``k``: its index; ``earlier``: the trials of the
        blocks before it; ``rows``: the rows of its face table where it reads one)."""
        raise NotImplementedError


def fill_emotion(text: str, emotion: str) -> str:
    """``text`` with ``{EMOTION}`` (upper-case) and ``{emotion}`` (as written) filled in: the
    prompt and the rating question."""
    return text.replace("{EMOTION}", emotion.upper()).replace("{emotion}", emotion)


def check_words(k: int, key: str, words: tuple[str, ...] | None, emotions: tuple[str, ...]) -> None:
    """A block's emotion words must be among the study's ``emotions``."""
    bad = [w for w in words or () if w not in emotions]
    if bad:
        raise ValueError(
            f"blocks[{k}].{key}: {bad} not among the study's emotions "
            f"({', '.join(emotions)}); add them to 'emotions' or correct the spelling"
        )
