"""Study commands: ``emogen study status|export|resume-link|check|simulate``, ``emogen replay``.

``study_app`` is a Typer sub-app; ``replay_command`` is a plain function for the top-level app
(``app.command("replay")(replay_command)``). ``emogen serve`` is :mod:`emogen.cli.serve`.
"""

from __future__ import annotations

import json
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from emogen.cli.options import JsonOpt, friendly_errors, show_result
from emogen.cli.outputs import ForceOpt, check_out_folder, moved, output_folder
from emogen.cli.study_check import check_study_command
from emogen.cli.study_retest import retest_command
from emogen.cli.study_simulate import simulate_study_command
from emogen.errors import ConfigError

if TYPE_CHECKING:
    from emogen.study.storage import Store

study_app = typer.Typer(
    help="Participant studies: progress, data export and simulated pilots.", no_args_is_help=True
)
study_app.command("simulate")(simulate_study_command)
study_app.command("check")(check_study_command)
study_app.command("retest-reliability")(retest_command)

DatabaseOpt = Annotated[
    str | None,
    typer.Option(
        "--database-url",
        help="SQLAlchemy URL (default: $EMOGEN_DATABASE_URL, then the SQLite file in the user "
        "data folder).",
    ),
]


class ExportFormat(StrEnum):
    parquet = "parquet"
    csv = "csv"


def _store(database_url: str | None, config: Path | None = None) -> Store:
    """The study database, for commands that only read it: never created (an SQLite path that
    does not exist, or a server that cannot be reached, is one error naming it)."""
    from emogen.study.config import load_study_config
    from emogen.study.storage import Store, resolve_database_url

    config_url = load_study_config(config).database_url if config is not None else None
    return Store(resolve_database_url(database_url, config_url), create=False)


@study_app.command("status")
@friendly_errors
def status(
    database_url: DatabaseOpt = None,
    config: Annotated[
        Path | None, typer.Option("--config", help="Study TOML (for its database_url).")
    ] = None,
    sessions: Annotated[bool, typer.Option("--sessions", help="One line per session.")] = False,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON.")] = False,
) -> None:
    """Sessions by stage, trials done and steps taken (by command), per study in the
    database."""
    from emogen.study.export import study_status
    from emogen.study.progress import progress_as_shown

    store = _store(database_url, config)
    studies = study_status(store)
    lines = progress_as_shown(store) if sessions else []
    if as_json:
        typer.echo(json.dumps({"studies": studies, "sessions": lines}, indent=2))
        return
    typer.echo(f"database {store.describe()}")
    if not studies:
        typer.echo("no studies yet")
    for s in studies:
        stages = ", ".join(f"{n} {k}" for k, n in s["by_stage"].items()) or "none"
        steps = ", ".join(f"{n} {k}" for k, n in s["steps"].items()) or "none"
        typer.echo(
            f"study {s['name']} (config {s['config_hash'][:12]}): {s['sessions']} sessions "
            f"({stages}); {s['trials_done']} trials done; steps: {steps}"
        )
    for line in lines:
        typer.echo(
            f"  session {line['session_id']:>5}  {line['participant_id']:<24} {line['stage']:<12} "
            f"{line['step']:<34} updated {line['updated_at']}"
        )
    store.dispose()


@study_app.command("export")
@friendly_errors
def export(
    out: Annotated[Path, typer.Option("--out", "-o", help="Output folder.")],
    fmt: Annotated[ExportFormat, typer.Option("--format", help="parquet or csv.")] = (
        ExportFormat.parquet
    ),
    study: Annotated[
        str | None, typer.Option("--study", help="Only the study of this name.")
    ] = None,
    database_url: DatabaseOpt = None,
    config: Annotated[
        Path | None, typer.Option("--config", help="Study TOML (for its database_url).")
    ] = None,
    since: Annotated[
        str | None,
        typer.Option(
            "--since",
            help="Incremental: only the sessions completed from this time (ISO 8601, e.g. the "
            "'until' the previous incremental export printed) to a minute ago; see "
            "docs/study.md.",
        ),
    ] = None,
    table: Annotated[
        list[str] | None,
        typer.Option("--table", help="Only this table (repeat for more; default: all)."),
    ] = None,
    force: ForceOpt = False,
    as_json: JsonOpt = False,
) -> None:
    """Tidy tables: sessions, trials, faces, selections, restarts, evolve_ratings, final_faces,
    categorise_responses, identities, study (every column and the join keys: docs/data.md; CSV
    seeds are text s<digits> so R keeps them exact).

    Written a few sessions at a time, in bounded memory whatever the study's size."""
    from emogen.study.export_stream import check_table_names, export_study, parse_since

    start = None if since is None else parse_since(since)
    check_table_names(table or [])
    check_out_folder(out, force=force)
    store = _store(database_url, config)
    try:
        with output_folder(out, force=force) as tmp:
            result = export_study(
                store,
                tmp,
                fmt.value,
                study=study,
                since=start,
                tables=tuple(table) if table else None,
            )
    finally:
        store.dispose()
    paths = moved(result.paths, tmp, out)
    lines = [f"wrote {p} ({result.rows[p.stem]} rows)" for p in paths]
    window: dict[str, str | None] = {"since": None, "until": None}
    if result.until is not None:
        window = {
            "since": result.since.isoformat() if result.since else None,
            "until": result.until.isoformat(),
        }
        lines.append(
            f"sessions completed from {window['since'] or ''} to {window['until']} "
            f"({out / 'export.json'}); next incremental export: --since {window['until']}"
        )
    show_result(
        as_json,
        {"wrote": [{"path": str(p), "rows": result.rows[p.stem]} for p in paths], **window},
        lines,
    )


