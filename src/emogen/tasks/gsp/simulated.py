"""A simulated participant at a GSP slider (:mod:`emogen.tasks.simulated`: the same model).

The faces along a slider differ in one direction of gene space only, so the participant
compares them by how far each lies from their own prototype of the concept *along* that
direction, |(gᵢ − p)·u| (u: the unit vector from the slider's first face to its last, in gene
space), and picks position i with probability ∝ exp(−dᵢ / ``select_noise``) — the softmax
chooser the GA's selections use (Gumbel trick), on the participant's own random stream.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def slide(maker: Any, frames: np.ndarray, emotion: str) -> int:
    """The slider position ``maker`` (:class:`~emogen.tasks.simulated.SimulatedParticipant`)
    chooses among the faces ``frames`` (positions × full weights)."""
    genes = maker.genes(frames)
    axis = genes[-1] - genes[0]
    u = axis / max(float(np.linalg.norm(axis)), 1e-12)
    d = np.abs((genes - maker.prototypes[emotion]) @ u)
    noise = maker.design.select_noise
    if noise == 0:
        return int(np.argmin(d))
    return int(np.argmin(d / noise - maker.rng.gumbel(size=len(d))))
