"""Identities: a shape (the rig's identity preset or coefficients) plus an appearance.

Six ready presets cross two sexes with three Monk skin tones (light 2, medium 5, dark 8);
``female-dark-v3`` and ``male-dark-v3`` are the dark ones for new studies: readable lips (as
``-v2``) and anger's furrows as visible as on the light presets. ``female-light-long``,
``female-medium-long`` and ``female-dark-v3-long`` are those female faces framed by long hair.
The rig's shape-only names keep working — ``generic``, ``male``, ``female`` — with a default
appearance of their sex at the medium tone. A lab defines its own in the study TOML::

    [identity.participant_match]
    shape = "female"            # generic | male | female | a list of identity coefficients
    skin_tone = 6.5             # Monk Skin Tone scale 1-10
    brow_colour = "#3a2a20"
    hair = "short"
    beard_shadow = 0.0
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict

from emogen.appearance.params import Appearance, appearance_from_dict
from emogen.errors import ConfigError

TONES = {"light": 2.0, "medium": 5.0, "dark": 8.0}


class Identity(BaseModel):
    """What a participant sees: a face shape and its appearance."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    shape: str | tuple[float, ...] = "generic"
    appearance: Appearance = Appearance()

    def record(self) -> dict[str, Any]:
        """Everything needed to re-render a stimulus of this identity exactly."""
        shape = self.shape if isinstance(self.shape, str) else list(self.shape)
        return {"shape": shape, "appearance": self.appearance.record()}


def _female(tone: float) -> Appearance:
    return Appearance(
        skin_tone=tone,
        brow_thickness=0.8,
        brow_density=0.9,
        hairline=1.0,
        lip_colour=1.15,
        redness=1.1,
        brow_colour="#2e221b" if tone < 4 else "#1e1713",
        hair_colour="#3b2a1e" if tone < 4 else "#1a1411",
    )


def _male(tone: float) -> Appearance:
    return Appearance(
        skin_tone=tone,
        brow_thickness=1.15,
        brow_density=1.1,
        hairline=1.12,
        beard_shadow=0.8,
        lip_colour=0.85,
        brow_colour="#2b2019" if tone < 4 else "#1c1612",
        hair_colour="#33261c" if tone < 4 else "#18120f",
    )


# Versioned dark presets for new studies (docs/appearance.md, Contrast): -v2, the lips and brows
# as readable against the skin as on the light presets (≥ 0.7 × their Weber contrast); -v3, the
# -v2 faces with deeper wrinkles and folds, so anger's glabellar furrows add ≥ 0.7 × the light
# preset's contrast (Anger's furrows; benchmarks/bench_furrows.py). The older names keep their
# look, so studies recorded with them replay unchanged.
_FEMALE_DARK_V2 = _female(TONES["dark"]).model_copy(update={"lip_depth": 0.15, "brow_density": 1.0})
_MALE_DARK_V2 = _male(TONES["dark"]).model_copy(update={"lip_colour": 1.0, "lip_depth": 0.2})

PRESETS: dict[str, Identity] = {
    **{f"female-{k}": Identity(shape="female", appearance=_female(v)) for k, v in TONES.items()},
    **{f"male-{k}": Identity(shape="male", appearance=_male(v)) for k, v in TONES.items()},
    "female-dark-v2": Identity(shape="female", appearance=_FEMALE_DARK_V2),
    "male-dark-v2": Identity(shape="male", appearance=_MALE_DARK_V2),
    "female-dark-v3": Identity(
        shape="female", appearance=_FEMALE_DARK_V2.model_copy(update={"wrinkle_strength": 2.0})
    ),
    "male-dark-v3": Identity(
        shape="male", appearance=_MALE_DARK_V2.model_copy(update={"wrinkle_strength": 1.6})
    ),
    # the female presets for new studies framed by long hair (hair = "long": a layer over the
    # face framing, docs/appearance.md); the short-haired ones keep their look for replay
    **{
        f"female-{k}-long": Identity(
            shape="female", appearance=a.model_copy(update={"hair": "long"})
        )
        for k, a in (
            ("light", _female(TONES["light"])),
            ("medium", _female(TONES["medium"])),
            ("dark-v3", _FEMALE_DARK_V2.model_copy(update={"wrinkle_strength": 2.0})),
        )
    },
    "generic": Identity(shape="generic", appearance=Appearance()),
    "female": Identity(shape="female", appearance=_female(TONES["medium"])),
    "male": Identity(shape="male", appearance=_male(TONES["medium"])),
}


def identity_from_dict(name: str, data: dict[str, Any]) -> Identity:
    """A lab's identity from a TOML table: ``shape`` plus any :class:`Appearance` keys."""
    if not isinstance(data, dict):
        raise ConfigError(f"identity '{name}' must be a table of keys; got {data!r}")
    rest = dict(data)
    shape = rest.pop("shape", "generic")
    if isinstance(shape, list):
        try:
            shape = tuple(float(x) for x in shape)
        except (TypeError, ValueError):
            raise ConfigError(
                f"identity '{name}': shape must be a preset name or a list of numbers; got {shape!r}"
            ) from None
    elif not isinstance(shape, str):
        raise ConfigError(
            f"identity '{name}': shape must be a preset name or a list of numbers; got {shape!r}"
        )
    return Identity(shape=shape, appearance=appearance_from_dict(rest, f"identity '{name}'"))


def resolve_identity(name: str, custom: dict[str, Identity] | None = None) -> Identity:
    """The identity called ``name``: the lab's own first, then the presets."""
    if custom and name in custom:
        return custom[name]
    if name in PRESETS:
        return PRESETS[name]
    known = sorted({*PRESETS, *(custom or {})})
    raise ConfigError(f"unknown identity '{name}'; known identities: {', '.join(known)}")


def identity_table(identity: Identity) -> dict[str, Any]:
    """An identity as a flat table (``shape`` then the appearance keys), as in the TOML."""
    shape = identity.shape if isinstance(identity.shape, str) else list(identity.shape)
    return {"shape": shape, **identity.appearance.record()}
