"""The `emogen` Typer app: every command group of :mod:`emogen.cli` registered on one app."""

from __future__ import annotations

from typing import Annotated

import typer

from emogen import __version__
from emogen.cli.analysis import analyse_command, power_command, replicate_command
from emogen.cli.correct import correct_command
from emogen.cli.model import model_app
from emogen.cli.render import render_app
from emogen.cli.serve import serve_command
from emogen.cli.simulate import simulate_command, sweep_command
from emogen.cli.study import replay_command, study_app

__all__ = ["app"]

app = typer.Typer(
    name="emogen",
    help="EmoGen: evolve quantified 3D facial expressions with participants, and analyse them.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"emogen {__version__}")
        raise typer.Exit


@app.callback()
def main(
    version: Annotated[
        bool, typer.Option("--version", callback=_version, is_eager=True, help="Print the version.")
    ] = False,
) -> None:
    """EmoGen command line."""


app.add_typer(model_app, name="model")
app.command("simulate")(simulate_command)
app.command("sweep")(sweep_command)
app.add_typer(render_app, name="render")
app.add_typer(study_app, name="study")
app.command("serve")(serve_command)
app.command("replay")(replay_command)
app.command("correct")(correct_command)
app.command("analyse")(analyse_command)
app.command("replicate")(replicate_command)
app.command("power")(power_command)
