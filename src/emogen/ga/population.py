"""A population: the faces shown in one generation, as read-only arrays."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np


def readonly(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class Population:
    """The faces shown in one generation (arrays read-only).

    genes : (n_faces, n_genes) float in [0, 1], the rig's gene space
    weights : (n_faces, n_shapes) float, full weight vectors (``rig.expand(genes)``)
    ids : (n_faces,) int, unique within an engine
    parent_ids : (n_faces, 2) int, ids of the parents in the previous generation, -1 for none
      (a ``mean_all`` face's parents are all that generation's selections)
    operators : (n_faces,) str — ``elite``, ``mean_all``, ``mean_elite_other``, ``kept``,
      ``crossover_mutation``, ``random``, or ``init_<emotion>``, ``init_arbitrary``,
      ``init_neutral``, ``init_fixed`` in generation 0
    correctives : (n_faces, C) float or None, corrective weights computed after the core
      weights by the engine's corrector (combinational, then collision); never evolved
    corrective_names : (C,) names of those columns
    keyframe_correctives : (n_faces, F, C) float or None, a dynamic face's corrective weights at
      the genome's keyframes (:func:`emogen.ga.motion.correct_keyframes`); ``correctives`` are
      then those of the peak profile ``weights``
    """

    genes: np.ndarray
    weights: np.ndarray
    ids: np.ndarray
    parent_ids: np.ndarray
    operators: np.ndarray
    generation: int
    attempt: int
    correctives: np.ndarray | None = None
    corrective_names: tuple[str, ...] = ()
    keyframe_correctives: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.ids)

    def row(self, i: int) -> Population:
        """Face ``i`` as a population of one."""
        s = slice(i, i + 1)
        return Population(
            readonly(self.genes[s]),
            readonly(self.weights[s]),
            readonly(self.ids[s]),
            readonly(self.parent_ids[s]),
            readonly(self.operators[s]),
            self.generation,
            self.attempt,
            None if self.correctives is None else readonly(self.correctives[s]),
            self.corrective_names,
            None if self.keyframe_correctives is None else readonly(self.keyframe_correctives[s]),
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "generation": self.generation,
            "attempt": self.attempt,
            "ids": self.ids.tolist(),
            "parent_ids": self.parent_ids.tolist(),
            "operators": self.operators.tolist(),
            "genes": self.genes.tolist(),
        }

    @classmethod
    def from_dict(
        cls,
        d: dict[str, Any],
        gene_shape: tuple[int, ...],
        expand: Callable[[np.ndarray], np.ndarray],
    ) -> Population:
        """A population stored by :meth:`to_dict` (genes (n, *gene_shape); ``expand`` makes
        its weights), uncorrected."""
        genes = np.array(d["genes"], dtype=np.float64).reshape(-1, *gene_shape)
        return cls(
            genes=readonly(genes),
            weights=readonly(expand(genes)),
            ids=readonly(np.array(d["ids"], dtype=np.int64)),
            parent_ids=readonly(np.array(d["parent_ids"], dtype=np.int64).reshape(-1, 2)),
            operators=readonly(np.array(d["operators"], dtype=str)),
            generation=int(d["generation"]),
            attempt=int(d["attempt"]),
        )
