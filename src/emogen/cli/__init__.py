"""The `emogen` command line, the top layer: it may import every other package.

Each command parses its options, loads what it needs and calls one library function. One
module per command group: :mod:`~emogen.cli.model` (``emogen model info|export|fetch``),
:mod:`~emogen.cli.simulate` (``simulate``, ``sweep``), :mod:`~emogen.cli.correct`,
:mod:`~emogen.cli.render` (``render``, ``render sheet|heatmap``), :mod:`~emogen.cli.study`
(``study status|export``, ``replay``), :mod:`~emogen.cli.serve`, :mod:`~emogen.cli.analysis`
(``analyse``, ``replicate``, ``power``); the shared option types and error handling are in
:mod:`~emogen.cli.options`, and :mod:`~emogen.cli.app` puts them on one Typer app.
"""

from emogen.cli.app import app
from emogen.cli.options import IdentityOpt, ModelOpt, RigOpt, friendly_errors, parse_named_weights

__all__ = ["IdentityOpt", "ModelOpt", "RigOpt", "app", "friendly_errors", "parse_named_weights"]
