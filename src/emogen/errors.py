"""The exceptions EmoGen raises. Every message names the bad value and what was expected."""


class EmoGenError(Exception):
    """Base class of every error EmoGen raises on purpose."""


class ConfigError(EmoGenError, ValueError):
    """A configuration value (TOML, CLI option, rig file) is missing, misspelt or out of range."""


class ModelFileError(EmoGenError):
    """A model file is missing, corrupt or inconsistent with the rest of the model."""


class ModelNotFoundError(ModelFileError):
    """No face model could be found anywhere EmoGen looks."""


class ShapeError(EmoGenError, ValueError):
    """An array has the wrong shape, or a blendshape name is unknown."""


class SelectionError(EmoGenError, ValueError):
    """A participant's (or observer's) selection breaks the GA's rules."""
