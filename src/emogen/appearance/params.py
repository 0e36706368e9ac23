"""What a face looks like beyond its shape: skin tone, brows, lips, hair, beard shadow.

Skin tone is given on the **Monk Skin Tone (MST) scale** (Monk, E. 2019/2023; the 10-point scale
Google published in 2022), 1 (lightest) to 10 (darkest); fractional values interpolate between
neighbouring swatches in linear RGB. The swatch is taken as the colour a frontal, lit cheek should
have under EmoGen's lighting (``look.json``): the generator divides it by the look's frontal
irradiance to get the albedo, so every tone looks right under the same lights.

Everything here is recorded with every stimulus (``Appearance.record()``), so a face can be
re-rendered exactly; ``seed`` fixes the procedural detail (mottling, hair strokes).
"""

from __future__ import annotations

import hashlib
import json
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from emogen.errors import ConfigError

#: The ten MST swatches (sRGB hex), tone 1 … 10.
MONK_SWATCHES = (
    "#f6ede4",
    "#f3e7db",
    "#f7ead0",
    "#eadaba",
    "#d7bd96",
    "#a07e56",
    "#825c43",
    "#604134",
    "#3a312a",
    "#292420",
)

#: Version of the texture generator: bumped whenever the same parameters would paint other texels,
#: so cached textures of an older generator are never reused.
GENERATOR_VERSION = 1


def hex_to_srgb(text: str, what: str = "colour") -> tuple[float, float, float]:
    t = text.strip()
    if len(t) != 7 or not t.startswith("#"):
        raise ConfigError(f"{what} must be a #rrggbb colour; got {text!r}")
    try:
        return (int(t[1:3], 16) / 255, int(t[3:5], 16) / 255, int(t[5:7], 16) / 255)
    except ValueError:
        raise ConfigError(f"{what} must be a #rrggbb colour; got {text!r}") from None


Colour = Annotated[str, Field(pattern=r"^#[0-9a-fA-F]{6}$")]


class Appearance(BaseModel):
    """A face's surface appearance (all parameters; defaults: a medium-tone face, dark brows)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    #: Monk Skin Tone scale, 1 (lightest) … 10 (darkest); fractions interpolate
    skin_tone: Annotated[float, Field(ge=1, le=10)] = 5.0
    #: regional redness (lips, cheeks, nose tip, ears): 0 none … 2 double
    redness: Annotated[float, Field(ge=0, le=2)] = 1.0
    #: eyebrow hair colour and shape
    brow_colour: Colour = "#2b2019"
    brow_thickness: Annotated[float, Field(ge=0.5, le=2.0)] = 1.0  # × the default band height
    brow_density: Annotated[float, Field(ge=0.0, le=2.0)] = 1.0  # × the default hairs per cm²
    #: scalp hair: "short" (a close crop with a natural hairline), "none" (bald) or "long" (the
    #: crop, framed under the ``face`` framing by long hair: :mod:`emogen.appearance.long_hair`)
    hair: Literal["short", "none", "long"] = "short"
    hair_colour: Colour = "#2a2019"
    hair_density: Annotated[float, Field(ge=0.0, le=1.0)] = 0.9
    #: hairline height above the brows as a fraction of the default (male recession > 1)
    hairline: Annotated[float, Field(ge=0.8, le=1.3)] = 1.0
    #: stubble shadow over the beard area, 0 none … 1 heavy
    beard_shadow: Annotated[float, Field(ge=0.0, le=1.0)] = 0.0
    #: lip colour strength: 0 lips the skin's colour … 1.5 strongly coloured
    lip_colour: Annotated[float, Field(ge=0.0, le=1.5)] = 1.0
    #: how much darker the vermilion is than its colour alone gives, 0 … 0.6: on dark skin the
    #: colour alone leaves the lips close to the skin's luminance (docs/appearance.md, Contrast)
    lip_depth: Annotated[float, Field(ge=0.0, le=0.6)] = 0.0
    #: the depth and shade of the wrinkles and folds the skin's strain makes (glabellar furrows,
    #: forehead lines, crow's feet), × this, 0 … 3 (1: the look of every earlier version): the
    #: same furrow is a smaller luminance step on dark skin (docs/appearance.md, Anger's furrows)
    wrinkle_strength: Annotated[float, Field(ge=0.0, le=3.0)] = 1.0
    #: seed of the procedural detail (mottling, hair strokes)
    seed: Annotated[int, Field(ge=0, lt=2**32)] = 0

    @field_validator("brow_colour", "hair_colour")
    @classmethod
    def _lower(cls, v: str) -> str:
        return v.lower()

    def record(self) -> dict[str, Any]:
        """Every parameter, for records and exports (``Appearance(**record)`` rebuilds it)."""
        return self.model_dump(mode="json")

    def key(self) -> str:
        """A short content hash of the parameters and the generator version."""
        text = json.dumps({"v": GENERATOR_VERSION, **self.record()}, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def appearance_from_dict(data: dict[str, Any], source: str = "appearance") -> Appearance:
    """An :class:`Appearance` from plain data, with errors that name the bad key and value."""
    try:
        return Appearance(**data)
    except ValidationError as exc:
        parts = []
        for err in exc.errors():
            loc = ".".join(str(p) for p in err["loc"])
            if err["type"] == "extra_forbidden":
                known = ", ".join(Appearance.model_fields)
                parts.append(f"unknown key '{loc}' (known: {known})")
            else:
                parts.append(f"'{loc}': {err['msg']} (got {err.get('input')!r})")
        raise ConfigError(f"invalid {source}: " + "; ".join(parts)) from None
    except TypeError as exc:
        raise ConfigError(f"invalid {source}: {exc}") from None
