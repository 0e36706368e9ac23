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
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Annotated

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from emogen.errors import ConfigError, ShapeError

DEFAULT_RIG = "ict_rig.toml"


class _Strict(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class GeneSpec(_Strict):
    name: str
    shapes: list[str] = Field(min_length=1)


class EyeSpec(_Strict):
    shapes: list[str]
    reason: str


class GazeSpec(_Strict):
    left_eyeball: str
    right_eyeball: str
    look_left: list[str]
    look_right: list[str]
    look_up: list[str]
    look_down: list[str]
    yaw_deg: Annotated[float, Field(ge=0, le=60)]
    pitch_up_deg: Annotated[float, Field(ge=0, le=60)]
    pitch_down_deg: Annotated[float, Field(ge=0, le=60)]


class EmotionSpec(_Strict):
    action_units: str
    core: list[str]
    optional: list[str] = []
    source: str


class IdentitySpec(_Strict):
    coefficients: list[float]
    description: str


class CorrectiveSpec(_Strict):
    name: str
    drivers: list[str] = Field(min_length=1)
    file: str | None = None
    description: str = ""


class DeriveSpec(_Strict):
    min_overlap: Annotated[float, Field(gt=0, le=2)]
    description: str = ""


class RigSpec(_Strict):
    name: str
    description: str = ""
    genes: list[GeneSpec] = []
    excluded: dict[str, str] = {}
    eye: EyeSpec | None = None
    gaze: GazeSpec | None = None
    emotions: dict[str, EmotionSpec] = {}
    identities: dict[str, IdentitySpec] = {}
    correctives: list[CorrectiveSpec] = []
    derive_correctives: DeriveSpec | None = None
    companions: dict[str, str] = {}


def _format_validation(exc: ValidationError, source: str) -> str:
    parts = []
    for err in exc.errors():
        loc = ".".join(str(p) for p in err["loc"])
        if err["type"] == "extra_forbidden":
            parts.append(f"unknown key '{loc}'")
        else:
            parts.append(f"'{loc}': {err['msg']} (got {err.get('input')!r})")
    return f"invalid rig {source}: " + "; ".join(parts)


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
        }


def read_rig_spec(path: Path | None = None) -> tuple[RigSpec, str]:
    """Parse a rig TOML (the packaged ICT default when ``path`` is None)."""
    if path is None:
        text = resources.files("emogen.data").joinpath(DEFAULT_RIG).read_text()
        source = f"(packaged {DEFAULT_RIG})"
    else:
        try:
            text = Path(path).read_text()
        except OSError as exc:
            raise ConfigError(f"cannot read rig file {path}: {exc.strerror}") from None
        source = str(path)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"rig {source} is not valid TOML: {exc}") from None
    try:
        return RigSpec.model_validate(data), source
    except ValidationError as exc:
        raise ConfigError(_format_validation(exc, source)) from None


def build_rig(spec: RigSpec, shape_names: tuple[str, ...], source: str = "") -> Rig:
    """Resolve a rig spec against a model's shape list; every name must exist."""
    known = set(shape_names)

    def check(names: list[str], where: str) -> None:
        bad = [n for n in names if n not in known]
        if bad:
            raise ConfigError(f"rig {source}: {where} names unknown shape(s) {bad}")

    grouped: dict[str, Gene] = {}
    claimed: set[str] = set()
    for g in spec.genes:
        check(g.shapes, f"gene '{g.name}'")
        grouped[g.name] = Gene(g.name, tuple(g.shapes))
        claimed.update(g.shapes)
    check(list(spec.excluded), "excluded")
    eye_shapes = set(spec.eye.shapes) if spec.eye else set()
    check(sorted(eye_shapes), "eye.shapes")
    overlap = claimed & set(spec.excluded)
    if overlap:
        raise ConfigError(
            f"rig {source}: shape(s) {sorted(overlap)} are both in a gene and excluded"
        )

    genes: list[Gene] = []
    seen: set[str] = set()
    for s in shape_names:
        if s in seen or s in spec.excluded:
            continue
        group = next((g for g in grouped.values() if s in g.shapes), None)
        if group is not None:
            gene = group
        elif s.endswith(("_L", "_R")) and f"{s[:-2]}_{'R' if s.endswith('_L') else 'L'}" in known:
            gene = Gene(s[:-2], (s[:-2] + "_L", s[:-2] + "_R"))
        else:
            gene = Gene(s, (s,))
        is_eye = bool(set(gene.shapes) & eye_shapes)
        if is_eye and not set(gene.shapes) <= eye_shapes:
            raise ConfigError(f"rig {source}: gene '{gene.name}' mixes eye and non-eye shapes")
        genes.append(Gene(gene.name, gene.shapes, is_eye))
        seen.update(gene.shapes)
    gene_names = {g.name for g in genes}

    emotions = {}
    for name, e in spec.emotions.items():
        bad = [b for b in (*e.core, *e.optional) if b not in gene_names]
        if bad:
            raise ConfigError(f"rig {source}: emotion '{name}' names unknown gene(s) {bad}")
        emotions[name] = Emotion(name, e.action_units, tuple(e.core), tuple(e.optional), e.source)

    gaze = None
    if spec.gaze is not None:
        gz = spec.gaze
        index = {s: i for i, s in enumerate(shape_names)}
        for key in ("look_left", "look_right", "look_up", "look_down"):
            check(getattr(gz, key), f"gaze.{key}")
        look = {
            k: np.array([index[s] for s in getattr(gz, k)])
            for k in ("look_left", "look_right", "look_up", "look_down")
        }
        gaze = Gaze(
            gz.left_eyeball,
            gz.right_eyeball,
            look["look_left"],
            look["look_right"],
            look["look_up"],
            look["look_down"],
            yaw=float(np.radians(gz.yaw_deg)),
            pitch_up=float(np.radians(gz.pitch_up_deg)),
            pitch_down=float(np.radians(gz.pitch_down_deg)),
        )
    correctives = []
    seen_names: set[str] = set()
    for c in spec.correctives:
        check(c.drivers, f"corrective '{c.name}' drivers")
        if c.name in known or c.name in seen_names:
            raise ConfigError(
                f"rig {source}: corrective name '{c.name}' is already a shape or corrective"
            )
        if len(set(c.drivers)) != len(c.drivers):
            raise ConfigError(f"rig {source}: corrective '{c.name}' repeats a driver {c.drivers}")
        if c.file is None and len(c.drivers) != 2:
            raise ConfigError(
                f"rig {source}: corrective '{c.name}' has no file, so it is derived from its "
                f"drivers' overlap, which needs exactly 2 drivers; got {len(c.drivers)}"
            )
        seen_names.add(c.name)
        file = None
        if c.file is not None:
            base = Path(source).parent if Path(source).is_file() else Path.cwd()
            file = str((base / c.file).resolve())
        correctives.append(Corrective(c.name, tuple(c.drivers), file, c.description))
    check(list(spec.companions), "companions")
    check(list(spec.companions.values()), "companions (leads)")
    for follower, lead in spec.companions.items():
        if follower == lead:
            raise ConfigError(f"rig {source}: companion '{follower}' cannot lead itself")
    return Rig(
        name=spec.name,
        shape_names=tuple(shape_names),
        genes=tuple(genes),
        excluded=dict(spec.excluded),
        eye_reason=spec.eye.reason if spec.eye else "",
        gaze=gaze,
        emotions=emotions,
        identities=dict(spec.identities),
        description=spec.description,
        correctives=tuple(correctives),
        derive_min_overlap=(
            spec.derive_correctives.min_overlap if spec.derive_correctives else None
        ),
        companions=dict(spec.companions),
    )


