"""The per-identity correctors a study's faces are corrected with (:class:`StudyCorrectors`);
a face's full weights are :mod:`emogen.tasks.weights`."""

from __future__ import annotations

from typing import TYPE_CHECKING

from emogen.errors import ConfigError
from emogen.ga.engine import Corrector, Engine, correctives_of
from emogen.model.rig import Rig
from emogen.study.config import StudyConfig
from emogen.tasks.weights import Floats, full_weights, weight_names

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

__all__ = ["Floats", "StudyCorrectors", "face_weight_names", "full_weights", "weight_names"]


class StudyCorrectors:
    """One corrector per identity shape and collision solver (``correctives_of`` the model with
    the shape of the study's identity of that name; identities that share a shape share it),
    made on first use; none when the study does not correct faces. ``solver``: the eq. 5 block solver a trial was
    recorded with (:func:`emogen.ga.state.collision_solver_of_state`; default the current)."""

    def __init__(self, config: StudyConfig, model: FaceModel | None) -> None:
        if config.correct and model is None:
            raise ConfigError(
                "the study corrects faces (correct = true): the server needs the face model "
                "(pass model=…), or set correct = false"
            )
        self.config = config
        self.model = model if config.correct else None
        self._models: dict[str | tuple[float, ...], FaceModel] = {}
        self._made: dict[tuple[str | tuple[float, ...], int], Corrector] = {}

    def __call__(self, identity: str, solver: int | None = None) -> Corrector | None:
        if self.model is None:
            return None
        if solver is None:
            from emogen.solvers import CURRENT_SOLVER

            solver = CURRENT_SOLVER
        shape = self.config.identity_of(identity).shape
        if (shape, solver) not in self._made:
            if shape not in self._models:
                self._models[shape] = (
                    self.model if shape == "generic" else self.model.with_identity(shape)
                )
            self._made[(shape, solver)] = correctives_of(self._models[shape], solver)
        return self._made[(shape, solver)]


def face_weight_names(config: StudyConfig, rig: Rig, correctors: StudyCorrectors) -> list[str]:
    """The names of a study's face weights (the model's shapes, then the correctives of a
    corrected study), from a probe generation of the GA on the generic identity."""
    probe = Engine(config.ga_for("generic"), rig, 0, corrector=correctors("generic")).ask()
    return weight_names(probe, rig)
