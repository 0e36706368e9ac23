"""Simulated conditions of the replication: one GA configuration toward one target, many runs
(a :class:`Condition`), and simulated participants each evolving their own internal target.

Every condition uses the replication's one seed (common random numbers: conditions differ only
by their settings); a condition asked for twice is simulated once.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from emogen.analysis.elites import simulate_elites, simulate_participants
from emogen.analysis.paper_targets import participant_target
from emogen.analysis.replication.settings import ReplicateSettings
from emogen.config import PAPER_SELECTIONS, GAConfig, InitConfig, MetricConfig, SimulationConfig
from emogen.metrics import cosine_distance
from emogen.rng import spawn_seeds

if TYPE_CHECKING:
    from emogen.model.face import FaceModel
    from emogen.model.rig import Rig


@dataclass(frozen=True, eq=False)
class Condition:
    """One simulated condition: errors (R, G+1) of the elites, final faces (R, S), the best
    initial option's error (R,), the target (S,)."""

    label: str
    errors: np.ndarray
    final: np.ndarray
    best_initial: np.ndarray
    target: np.ndarray
    fixed_options: np.ndarray

    @property
    def final_errors(self) -> np.ndarray:
        return self.errors[:, -1]

    def stats(self, g: int = -1) -> tuple[float, float]:
        """μ, σ of the elites' error in generation ``g``."""
        e = self.errors[:, g]
        return float(e.mean()), float(e.std(ddof=1))

    @property
    def mean_face(self) -> np.ndarray:
        return np.asarray(self.final.mean(axis=0))

    @property
    def mean_face_cd(self) -> float:
        """CD of the mean final face to the target."""
        return float(cosine_distance(self.mean_face, self.target))


@dataclass(frozen=True)
class ConditionSpec:
    """A condition's GA settings beyond the replication's defaults (protocol initialisation
    with 3–8 active genes, the paper's selections, EmoGen's GA, a noiseless CD observer).
    ``training`` / ``training_weights``: the empirical metrics' training set (file, (n, S))."""

    metric: str = "cd"
    init: str = "protocol"
    fixed_option: int | None = None
    activation_range: tuple[int, int] = (3, 8)
    selections: tuple[int, ...] = PAPER_SELECTIONS
    variant: str = "emogen"
    training: Path | None = None
    runs: int | None = None
    noise: float = 0.0
    correct: bool = False
    training_weights: np.ndarray | None = field(default=None, compare=False)

    def key(self) -> tuple[object, ...]:
        """What identifies the simulation (the training weights are the training file's)."""
        return (
            self.metric,
            self.init,
            self.fixed_option,
            self.activation_range,
            self.selections,
            self.variant,
            None if self.training is None else str(self.training),
            self.runs,
            self.noise,
            self.correct,
        )


@dataclass(frozen=True)
class ParticipantFaces:
    """Simulated participants' faces (count, S) — final elites, or (count, G, S) the elites of
    generations 1…G — and their internal targets (count, S)."""

    faces: np.ndarray
    targets: np.ndarray


@dataclass(eq=False)
class ConditionRunner:
    """Simulates conditions and simulated participants on ``model`` with ``settings``."""

    model: FaceModel
    settings: ReplicateSettings
    _cache: dict[tuple[object, ...], Condition] = field(default_factory=dict, repr=False)

    @property
    def rig(self) -> Rig:
        return self.model.rig

    def weights(self, named: dict[str, float]) -> np.ndarray:
        """Full weights (S,) of named shape or gene weights."""
        return np.asarray(self.rig.weights_from_names(named), dtype=np.float64)

    def config(self, target: dict[str, float], spec: ConditionSpec) -> SimulationConfig:
        init_cfg = {
            "kind": spec.init,
            "fixed_option": spec.fixed_option,
            "activation_range": spec.activation_range,
        }
        metric_cfg: dict[str, object] = {"name": spec.metric}
        if spec.training is not None:
            metric_cfg["training"] = spec.training
        return SimulationConfig.model_validate(
            {
                "ga": GAConfig.model_validate(
                    {"variant": spec.variant, "init": InitConfig.model_validate(init_cfg)}
                ),
                "target": target,
                "runs": spec.runs or self.settings.runs,
                "seed": self.settings.seed,
                "selections": spec.selections,
                "metric": MetricConfig.model_validate(metric_cfg),
                "noise_temperature": spec.noise,
                "correct": spec.correct,
            }
        )

    def condition(
        self, label: str, target: dict[str, float], spec: ConditionSpec | None = None
    ) -> Condition:
        """Simulate (or fetch) ``settings.runs`` runs toward ``target`` under ``spec``."""
        from emogen.simulate import build_problem

        spec = spec or ConditionSpec()
        key = (tuple(sorted(target.items())), spec.key())
        if key in self._cache:
            return self._cache[key]
        cfg = self.config(target, spec)
        problem = build_problem(cfg, self.model, all_weights=True, training=spec.training_weights)
        seeds = np.array(spawn_seeds(cfg.seed or 0, cfg.runs), dtype=np.int64)
        elites = simulate_elites(problem, np.arange(cfg.runs), seeds)
        found = Condition(
            label=label,
            errors=elites.errors,
            final=elites.final,
            best_initial=elites.best_initial,
            target=np.asarray(problem.target, dtype=np.float64),
            fixed_options=elites.fixed_options,
        )
        self._cache[key] = found
        return found

    def participants(
        self,
        emotion: str,
        count: int,
        *,
        seed: int,
        init: str = "protocol",
        every_generation: bool = False,
    ) -> ParticipantFaces:
        """Simulated participants evolving ``emotion``, each toward their own internal target
        (:func:`~emogen.analysis.paper_targets.participant_target`) with choice noise; final
        elites, or with ``every_generation`` the elites of generations 1…G."""
        from emogen.simulate import build_problem

        rng = np.random.default_rng(seed)
        spec = ConditionSpec(init=init, runs=1, noise=self.settings.participant_noise)
        cfg = self.config({"jawOpen": 1.0}, spec).model_copy(update={"seed": seed})
        problem = build_problem(cfg, self.rig, all_weights=True)
        targets = np.stack(
            [self.weights(participant_target(self.rig, emotion, rng=rng)) for _ in range(count)]
        )
        runs = simulate_participants(problem, targets, spawn_seeds(seed, count))
        faces = [e.weights[0, 1:] if every_generation else e.final[0] for e in runs]
        return ParticipantFaces(np.stack(faces), targets)
