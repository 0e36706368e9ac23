"""The rig: how a model's blendshapes are controlled and evolved.

A rig (TOML; ``emogen/data/ict_rig.toml`` is the default for ICT-FaceKit) declares

* **genes**, the unique core controls the GA evolves. A left/right pair (``X_L``/``X_R``) is one
  gene ``X`` written equally to both sides; explicit groups override the automatic pairing
  (ICT's horizontal gaze: ``eyeLookLeft`` drives ``eyeLookOut_L`` and ``eyeLookIn_R``, so both eyes
  turn the same way);
* **excluded** shapes, never evolved, each with its reason;
* **eye** shapes, evolved only while eye motion is enabled;
* **emotions**: building blocks (genes) from FACS/EMFACS prototypes for protocol initialisation;
* **gaze**: rigid eyeball rotation driven by the ``eyeLook*`` weights (ICT's shapes move the lids
  but not the eyeballs);
* **identities**: named identity-coefficient presets;
* **correctives**: combinational corrective shapes, each activated by the product of its driver
  shapes' weights (``[[correctives]]``: name, drivers, optional ``file`` — an OBJ, or a GLB with a
  morph target of that name — relative to the rig file; without a file the shape is derived
  from the geometry by the double-counting rule of :mod:`emogen.correct.combinational`), and
  ``[derive_correctives] min_overlap`` to derive one for every pair of shapes whose overlap
  score reaches it;
* **companions**: shapes meaningful only with another (``mouthClose = "jawOpen"``): their
  effective weight is capped at their lead's.

This module holds the resolved rig (:class:`Rig`: genes ↔ shapes) and its parts;
:mod:`emogen.model.rig_spec` the TOML schema and reading it; :mod:`emogen.model.rig_build`
building a rig from a spec (:func:`~emogen.model.rig_build.load_rig`) or from shape names alone
(:func:`~emogen.model.rig_build.generic_rig`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from emogen.errors import ConfigError, ShapeError
from emogen.model.rig_spec import IdentitySpec


@dataclass(frozen=True)
class Gene:
    name: str
    shapes: tuple[str, ...]
    eye: bool = False


@dataclass(frozen=True)
class Gaze:
    left_eyeball: str
    right_eyeball: str
    look_left: np.ndarray  # indices into the shape list
    look_right: np.ndarray
    look_up: np.ndarray
    look_down: np.ndarray
    yaw: float  # radians at full weight
    pitch_up: float
    pitch_down: float

    def angles(self, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Conjugate gaze (yaw toward the subject's left, pitch up) in radians, per face.

        weights : (n_faces, n_shapes). Both eyes get the same rotation.
        """
        h = weights[:, self.look_left].mean(1) - weights[:, self.look_right].mean(1)
        up = weights[:, self.look_up].mean(1)
        down = weights[:, self.look_down].mean(1)
        return h * self.yaw, up * self.pitch_up - down * self.pitch_down


@dataclass(frozen=True)
class Emotion:
    name: str
    action_units: str
    core: tuple[str, ...]
    optional: tuple[str, ...]
    source: str

    @property
    def blocks(self) -> tuple[str, ...]:
        return self.core + self.optional


@dataclass(frozen=True)
class Corrective:
    """A declared combinational corrective: activation = product of the drivers' weights.

    ``file``: an absolute path to the artist's shape (OBJ, or GLB with a morph target named
    ``name``); None: derived from the geometry (double-counting rule).
    """

    name: str
    drivers: tuple[str, ...]
    file: str | None = None
    description: str = ""


