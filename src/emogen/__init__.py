"""EmoGen: participant-guided evolution of quantified 3D facial expressions."""

from emogen.errors import (
    ConfigError,
    EmoGenError,
    ModelFileError,
    ModelNotFoundError,
    SelectionError,
    ShapeError,
)

__version__ = "0.1.0"

__all__ = [
    "ConfigError",
    "EmoGenError",
    "FaceModel",
    "ModelFileError",
    "ModelNotFoundError",
    "SelectionError",
    "ShapeError",
    "__version__",
    "load_model",
]


def __getattr__(name: str):  # lazy: `import emogen` stays light for the CLI
    if name == "FaceModel":
        from emogen.model.face import FaceModel

        return FaceModel
    if name == "load_model":
        from emogen.model.load import load_model

        return load_model
    raise AttributeError(name)
