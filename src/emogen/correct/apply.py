"""Correcting faces: core weights → companions capped → combinational → collision (eq. 5).

:class:`Corrector` holds one model's corrective matrices restricted to the vertices the
collision detector reads (float64, for the model's identity); :func:`Corrector.correct` returns
a :class:`CorrectionResult` recording the core weights and every corrective weight separately.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from emogen.correct.blend import blend
from emogen.correct.combinational import activations
from emogen.correct.correctives import Correctives, correctives_for
from emogen.correct.solve import CURRENT_SOLVER, MAX_ITERATIONS, solve_collisions

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

TYPE_NAMES = ("lip", "teeth")
CHUNK = 512  # faces whose lip vertices are held at once


@dataclass(frozen=True)
class CorrectionResult:
    """The correction of a batch of faces (arrays (B, …)).

    core : (B, S) the weights as given (the GA's genes expanded)
    weights : (B, S) effective shape weights (a companion capped at its lead, e.g. mouthClose
      at most jawOpen); equal to ``core`` for a face without such a conflict
    combinational : (B, C) product activations of the combinational correctives
    collision : (B, 8) collision corrective weights in [0, 1] (eq. 5)
    within_before, within_after : (B, 2) int, anchors within the lower lip (lip, teeth types)
      before and after the collision correction
    remaining_depth : (B,) float, the deepest pair still colliding after correction (cm)
    iterations : (B,) int, detect–solve rounds (0: no collision)
    """

    shape_names: tuple[str, ...]
    combinational_names: tuple[str, ...]
    collision_names: tuple[str, ...]
    core: np.ndarray
    weights: np.ndarray
    combinational: np.ndarray
    collision: np.ndarray
    within_before: np.ndarray
    within_after: np.ndarray
    remaining_depth: np.ndarray
    iterations: np.ndarray

    def __len__(self) -> int:
        return len(self.core)

    @property
    def collided(self) -> np.ndarray:
        """(B,) bool: a collision was detected on the face as given."""
        return self.within_before.sum(1) > 0

    @property
    def remaining(self) -> np.ndarray:
        """(B,) bool: a collision is still detected after correction (what remains uncorrected)."""
        return self.within_after.sum(1) > 0

    @property
    def corrective_names(self) -> tuple[str, ...]:
        return self.combinational_names + self.collision_names

    @property
    def correctives(self) -> np.ndarray:
        """(B, C + 8) every corrective weight, in ``corrective_names`` order."""
        return np.concatenate([self.combinational, self.collision], axis=1)

    def changed(self) -> np.ndarray:
        """(B,) bool: the corrected face differs from the face as given."""
        return (
            np.any(self.weights != self.core, axis=1)
            | np.any(self.combinational != 0, axis=1)
            | np.any(self.collision != 0, axis=1)
        )

    def columns(self) -> dict[str, np.ndarray]:
        """Named columns: shapes (effective weights), then every corrective weight."""
        out = {n: self.weights[:, i] for i, n in enumerate(self.shape_names)}
        out |= {n: self.correctives[:, i] for i, n in enumerate(self.corrective_names)}
        return out

    def report(self) -> dict[str, object]:
        """Counts for a log line: faces, collided, corrected, remaining, worst remaining depth."""
        return {
            "faces": len(self),
            "collided": int(self.collided.sum()),
            "remaining": int(self.remaining.sum()),
            "max_remaining_depth_cm": float(self.remaining_depth.max(initial=0.0)),
            "max_iterations_used": int(self.iterations.max(initial=0)),
        }


class Corrector:
    """Corrects faces of one model (one identity); see the module docstring."""

    def __init__(self, model: FaceModel, correctives: Correctives | None = None) -> None:
        # Only what correcting needs, not the model: a cache keyed weakly by the model
        # (:func:`emogen.correct.faces.corrector_for`) must not keep it alive.
        self.shape_names = model.shape_names
        self.n_vertices = model.n_vertices
        self.correctives = correctives if correctives is not None else correctives_for(model)
        c = self.correctives
        self._companions = {int(f): int(lead) for f, lead in c.companions}
        lay = c.layout
        if lay is not None and c.n_collision:
            idx = lay.vertices
            self._base_rows = np.vstack(
                [
                    model.deltas[:, idx].reshape(model.n_shapes, -1),
                    c.combinational_deltas[:, idx].reshape(c.n_combinational, -1),
                ]
            ).astype(np.float64)
            self._neutral = model.neutral[idx].reshape(-1).astype(np.float64)
            self._collision_local = c.collision_deltas[:, idx].astype(np.float64)

    def effective_weights(self, weights: np.ndarray) -> np.ndarray:
        """Companions capped at their leads: (B, S) → (B, S) float64."""
        w = np.array(weights, dtype=np.float64)
        for follower, lead in self._companions.items():
            w[:, follower] = np.minimum(w[:, follower], w[:, lead])
        return w

    def correct(
        self,
        weights: np.ndarray,
        *,
        collisions: bool = True,
        max_iterations: int = MAX_ITERATIONS,
        solver: int = CURRENT_SOLVER,
    ) -> CorrectionResult:
        """Correct faces: weights (B, S) in [0, 1] → :class:`CorrectionResult` (``solver``:
        the eq. 5 block solver, :data:`emogen.correct.solve.SOLVERS`)."""
        c = self.correctives
        core = np.array(weights, dtype=np.float64)
        eff = self.effective_weights(core)
        comb = activations(eff, c.drivers, c.driver_mask)
        b_n = len(core)
        col = np.zeros((b_n, c.n_collision))
        before = np.zeros((b_n, 2), dtype=np.int64)
        after = np.zeros((b_n, 2), dtype=np.int64)
        depth = np.zeros(b_n)
        iters = np.zeros(b_n, dtype=np.int64)
        if collisions and c.layout is not None and c.n_collision and b_n:
            for start in range(0, b_n, CHUNK):  # bounds the memory of the local vertices
                rows = slice(start, start + CHUNK)
                n = len(eff[rows])
                base = blend(
                    self._neutral, np.concatenate([eff[rows], comb[rows]], axis=1), self._base_rows
                )
                sol = solve_collisions(
                    base.reshape(n, -1, 3),
                    self._collision_local,
                    c.layout,
                    max_iterations=max_iterations,
                    solver=solver,
                )
                col[rows], before[rows], after[rows] = (
                    sol.weights,
                    sol.within_before,
                    sol.within_after,
                )
                depth[rows], iters[rows] = sol.depth_after, sol.iterations
        return CorrectionResult(
            shape_names=self.shape_names,
            combinational_names=c.combinational_names,
            collision_names=c.collision_names,
            core=core,
            weights=eff,
            combinational=comb,
            collision=col,
            within_before=before,
            within_after=after,
            remaining_depth=depth,
            iterations=iters,
        )

    @cached_property
    def corrective_rows(self) -> np.ndarray:
        """(C + 8, V·3) float32: every corrective's offsets, in ``names`` order."""
        c = self.correctives
        width = 3 * self.n_vertices
        rows = np.concatenate(
            [
                c.combinational_deltas.reshape(c.n_combinational, width),
                c.collision_deltas.reshape(c.n_collision, width),
            ]
        )
        rows.setflags(write=False)
        return rows

    def add_offsets(self, result: CorrectionResult, vertices: np.ndarray) -> None:
        """Add the correctives of ``result`` to its faces' ``vertices`` (B, V, 3) float32, in place.

        Faces whose corrective weights are all zero are not touched (bit for bit).
        """
        w = result.correctives.astype(np.float32)
        touched = np.flatnonzero(np.any(w != 0, axis=1))
        if len(touched) == 0 or w.shape[1] == 0:
            return
        flat = vertices.reshape(len(vertices), -1)
        for start in range(0, len(touched), 256):
            rows = touched[start : start + 256]
            flat[rows] += w[rows] @ self.corrective_rows
