"""The rig file: the TOML schema of a rig (pydantic) and reading one.

See :mod:`emogen.model.rig` for what a rig declares; :mod:`emogen.model.rig_build` resolves a
spec against a model's shape list.
"""

from __future__ import annotations

import tomllib
from importlib import resources
from pathlib import Path
from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from emogen.errors import ConfigError

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


class ReachSpec(_Strict):
    """Derived shapes that extend the rig's reach (:mod:`emogen.correct.reach`), by version."""

    version: Annotated[int, Field(ge=1, le=2)]
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
    reach: ReachSpec | None = None


def _format_validation(exc: ValidationError, source: str) -> str:
    parts = []
    for err in exc.errors():
        loc = ".".join(str(p) for p in err["loc"])
        if err["type"] == "extra_forbidden":
            parts.append(f"unknown key '{loc}'")
        else:
            parts.append(f"'{loc}': {err['msg']} (got {err.get('input')!r})")
    return f"invalid rig {source}: " + "; ".join(parts)


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
