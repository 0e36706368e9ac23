"""The ``categorise`` task: one face per trial, answered with one of the study's emotion labels
(offered in an order drawn per trial), optionally an intensity and a confidence rating.

Its block config is :class:`emogen.tasks.categorise.block.CategoriseBlock`; where its faces
come from is :mod:`emogen.tasks.categorise.sources`; a simulated participant labels a face by its distance to their own
prototypes (:mod:`emogen.tasks.simulated`). This module holds what the page is sent and what an
answer must be.
"""

from __future__ import annotations

from typing import Literal

from typing_extensions import TypedDict

from emogen.errors import SelectionError
from emogen.tasks.categorise.block import NONE_LABEL, CategoriseBlock
from emogen.tasks.protocol import FaceView


class RatingScale(TypedDict):
    """A rating a categorise trial asks: its question, its number of points and the words at
    its ends (1 and ``points``)."""

    question: str
    points: int
    low_label: str
    high_label: str


class CategoriseView(TypedDict):
    """What a categorise trial shows: the face, the question, the labels in their order, and the
    ratings asked (None when not asked); never the emotion the face was made for, nor whose face
    it is."""

    task: Literal["categorise"]
    question: str
    face: FaceView
    labels: list[str]
    none_option: bool
    intensity: RatingScale | None
    confidence: RatingScale | None


class CategoriseResult(TypedDict):
    """A categorise trial's record for an embedding page, once answered: the label given and
    the face's weights (never what it was made for, nor whose it is)."""

    task: Literal["categorise"]
    label: str
    weights: list[float]


def _scale(
    block: CategoriseBlock, asked: bool, question: str, ends: tuple[str, str]
) -> RatingScale | None:
    if not asked:
        return None
    return {
        "question": question,
        "points": block.points,
        "low_label": ends[0],
        "high_label": ends[1],
    }


def categorise_view(block: CategoriseBlock, face: FaceView, labels: list[str]) -> CategoriseView:
    return {
        "task": "categorise",
        "question": block.question,
        "face": face,
        "labels": labels,
        "none_option": block.none_option,
        "intensity": _scale(
            block, block.intensity, block.intensity_question, block.intensity_labels
        ),
        "confidence": _scale(
            block, block.confidence, block.confidence_question, block.confidence_labels
        ),
    }


def _rating(name: str, value: int | None, asked: bool, points: int) -> None:
    if not asked:
        if value is not None:
            raise SelectionError(f"this block does not ask for {name}; got {name} = {value}")
        return
    if value is None:
        raise SelectionError(f"{name} is required in this block (an integer 1-{points})")
    if not 1 <= value <= points:
        raise SelectionError(f"{name} must be an integer in [1, {points}]; got {value}")


def check_answer(
    block: CategoriseBlock,
    offered: list[str],
    label: str,
    intensity: int | None,
    confidence: int | None,
) -> int:
    """The answer's position among the labels offered (``len(offered)`` for "none of these");
    a SelectionError naming what is wrong otherwise."""
    if label in offered:
        position = offered.index(label)
    elif label == NONE_LABEL and block.none_option:
        position = len(offered)
    else:
        allowed = [*offered, *([NONE_LABEL] if block.none_option else [])]
        raise SelectionError(f"label must be one of {', '.join(allowed)}; got {label!r}")
    # "none of these" names no expression whose intensity could be rated
    _rating("intensity", intensity, block.intensity and label != NONE_LABEL, block.points)
    _rating("confidence", confidence, block.confidence, block.points)
    return position