BASE_URL_ENV = "EMOGEN_BASE_URL"


@study_app.command("resume-link")
@friendly_errors
def resume_link(
    participant: Annotated[str, typer.Argument(help="The participant id (as in the study link).")],
    database_url: DatabaseOpt = None,
    base_url: Annotated[
        str | None,
        typer.Option(
            "--base-url",
            help="The server's public address, e.g. https://study.example.org (default: "
            "$EMOGEN_BASE_URL, then http://127.0.0.1:8000 as `emogen serve` listens).",
        ),
    ] = None,
    study: Annotated[
        str | None, typer.Option("--study", help="The study's name (when the id is in several).")
    ] = None,
    config: Annotated[
        Path | None, typer.Option("--config", help="Study TOML (for its database_url).")
    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """Print a participant's personal session link, to give back to them (exit 2 if none)."""
    import os

    from emogen.study.progress import participant_token, session_link

    store = _store(database_url, config)
    try:
        token = participant_token(store, participant, study=study)
    finally:
        store.dispose()
    base = base_url or os.environ.get(BASE_URL_ENV) or "http://127.0.0.1:8000"
    link = session_link(base, token)
    show_result(as_json, {"participant_id": participant, "link": link}, [link])


@friendly_errors
def replay_command(
    session_id: Annotated[
        int | None,
        typer.Argument(
            help="Session id (see `emogen study status --sessions`); with "
            "--from-export, default every exported session."
        ),
    ] = None,
    database_url: DatabaseOpt = None,
    from_export: Annotated[
        Path | None,
        typer.Option(
            "--from-export",
            help="Replay from a folder written by `emogen study "
            "export` (Parquet or CSV) instead of the database.",
        ),
    ] = None,
    model: Annotated[
        Path | None, typer.Option("--model", help="Face model (default: the study's).")
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON.")] = False,
) -> None:
    """Regenerate every population of a session from its seeds and selections; compare."""
    if from_export is not None:
        reports = _replay_export(from_export, session_id, model)
    else:
        from emogen.model import load_model
        from emogen.study.replay import replay_session, study_of_session

        if session_id is None:
            raise ConfigError("replay needs a SESSION_ID (or --from-export FOLDER)")
        store = _store(database_url)
        cfg = study_of_session(store, session_id)
        face_model = load_model(model if model is not None else cfg.model, rig=cfg.rig)
        reports = [
            replay_session(
                store, session_id, face_model.rig, face_model.model_hash, model=face_model
            )
        ]
        store.dispose()
    if as_json:
        data = [r.to_dict() for r in reports]
        typer.echo(json.dumps(data[0] if from_export is None else data, indent=2))
    else:
        for report in reports:
            _echo_report(report)
    if not all(r.ok for r in reports):
        raise typer.Exit(1)


def _replay_export(folder: Path, session_id: int | None, model: Path | None) -> list[Any]:
    from emogen.model import load_model
    from emogen.study.config import StudyConfig
    from emogen.study.replay_export import read_exported, replay_exported

    configs = read_exported(folder)["study"]["config_json"]
    if len(configs) == 0:
        raise ConfigError(f"the export at {folder} holds no study")
    cfg = StudyConfig.model_validate(json.loads(configs.iloc[0]))
    face_model = load_model(model if model is not None else cfg.model, rig=cfg.rig)
    return replay_exported(
        folder,
        face_model.rig,
        face_model.model_hash,
        model=face_model,
        session_ids=None if session_id is None else [session_id],
    )


def _echo_report(report: Any) -> None:
    """A session's replay in words: what was rebuilt and checked, the verdict, and each
    difference and each thing not checked (with why)."""
    done = [f"{report.populations} populations, {report.faces} faces replayed"]
    checked = dict(getattr(report, "checked", {}))
    if checked:
        done = [] if not report.populations else done
        done.append(", ".join(f"{n} {what}" for what, n in checked.items()) + " checked")
    unchecked = list(getattr(report, "unchecked", []))
    if report.ok:
        verdict = "every face matches"
    elif report.mismatches or not report.model_hash_matches:
        verdict = "MISMATCH"
    else:
        verdict = f"NOT ALL CHECKED ({len(unchecked)} not checked, below)"
    typer.echo(f"session {report.session_id}: {', '.join(done)}: {verdict}")
    deviation = getattr(report, "weight_deviation", 0.0)
    if report.faces or report.stimuli:
        from emogen.tasks.rounding import WEIGHT_TOLERANCE

        exact = "ids, parents, operators and genes" if report.populations else "positions"
        typer.echo(
            f"  largest weight deviation {deviation:.3g} (floating-point rounding up to "
            f"{WEIGHT_TOLERANCE:g} counts as equal; {exact} exactly)"
        )
    if not report.model_hash_matches:
        typer.echo("  the model differs from the one the session was recorded with")
    for m in unchecked[:20]:
        typer.echo(f"  not checked: {m}")
    if len(unchecked) > 20:
        typer.echo(f"  … and {len(unchecked) - 20} more not checked (--json lists every one)")
    for m in report.mismatches[:20]:
        typer.echo(f"  {m}")
    if len(report.mismatches) > 20:
        typer.echo(f"  … and {len(report.mismatches) - 20} more (--json lists every one)")