@dataclass(frozen=True)
class Rig:
    """Controls of a face model. Gene order is the rig's; shape order is the model's."""

    name: str
    shape_names: tuple[str, ...]
    genes: tuple[Gene, ...]
    excluded: dict[str, str]
    eye_reason: str
    gaze: Gaze | None
    emotions: dict[str, Emotion]
    identities: dict[str, IdentitySpec]
    description: str = ""
    _expansion: dict[bool, np.ndarray] = field(default_factory=dict, repr=False, compare=False)
    correctives: tuple[Corrective, ...] = ()
    derive_min_overlap: float | None = None
    companions: dict[str, str] = field(default_factory=dict)
    #: version of the derived reach shapes (:mod:`emogen.correct.reach`); None: none (rig 1)
    reach_version: int | None = None

    # ---- gene space -------------------------------------------------------------------
    def gene_names(self, eye_motion: bool = True) -> tuple[str, ...]:
        """The unique core shapes the GA evolves (eye genes only with eye motion)."""
        return tuple(g.name for g in self.genes if eye_motion or not g.eye)

    def active_genes(self, eye_motion: bool = True) -> tuple[Gene, ...]:
        return tuple(g for g in self.genes if eye_motion or not g.eye)

    @property
    def pairs(self) -> tuple[tuple[str, str], ...]:
        """Left/right shape pairs (``X_L``, ``X_R``) present in the model."""
        names = set(self.shape_names)
        return tuple(
            (s, s[:-2] + "_R")
            for s in self.shape_names
            if s.endswith("_L") and s[:-2] + "_R" in names
        )

    def disabled_shapes(self, eye_motion: bool = True) -> dict[str, str]:
        """Shapes never written by :meth:`expand`, with the reason for each."""
        out = dict(self.excluded)
        if not eye_motion:
            for g in self.genes:
                if g.eye:
                    out.update({s: self.eye_reason for s in g.shapes})
        return out

    def expansion_matrix(self, eye_motion: bool = True) -> np.ndarray:
        """(n_genes, n_shapes) 0/1 matrix: full weights = genes @ E."""
        if eye_motion not in self._expansion:
            index = {s: i for i, s in enumerate(self.shape_names)}
            genes = self.active_genes(eye_motion)
            e = np.zeros((len(genes), len(self.shape_names)))
            for g_i, g in enumerate(genes):
                e[g_i, [index[s] for s in g.shapes]] = 1.0
            e.setflags(write=False)
            self._expansion[eye_motion] = e
        return self._expansion[eye_motion]

    def expand(self, genes: np.ndarray, eye_motion: bool = True) -> np.ndarray:
        """Gene vectors (n_faces, n_genes) → full weight vectors (n_faces, n_shapes).

        Every shape of a gene gets the gene's value (symmetry); excluded shapes get 0.
        """
        genes = np.asarray(genes, dtype=np.float64)
        e = self.expansion_matrix(eye_motion)
        if genes.ndim != 2 or genes.shape[1] != e.shape[0]:
            raise ShapeError(
                f"genes must have shape (n_faces, {e.shape[0]}) for rig '{self.name}' "
                f"(eye_motion={eye_motion}); got {genes.shape}"
            )
        return genes @ e

    def contract(self, weights: np.ndarray, eye_motion: bool = True) -> np.ndarray:
        """Full weights (n_faces, n_shapes) → genes (n_faces, n_genes); inverse of :meth:`expand`.

        A gene is the mean of its shapes' weights (exact for symmetric faces).
        """
        weights = np.asarray(weights, dtype=np.float64)
        e = self.expansion_matrix(eye_motion)
        if weights.ndim != 2 or weights.shape[1] != e.shape[1]:
            raise ShapeError(
                f"weights must have shape (n_faces, {e.shape[1]}); got {weights.shape}"
            )
        return (weights @ e.T) / e.sum(1)

    def gene_index(self, name: str, eye_motion: bool = True) -> int:
        names = self.gene_names(eye_motion)
        if name not in names:
            raise ShapeError(f"unknown gene '{name}'; genes are: {', '.join(names)}")
        return names.index(name)

    def weights_from_names(self, named: dict[str, float]) -> np.ndarray:
        """A full weight vector (n_shapes,) from ``{shape or gene name: value}``."""
        w = np.zeros(len(self.shape_names))
        index = {s: i for i, s in enumerate(self.shape_names)}
        genes = {g.name: g for g in self.genes}
        for key, value in named.items():
            if not 0.0 <= float(value) <= 1.0:
                raise ConfigError(f"weight of '{key}' must be in [0, 1]; got {value}")
            if key in index:
                w[index[key]] = value
            elif key in genes:
                w[[index[s] for s in genes[key].shapes]] = value
            else:
                raise ShapeError(
                    f"unknown shape or gene '{key}'; shapes are: {', '.join(self.shape_names)}"
                )
        return w

    def summary(self) -> dict[str, object]:
        return {
            "name": self.name,
            "genes": [{"name": g.name, "shapes": list(g.shapes), "eye": g.eye} for g in self.genes],
            "pairs": [list(p) for p in self.pairs],
            "excluded": self.excluded,
            "eye_shapes_disabled_without_eye_motion": sorted(
                s for g in self.genes if g.eye for s in g.shapes
            ),
            "emotions": {
                k: {
                    "action_units": e.action_units,
                    "core": list(e.core),
                    "optional": list(e.optional),
                }
                for k, e in self.emotions.items()
            },
            "identities": sorted(self.identities),
            "correctives": [
                {"name": c.name, "drivers": list(c.drivers), "file": c.file}
                for c in self.correctives
            ],
            "derive_correctives": self.derive_min_overlap,
            "companions": dict(self.companions),
            "reach": self.reach_version,
        }

    def corrective_settings(self) -> dict[str, object]:
        """What the combinational correctives are built from (JSON-ready, for cache keys)."""
        return {
            "correctives": [
                {"name": c.name, "drivers": list(c.drivers), "file": c.file}
                for c in self.correctives
            ],
            "derive_min_overlap": self.derive_min_overlap,
            "companions": dict(sorted(self.companions.items())),
            "reach": self.reach_version,
        }
