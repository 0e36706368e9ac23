"""``emogen study retest-reliability FIRST RETEST``: between-session reliability of a retest
study (``retest_of``) against its first session (:mod:`emogen.analysis.retest`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from emogen.cli.options import JsonOpt, friendly_errors, show_result


@friendly_errors
def retest_command(
    first: Annotated[Path, typer.Argument(help="The first session's export folder.")],
    retest: Annotated[Path, typer.Argument(help="The retest study's export folder.")],
    out: Annotated[
        Path | None, typer.Option("--out", "-o", help="Write retest.md and retest.csv here.")
    ] = None,
    level: Annotated[float, typer.Option("--level", help="Interval coverage.")] = 0.95,
    as_json: JsonOpt = False,
) -> None:
    """Does a participant make the same face on another day? The between-session ICC per
    emotion × identity (participants matched by id), with the first session's within-session
    ICC beside it."""
    from emogen.analysis.people import load_people
    from emogen.analysis.retest import retest_table, retest_text
    from emogen.errors import ConfigError

    if not 0 < level < 1:
        raise ConfigError(f"--level must be between 0 and 1; got {level}")
    table = retest_table(load_people(first), load_people(retest), level=level)
    text = retest_text(table, level)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        table.to_csv(out / "retest.csv", index=False)
        (out / "retest.md").write_text(f"# Retest reliability\n\n{text}\n")
    show_result(as_json, {"cells": table.to_dict("records")}, text.splitlines())