def load_rig(shape_names: tuple[str, ...], path: Path | None = None) -> Rig:
    spec, source = read_rig_spec(path)
    return build_rig(spec, shape_names, source)


# ---- a rig for models that come without one (imported GLBs) ---------------------------------
_SIDE_SUFFIXES = (("_L", "_R"), ("Left", "Right"))  # ICT-FaceKit style, ARKit style


def _strip_side(name: str) -> str:
    for left, right in _SIDE_SUFFIXES:
        for suffix in (left, right):
            if name.endswith(suffix) and len(name) > len(suffix):
                return name[: -len(suffix)]
    return name


def generic_rig(shape_names: tuple[str, ...], name: str = "generic") -> Rig:
    """A rig built from shape names alone, for models without a rig file.

    Left/right twins are one gene each: ``X_L``/``X_R`` and ARKit's ``XLeft``/``XRight``
    (``eyeBlinkLeft`` + ``eyeBlinkRight`` → gene ``eyeBlink``). As in the ICT rig, horizontal
    gaze is grouped conjugately (``eyeLookOut`` of one eye with ``eyeLookIn`` of the other), the
    ICT rig's exclusions (lateral jaw/mouth shifts, ``mouthClose``) and companions apply to
    shapes of the same name, its rule for derived correctives applies, and eye shapes (blink,
    look, pupil) are switched off with eye motion. No emotions, gaze rotation or identities.
    """
    ict, _ = read_rig_spec(None)
    known = set(shape_names)
    excluded = {s: reason for s, reason in ict.excluded.items() if s in known}
    genes: list[GeneSpec] = []
    for left, right in _SIDE_SUFFIXES:
        out_l, in_r, out_r, in_l = (
            f"eyeLook{d}{s}"
            for d, s in (("Out", left), ("In", right), ("Out", right), ("In", left))
        )
        if {out_l, in_r, out_r, in_l} <= known - set(excluded):
            genes += [
                GeneSpec(name="eyeLookLeft", shapes=[out_l, in_r]),
                GeneSpec(name="eyeLookRight", shapes=[out_r, in_l]),
            ]
    claimed = {s for g in genes for s in g.shapes}
    left, right = _SIDE_SUFFIXES[1]
    for s in shape_names:  # ARKit twins (build_rig pairs X_L/X_R itself)
        twin = s[: -len(left)] + right if s.endswith(left) else ""
        if twin in known and not {s, twin} & (claimed | set(excluded)):
            base = s[: -len(left)]
            genes.append(
                GeneSpec(
                    name=base if base not in known else f"{base}{left}{right}", shapes=[s, twin]
                )
            )
    eye_bases = {_strip_side(s) for s in ict.eye.shapes} if ict.eye else set()
    eye_shapes = [s for s in shape_names if _strip_side(s) in eye_bases]
    spec = RigSpec(
        name=name,
        description=f"Generic rig derived from {len(shape_names)} shape names (left/right twins paired).",
        genes=genes,
        excluded=excluded,
        eye=EyeSpec(shapes=eye_shapes, reason=ict.eye.reason) if ict.eye and eye_shapes else None,
        derive_correctives=ict.derive_correctives,
        companions={f: lead for f, lead in ict.companions.items() if {f, lead} <= known},
    )
    return build_rig(spec, tuple(shape_names), f"(generic rig '{name}')")
