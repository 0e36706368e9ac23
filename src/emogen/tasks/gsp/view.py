"""What a GSP trial shows: one face and a slider over one of its genes.

The view carries the face at every slider position (``frames``: full weights, correctives
included in a corrected study), so the page morphs the face live as the slider moves, between
neighbouring positions, without asking the server; ``strip``: the nine positions a page without
WebGL offers as pictures instead. It never says which gene the slider moves, nor the chain's
history.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from typing_extensions import TypedDict

from emogen.errors import SelectionError
from emogen.tasks.gsp.block import GspBlock
from emogen.tasks.protocol import FaceView

#: The pictures a page without WebGL shows (the fallback strip).
STRIP = 9


class Slider(TypedDict):
    """The slider: its range (gene values), its number of positions and where it starts (a
    position drawn per trial, recorded: against anchoring)."""

    min: float
    max: float
    steps: int
    start: int


class GspView(TypedDict):
    """A GSP trial: the concept, and either ``waiting`` (every chain of the concept is being
    extended by someone else: ask again shortly) or the face at the slider's start, the slider,
    the face at every position and the strip's positions."""

    task: Literal["gsp"]
    emotion: str
    waiting: bool
    face: FaceView | None
    slider: Slider | None
    frames: list[list[float]]
    strip: list[int]


class GspResult(TypedDict):
    """A GSP trial's record for an embedding page, once answered: the concept, the position
    and value chosen, where the slider started, and the chosen face's weights."""

    task: Literal["gsp"]
    emotion: str
    position: int
    value: float
    slider_start: int
    weights: list[float]


def grid(block: GspBlock) -> np.ndarray:
    """The slider's values, position by position."""
    lo, hi = block.slider
    return np.linspace(lo, hi, block.steps)


def strip_positions(steps: int) -> list[int]:
    """The fallback strip's positions: nine spread evenly over the slider, both ends included."""
    return [round(float(x)) for x in np.linspace(0, steps - 1, STRIP)]


def slider_start(seed: int, steps: int) -> int:
    """Where a trial's slider starts: a position drawn from the trial's seed."""
    return int(np.random.default_rng(int(seed)).integers(steps))


def frames_genes(genes: np.ndarray, dimension: int, values: np.ndarray) -> np.ndarray:
    """(positions, n_genes): the face with its ``dimension`` gene at each value."""
    out = np.repeat(np.asarray(genes, dtype=np.float64)[None, :], len(values), axis=0)
    out[:, dimension] = values
    return out


def full_weights(rig: Any, eye_motion: bool, corrector: Any, genes: np.ndarray) -> np.ndarray:
    """(n, n_weights): faces' shape weights from their genes, then their correctives (a
    corrected study's corrector for the identity; None: none)."""
    w = rig.expand(np.atleast_2d(genes), eye_motion)
    if corrector is None:
        return np.asarray(w, dtype=np.float64)
    _, extra = corrector(w)
    return np.hstack([w, np.asarray(extra, dtype=np.float64).reshape(len(w), -1)])


def gsp_view(
    block: GspBlock, emotion: str, frames: np.ndarray | None, start: int | None
) -> GspView:
    if frames is None or start is None:
        return {
            "task": "gsp",
            "emotion": emotion,
            "waiting": True,
            "face": None,
            "slider": None,
            "frames": [],
            "strip": [],
        }
    lo, hi = block.slider
    rows = [[float(x) for x in f] for f in frames]
    return {
        "task": "gsp",
        "emotion": emotion,
        "waiting": False,
        "face": {"id": start, "weights": rows[start]},
        "slider": {"min": lo, "max": hi, "steps": block.steps, "start": start},
        "frames": rows,
        "strip": strip_positions(block.steps),
    }


def check_position(block: GspBlock, position: int, fallback: bool) -> None:
    """A SelectionError naming the position where it is not one the page offered."""
    if not 0 <= position < block.steps:
        raise SelectionError(
            f"position must be an integer in [0, {block.steps - 1}]; got {position}"
        )
    strip = strip_positions(block.steps)
    if fallback and position not in strip:
        raise SelectionError(
            f"a fallback answer is one of the strip's positions {strip}; got {position}"
        )
