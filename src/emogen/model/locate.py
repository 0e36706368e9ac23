"""Finding the face model: ``--model PATH`` > ``$EMOGEN_MODEL`` > the user cache."""

from __future__ import annotations

import os
from pathlib import Path

from emogen.errors import ModelNotFoundError


def how_to_get_model() -> str:
    from emogen.model.io.fetch import default_model_dir

    return (
        "Get ICT-FaceKit (MIT licence) with `emogen model fetch` "
        f"(installs into {default_model_dir()}), or point `--model PATH` or the EMOGEN_MODEL "
        "environment variable at an ICT-FaceKit FaceXModel folder or an ARKit-named GLB."
    )


def find_model(path: str | os.PathLike[str] | None = None) -> Path:
    """The model location to load, checking each candidate in order of precedence."""
    from emogen.model.io.fetch import default_model_dir

    if path is not None:
        p = Path(path).expanduser()
        if not p.exists():
            raise ModelNotFoundError(f"model path does not exist: {p}. {how_to_get_model()}")
        return p
    env = os.environ.get("EMOGEN_MODEL")
    if env:
        p = Path(env).expanduser()
        if not p.exists():
            raise ModelNotFoundError(
                f"EMOGEN_MODEL points at {p}, which does not exist. {how_to_get_model()}"
            )
        return p
    cached = default_model_dir() / "FaceXModel"
    if cached.is_dir():
        return cached
    raise ModelNotFoundError(
        f"no face model found: no --model given, EMOGEN_MODEL is not set, and {cached} "
        f"does not exist. {how_to_get_model()}"
    )
