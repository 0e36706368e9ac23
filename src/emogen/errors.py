"""The exceptions EmoGen raises. Every message names the bad value and what was expected.

The command line maps them to exit statuses (docs/cli.md): 2 a usage error (an option or a
config value: :class:`ConfigError`, :class:`ShapeError`, :class:`SelectionError`), 3 a data error
(an input file's content: :class:`DataError`, :class:`ModelFileError`), 4 an environment error
(:class:`ResourceError`, :class:`ModelNotFoundError`, and the operating system's own errors).
"""

from pathlib import Path


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


class DataError(ConfigError):
    """An input file's content is wrong: a face table, an export, recorded data (exit 3)."""


class ResourceError(EmoGenError):
    """The machine or a service stands in the way: a database that cannot be reached or does
    not exist, a folder that cannot be written (exit 4)."""


def did_you_mean_path(path: Path) -> str:
    """`` (did you mean …?)`` naming the closest entry beside a path that does not exist."""
    import difflib

    parent = path.parent
    try:
        names = [p.name for p in parent.iterdir()]
    except OSError:
        return ""
    close = difflib.get_close_matches(path.name, names, n=1, cutoff=0.6)
    return f" (did you mean {parent / close[0]}?)" if close else ""
