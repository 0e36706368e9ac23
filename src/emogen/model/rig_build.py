"""Building a :class:`~emogen.model.rig.Rig`: a rig spec (TOML) resolved against a model's
shape list (:func:`build_rig`, :func:`load_rig`), or a rig from shape names alone
(:func:`generic_rig`, for models that come without a rig file)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from emogen.errors import ConfigError
from emogen.model.rig import Corrective, Emotion, Gaze, Gene, Rig
from emogen.model.rig_spec import EyeSpec, GeneSpec, RigSpec, read_rig_spec


def build_rig(spec: RigSpec, shape_names: tuple[str, ...], source: str = "") -> Rig:
    """Resolve a rig spec against a model's shape list; every name must exist."""
    check = _name_checker(set(shape_names), source)
    genes = _resolve_genes(spec, shape_names, source, check)
    emotions = _resolve_emotions(spec, {g.name for g in genes}, source)
    gaze = _resolve_gaze(spec, shape_names, check)
    correctives = _resolve_correctives(spec, set(shape_names), source, check)
    _check_companions(spec, source, check)
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
        correctives=correctives,
        derive_min_overlap=(
            spec.derive_correctives.min_overlap if spec.derive_correctives else None
        ),
        companions=dict(spec.companions),
        reach_version=spec.reach.version if spec.reach else None,
    )


#: ``check(names, where)`` raises a ConfigError naming the rig, ``where`` and the unknown shapes.
_Check = Callable[[list[str], str], None]


def _name_checker(known: set[str], source: str) -> _Check:
    def check(names: list[str], where: str) -> None:
        bad = [n for n in names if n not in known]
        if bad:
            raise ConfigError(f"rig {source}: {where} names unknown shape(s) {bad}")

    return check


def _resolve_genes(
    spec: RigSpec, shape_names: tuple[str, ...], source: str, check: _Check
) -> list[Gene]:
    """Genes in the model's shape order: declared groups, then left/right pairs, then singles."""
    known = set(shape_names)
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
    return genes


def _resolve_emotions(spec: RigSpec, gene_names: set[str], source: str) -> dict[str, Emotion]:
    """The emotions' building blocks; every block must be a gene."""
    emotions = {}
    for name, e in spec.emotions.items():
        bad = [b for b in (*e.core, *e.optional) if b not in gene_names]
        if bad:
            raise ConfigError(f"rig {source}: emotion '{name}' names unknown gene(s) {bad}")
        emotions[name] = Emotion(name, e.action_units, tuple(e.core), tuple(e.optional), e.source)
    return emotions


def _resolve_gaze(spec: RigSpec, shape_names: tuple[str, ...], check: _Check) -> Gaze | None:
    """Eyeball rotation: the look shapes as indices into the shape list, angles in radians."""
    if spec.gaze is None:
        return None
    gz = spec.gaze
    index = {s: i for i, s in enumerate(shape_names)}
    for key in ("look_left", "look_right", "look_up", "look_down"):
        check(getattr(gz, key), f"gaze.{key}")
    look = {
        k: np.array([index[s] for s in getattr(gz, k)])
        for k in ("look_left", "look_right", "look_up", "look_down")
    }
    return Gaze(
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


def _resolve_correctives(
    spec: RigSpec, known: set[str], source: str, check: _Check
) -> tuple[Corrective, ...]:
    """Declared correctives, their files made absolute (relative to the rig file)."""
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
    return tuple(correctives)


def _check_companions(spec: RigSpec, source: str, check: _Check) -> None:
    check(list(spec.companions), "companions")
    check(list(spec.companions.values()), "companions (leads)")
    for follower, lead in spec.companions.items():
        if follower == lead:
            raise ConfigError(f"rig {source}: companion '{follower}' cannot lead itself")


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
