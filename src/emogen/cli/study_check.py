"""``emogen study check STUDY.toml``: a study vetted before anyone takes part
(:mod:`emogen.study.check`); ``emogen serve`` runs the same check before it listens."""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from emogen.cli.options import JsonOpt, friendly_errors, show_result
from emogen.errors import ConfigError

if TYPE_CHECKING:
    from emogen.study.check import CheckReport


def checked_study(path: Path, with_rig: bool = False) -> CheckReport:
    """The check of the study at ``path`` (a config that does not load is a ConfigError);
    ``with_rig``: against its model's rig too (identities, the genes blocks name), where the
    model is found (else by names alone, as ``serve``'s check before it loads the model)."""
    from emogen.errors import ModelNotFoundError
    from emogen.model import load_model
    from emogen.study.check import check_study
    from emogen.study.config import load_study_config

    config = load_study_config(path)
    rig = None
    if with_rig:
        try:
            rig = load_model(config.model, rig=config.rig).rig
        except ModelNotFoundError:
            rig = None
    return check_study(config, rig)


def refuse_errors(report: CheckReport, path: Path) -> None:
    """A ConfigError listing the report's errors, if any."""
    if report.errors:
        listed = "; ".join(f"{f.where}: {f.message}" for f in report.errors)
        n = len(report.errors)
        raise ConfigError(
            f"study {path} has {n} error{'s' * (n != 1)} (see `emogen study check {path}`): "
            f"{listed}"
        )


def check_before_serving(path: Path) -> None:
    """``serve``'s check: refuse a study with errors; its warnings on stderr (the session
    length is in the banner the server prints once it listens)."""
    report = checked_study(path)
    refuse_errors(report, path)
    for finding in report.warnings:
        typer.echo(finding.line(), err=True)


@friendly_errors
def check_study_command(
    config: Annotated[Path, typer.Argument(help="The study TOML.")],
    as_json: JsonOpt = False,
) -> None:
    """Check a study before it goes live: placeholders in every text, emotion words, identities,
    the genes blocks name (against the model's rig, where the model is found), the participant
    link, and how long a session takes (exit 1 when there are errors)."""
    report = checked_study(config, with_rig=True)
    data = {
        "errors": [asdict(f) for f in report.errors],
        "warnings": [asdict(f) for f in report.warnings],
        "screens": report.length.screens,
        "seconds": list(report.length.seconds),
        "minutes": list(report.length.minutes),
        "notes": list(report.notes),
    }
    show_result(as_json, data, [f"study {config}", *report.lines()])
    if report.errors:
        raise typer.Exit(1)
