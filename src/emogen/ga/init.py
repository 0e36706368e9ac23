"""Generation 0 (Section III-C): protocol-generated or fixed (read from a file of sets)."""

from __future__ import annotations

import tomllib
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from emogen.config import GAConfig, format_validation_error
from emogen.errors import ConfigError, EmoGenError
from emogen.model.rig import Rig

DEFAULT_FIXED_INIT = "fixed_init.toml"
NEUTRAL = "init_neutral"
ARBITRARY = "init_arbitrary"
FIXED = "init_fixed"


def emotion_label(emotion: str) -> str:
    return f"init_{emotion}"


# ---- protocol generation ------------------------------------------------------------------
@dataclass(frozen=True)
class _Protocol:
    """What protocol initialisation draws from, worked out once for a rig and its settings:
    each emotion face's (core, optional) gene blocks, the labels before shuffling."""

    blocks: tuple[tuple[np.ndarray, np.ndarray], ...]
    n_genes: int
    lo: int
    hi: int
    arbitrary: int
    labels: np.ndarray

    def draw(self, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """(genes (n_faces, n_genes) before shuffling, the shuffling permutation) of one
        population, drawn from ``rng`` in the documented order (:func:`protocol_init`)."""
        lo, hi = self.lo, self.hi
        genes = np.zeros((len(self.labels), self.n_genes))
        face = 0
        for core, optional in self.blocks:
            n = int(rng.integers(lo, hi + 1))
            order = np.concatenate((rng.permutation(core), rng.permutation(optional)))[:n]
            genes[face, order] = rng.random(len(order))
            face += 1
        for _ in range(self.arbitrary):
            n = int(rng.integers(lo, hi + 1))
            chosen = rng.choice(self.n_genes, size=min(n, self.n_genes), replace=False)
            genes[face, chosen] = rng.random(len(chosen))
            face += 1
        return genes, rng.permutation(len(self.labels))


def _protocol(
    rig: Rig,
    eye_motion: bool,
    activation_range: tuple[int, int],
    emotions: tuple[str, ...],
    faces_per_emotion: int,
    arbitrary: int,
) -> _Protocol:
    lo, hi = activation_range
    if not 1 <= lo <= hi:
        raise ConfigError(f"activation_range must be [lo, hi] with 1 <= lo <= hi; got {lo}-{hi}")
    names = rig.gene_names(eye_motion)
    index = {g: i for i, g in enumerate(names)}
    blocks, labels = [], []
    for emotion in emotions:
        if emotion not in rig.emotions:
            raise ConfigError(
                f"init.emotions: unknown emotion '{emotion}'; rig '{rig.name}' defines: "
                f"{', '.join(rig.emotions) or 'none'}"
            )
        spec = rig.emotions[emotion]
        core = np.array([index[g] for g in spec.core if g in index], dtype=np.int64)
        optional = np.array([index[g] for g in spec.optional if g in index], dtype=np.int64)
        blocks += [(core, optional)] * faces_per_emotion
        labels += [emotion_label(emotion)] * faces_per_emotion
    labels += [ARBITRARY] * arbitrary + [NEUTRAL]
    return _Protocol(tuple(blocks), len(names), lo, hi, arbitrary, np.asarray(labels))


def protocol_init(
    rig: Rig,
    *,
    eye_motion: bool = True,
    activation_range: tuple[int, int] = (3, 8),
    emotions: tuple[str, ...] = ("happy", "sad", "angry", "fearful"),
    faces_per_emotion: int = 2,
    arbitrary: int = 1,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray]:
    """A protocol-generated initial population, shuffled.

    Returns genes : (n_faces, n_genes) float with n_faces = len(emotions) × faces_per_emotion
    + arbitrary + 1, and labels : (n_faces,) str (``init_happy``, ``init_arbitrary``,
    ``init_neutral``, …) saying what made each face.

    * Emotion faces: n ~ U{lo..hi} unique core shapes (genes). They are taken from the
      emotion's building blocks in the rig — its core genes first, in random order, then its
      optional ones, in random order — up to n; values U(0,1). n is **capped** at the number of
      the emotion's blocks (8 for happy, sad and fearful, 10 for angry in the ICT rig), so a
      range such as 8-16 gives every emotion face all its blocks. With eye motion off, blocks
      that are eye genes are skipped (and do not count).
    * Arbitrary faces: n ~ U{lo..hi} genes drawn without replacement from all active genes
      (capped at their number), values U(0,1).
    * One neutral face (all zeros).

    Draw order: per face in the order above, n, then the block order (core, then optional) or
    the gene indices, then the values; finally the permutation that shuffles the slots.
    """
    plan = _protocol(rig, eye_motion, activation_range, emotions, faces_per_emotion, arbitrary)
    genes, perm = plan.draw(rng)
    return genes[perm], plan.labels[perm]


# ---- fixed sets ----------------------------------------------------------------------------
class _Strict(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class FixedSet(_Strict):
    description: str = ""
    faces: list[dict[str, float]] = Field(min_length=1)


class FixedInitFile(_Strict):
    description: str = ""
    sets: list[FixedSet] = Field(min_length=1)


def _face_genes(rig: Rig, named: dict[str, float], where: str) -> np.ndarray:
    """Named weights (genes or shapes) → the full gene vector, checking symmetry."""
    try:
        weights = rig.weights_from_names(named)[None]
    except EmoGenError as exc:
        raise ConfigError(f"{where}: {exc}") from None
    shape_index = {s: i for i, s in enumerate(rig.shape_names)}
    for shape in named:
        if shape in rig.excluded and weights[0, shape_index[shape]] != 0:
            raise ConfigError(
                f"{where}: shape '{shape}' is not evolved ({rig.excluded[shape]}); remove it"
            )
    for gene in rig.genes:
        values = {s: float(weights[0, shape_index[s]]) for s in gene.shapes}
        if len(set(values.values())) > 1:
            raise ConfigError(
                f"{where}: gene '{gene.name}' has unequal weights on its shapes {values}; "
                f"faces are symmetric, so name the gene ('{gene.name} = …') instead"
            )
    genes: np.ndarray = rig.contract(weights, True)[0]
    return genes


def read_fixed_sets(
    path: Path | None, rig: Rig, *, eye_motion: bool = True, population_size: int = 10
) -> np.ndarray:
    """Every set of a fixed-initialisation file, as genes (n_sets, population_size, n_genes).

    The file (TOML) holds ``[[sets]]`` tables, each with ``faces = [{jawOpen = 0.5, …}, …]``
    (one inline table of gene or shape weights per face; a left/right pair must be equal, an
    excluded shape must not appear). ``path`` None reads the packaged sample. With eye motion
    off, eye genes in the file are dropped (the study disabled them).
    """
    if path is None:
        text = resources.files("emogen.data").joinpath(DEFAULT_FIXED_INIT).read_text()
        source = f"(packaged {DEFAULT_FIXED_INIT})"
    else:
        try:
            text = Path(path).read_text()
        except OSError as exc:
            raise ConfigError(
                f"cannot read fixed initialisation file {path}: {exc.strerror}"
            ) from None
        source = str(path)
    try:
        spec = FixedInitFile.model_validate(tomllib.loads(text))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"fixed initialisation {source} is not valid TOML: {exc}") from None
    except ValidationError as exc:
        raise ConfigError(format_validation_error(exc, source)) from None
    all_names = rig.gene_names(True)
    keep = [all_names.index(g) for g in rig.gene_names(eye_motion)]
    sets = []
    for s_i, fixed in enumerate(spec.sets, start=1):
        if len(fixed.faces) != population_size:
            raise ConfigError(
                f"{source}: set {s_i} has {len(fixed.faces)} faces; the population has "
                f"{population_size} (population_size)"
            )
        faces = [
            _face_genes(rig, face, f"{source}: set {s_i} face {f_i}")
            for f_i, face in enumerate(fixed.faces, start=1)
        ]
        sets.append(np.stack(faces)[:, keep])
    return np.stack(sets)


def fixed_init(
    sets: np.ndarray, option: int | None, *, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, int]:
    """One fixed set: ``option`` (numbered from 1) or, if None, one drawn uniformly.

    sets : (n_sets, n_faces, n_genes). Returns (genes (n_faces, n_genes), labels, option).
    """
    if option is None:
        option = int(rng.integers(len(sets))) + 1
    if not 1 <= option <= len(sets):
        raise ConfigError(f"init.fixed_option must be in [1, {len(sets)}]; got {option}")
    genes = sets[option - 1].copy()
    return genes, np.full(len(genes), FIXED), option


def first_generations(
    config: GAConfig,
    rig: Rig,
    fixed_sets: np.ndarray | None,
    *,
    rngs: Sequence[np.random.Generator],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Generation 0 of R runs as ``config.init`` says, run r from ``rngs[r]``: one of the
    ``fixed_sets`` (when given; see :func:`fixed_init`) or protocol initialisation (the set
    of building blocks worked out once, then each run's draws). Returns (genes (R, N, K),
    labels (R, N), fixed options (R,), −1 for protocol populations)."""
    init = config.init
    if fixed_sets is not None:
        made = [fixed_init(fixed_sets, init.fixed_option, rng=rng) for rng in rngs]
        n = fixed_sets.shape[1]
        return (
            np.array([m[0] for m in made]).reshape(len(made), *fixed_sets.shape[1:]),
            np.array([m[1] for m in made], dtype=str).reshape(len(made), n),
            np.array([m[2] for m in made], dtype=np.int64),
        )
    plan = _protocol(
        rig,
        config.eye_motion,
        init.activation_range,
        init.emotions,
        init.faces_per_emotion,
        config.arbitrary_faces(),
    )
    drawn = [plan.draw(rng) for rng in rngs]
    perms = np.array([d[1] for d in drawn], dtype=np.int64).reshape(len(drawn), -1)
    genes = np.array([d[0] for d in drawn]).reshape(len(drawn), *perms.shape[1:], plan.n_genes)
    genes = np.take_along_axis(genes, perms[:, :, None], axis=1)
    return genes, plan.labels[perms], np.full(len(drawn), -1, dtype=np.int64)


def first_generation(
    config: GAConfig, rig: Rig, fixed_sets: np.ndarray | None, *, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, int]:
    """Generation 0 of one run (:func:`first_generations` of one): (genes, labels, fixed
    option, or −1 for a protocol population)."""
    genes, labels, options = first_generations(config, rig, fixed_sets, rngs=[rng])
    return genes[0], labels[0], int(options[0])
