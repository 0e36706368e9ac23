"""Analysis commands: ``emogen analyse``, ``emogen replicate`` (and ``emogen power``).

Plain command functions for the top-level app (``app.command("analyse")(analyse_command)``,
likewise ``replicate_command`` and :func:`~emogen.cli.power.power_command`); ``analysis_app``
holds all three, for tests and for ``python -m emogen.cli.analysis``.
"""

from __future__ import annotations

import shlex
import sys
import time
from pathlib import Path
from typing import Annotated, Any

import typer

from emogen.cli.options import (
    FigureFormatOpt,
    JsonOpt,
    ModelOpt,
    RigOpt,
    SeedOpt,
    at_least,
    friendly_errors,
    show_result,
    stage_printer,
)
from emogen.cli.outputs import ForceOpt, check_out_folder, output_folder
from emogen.cli.power import power_command

ProgressOpt = Annotated[
    bool | None,
    typer.Option(
        "--progress/--no-progress",
        help="Show each stage on stderr (default: when stderr is a terminal).",
    ),
]
PrimaryOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--primary",
        help="A primary test, named before the analysis (repeatable; default "
        "categorisation.own_distance.primary); every other test is marked exploratory. "
        "The names: docs/analysis.md, 'Multiplicity plan'.",
    ),
]
ChoiceNoiseOpt = Annotated[
    float | None,
    typer.Option(
        "--choice-noise",
        min=0.0,
        help="Participants' choice noise T (softmax, CD units) in the GA-noise null "
        "(default: a simulation's own T; for a study, an assumed and reported T = 0).",
    ),
]
RenderOpt = Annotated[
    bool, typer.Option("--render/--no-render", help="Render mean faces and heatmaps (OpenGL).")
]

ConfigOpt = Annotated[
    Path | None,
    typer.Option(
        "--config",
        help="Study TOML: its [ga] settings for the GA-noise simulation (default: inferred "
        "from the data).",
    ),
]

NoiseRunsOpt = Annotated[
    int,
    typer.Option(
        "--noise-runs", callback=at_least(1), help="Simulated runs per group for the GA noise."
    ),
]

GmmDimsOpt = Annotated[
    float,
    typer.Option(
        "--gmm-dims", help="PCA components for the GMM (an integer, or a variance share < 1)."
    ),
]

AlphaOpt = Annotated[float, typer.Option("--alpha", help="Level of the GA-noise test.")]

ParticipantsOpt = Annotated[
    Path | None,
    typer.Option(
        "--participants",
        help="Participant table (CSV or Parquet): a participant_id column and any others "
        "(e.g. group = clinical/control), joined to a study's faces and answers.",
    ),
]

GroupColumnOpt = Annotated[
    str,
    typer.Option(
        "--group-column", help="The participant table's column whose groups are compared."
    ),
]

ExclusionOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--exclusion",
        help="Change one threshold of the exclusion rule, KEY=VALUE (VALUE 'none' turns "
        "that criterion off), e.g. min_median_rt_ms=500; repeatable. See docs/analysis.md.",
    ),
]

RetestArg = Annotated[
    Path | None,
    typer.Argument(
        help="A retest study's export (retest_of): adds the between-session reliability "
        "(ICC across the two sessions, participants matched by id) to the report.",
    ),
]

ExclusionsOpt = Annotated[
    bool,
    typer.Option(
        "--exclusions/--no-exclusions",
        help="Apply the exclusion rule before every analysis of a study (default) or not.",
    ),
]


def study_ga(config: Path) -> Any:
    """``--config``: the GA settings of the study the export came from."""
    from emogen.study.config import load_study_config

    return load_study_config(config).ga


def command_line(data: Path, retest: Path | None, out: Path) -> str:
    """The command that made the report (this process's, or the arguments given)."""
    if sys.argv[1:2] == ["analyse"]:
        return shlex.join(["emogen", *sys.argv[1:]])
    given = [str(p) for p in (data, retest) if p is not None]
    return shlex.join(["emogen", "analyse", *given, "--out", str(out)]) + " …"


def check_retest(first: Any, second: Any) -> None:
    """``emogen analyse FIRST RETEST``: both must be study exports (participants to match)."""
    from emogen.errors import ConfigError

    if (first.kind, second.kind) != ("study", "study"):
        raise ConfigError(
            f"a retest analysis needs two study exports; {first.source} is a {first.kind} "
            f"output and {second.source} a {second.kind} output"
        )


@friendly_errors
def analyse_command(
    data: Annotated[
        Path,
        typer.Argument(help="A study export folder (emogen study export) or simulation output."),
    ],
    out: Annotated[Path, typer.Option("--out", "-o", help="Report folder.")],
    retest: RetestArg = None,
    config: ConfigOpt = None,
    noise_runs: NoiseRunsOpt = 500,
    gmm_dims: GmmDimsOpt = 2,
    alpha: AlphaOpt = 0.05,
    choice_noise: ChoiceNoiseOpt = None,
    participants: ParticipantsOpt = None,
    group_column: GroupColumnOpt = "group",
    exclusion: ExclusionOpt = None,
    exclusions: ExclusionsOpt = True,
    seed: SeedOpt = 1,
    render: RenderOpt = True,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
    force: ForceOpt = False,
    as_json: JsonOpt = False,
    progress: ProgressOpt = None,
    figure_format: FigureFormatOpt = None,
    primary: PrimaryOpt = None,
) -> None:
    """Analyse a study export or simulation output: error distributions, KL per generation,
    bias and repeatability bins, PCA + GMM separability, GA-noise test, prototypes, renders.
    With a second study export (a retest study, retest_of): the between-session reliability.

    Writes OUT/index.html and OUT/README.md with figures/ and tables/ (CSV), and analysis.json.
    """
    from emogen.analysis import plots
    from emogen.analysis.analyse import AnalysisOptions, analyse
    from emogen.analysis.data import load_dataset
    from emogen.model import load_model

    plots.check_formats(figure_format or ["png", "svg"])  # a bad --format before any work

    from emogen.analysis.exclusions import rule_from_options
    from emogen.analysis.plan import DEFAULT_PRIMARY, check_primary

    rule = rule_from_options(exclusion or []) if exclusions else None
    planned = check_primary(tuple(primary) if primary else DEFAULT_PRIMARY)
    dataset = load_dataset(data)  # fails fast on a folder that is not data
    if retest is not None:
        check_retest(dataset, load_dataset(retest))
    if participants is not None:  # a wrong participant table before any work
        from emogen.analysis.analyse_people import check_participants

        check_participants(dataset, participants, group_column)
    check_out_folder(out, force=force)
    ga = None if config is None else study_ga(config)
    model = load_model(model_path, rig=rig)
    options = AnalysisOptions(
        render=render,
        noise_runs=noise_runs,
        seed=seed,
        gmm_dims=gmm_dims,
        alpha=alpha,
        ga=ga,
        choice_noise=choice_noise,
        participants=participants,
        group_column=group_column,
        exclusions=rule,
        primary=planned,
        retest=retest,
        command=command_line(data, retest, out),
    )
    with output_folder(out, force=force) as tmp, plots.formats(figure_format or ["png", "svg"]):
        analyse(dataset, tmp, model=model, options=options, progress=stage_printer(progress))
    wrote = [str(out / "index.html"), str(out / "README.md"), str(out / "analysis.json")]
    show_result(
        as_json,
        {"kind": dataset.kind, "groups": list(dataset.groups), "wrote": wrote},
        [f"wrote {wrote[0]} and {wrote[1]}"],
    )


@friendly_errors
def replicate_command(
    out: Annotated[Path, typer.Option("--out", "-o", help="Report folder.")],
    quick: Annotated[
        bool,
        typer.Option("--quick", help="100 runs per condition, 60 participants (a few minutes)."),
    ] = False,
    runs: Annotated[
        int | None, typer.Option("--runs", help="Runs per condition (default 500, quick 100).")
    ] = None,
    only: Annotated[
        list[str] | None,
        typer.Option("--only", help="Run only experiments whose name contains this; repeatable."),
    ] = None,
    seed: Annotated[
        int | None,
        typer.Option("--seed", help="First seed (default 1; --quick: its own, 101)."),
    ] = None,
    seeds: Annotated[
        int | None,
        typer.Option(
            "--seeds",
            min=1,
            help="Independent seeds every verdict combines (default 10; --quick: 3).",
        ),
    ] = None,
    render: RenderOpt = True,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
    force: ForceOpt = False,
    as_json: JsonOpt = False,
    progress: ProgressOpt = None,
    figure_format: FigureFormatOpt = None,
) -> None:
    """Run the paper's Section IV experiments on our model and write the report, each finding
    beside the paper's numbers with a verdict over several seeds (holds / partly / differs /
    inconclusive)."""
    from emogen.analysis import plots
    from emogen.analysis.replication import ReplicateSettings, replicate
    from emogen.model import load_model

    extra: dict[str, object] = {"render": render}
    if seeds is not None:
        extra["seeds"] = seeds
    if seed is not None:
        extra["seed"] = seed
    if runs is not None:
        extra["runs"] = runs
    plots.check_formats(figure_format or ["png", "svg"])  # a bad --format before any work
    settings = (
        ReplicateSettings.quick_settings(**extra)
        if quick
        else ReplicateSettings.full_settings(**extra)
    )
    check_out_folder(out, force=force)
    model = load_model(model_path, rig=rig)
    start = time.perf_counter()
    show = stage_printer(progress)
    command = _replicate_line(quick, runs, only, settings.seed, settings.seeds, render, out)
    with output_folder(out, force=force) as tmp, plots.formats(figure_format or ["png", "svg"]):
        findings = replicate(
            model, tmp, settings, only=only, progress=show or (lambda _n: None), command=command
        )
    _show_findings(as_json, findings, time.perf_counter() - start, command, out)


def _replicate_line(
    quick: bool,
    runs: int | None,
    only: list[str] | None,
    seed: int,
    seeds: int,
    render: bool,
    out: Path,
) -> str:
    """The command that reproduces this report exactly (recorded in it)."""
    return " ".join(
        ["emogen replicate", *(["--quick"] if quick else [])]
        + ([f"--runs {runs}"] if runs is not None else [])
        + [f"--only '{w}'" for w in only or []]
        + [f"--seed {seed} --seeds {seeds}"]
        + ([] if render else ["--no-render"])
        + [f"--out {out}"]
    )


def _show_findings(
    as_json: bool, findings: list[Any], seconds: float, command: str, out: Path
) -> None:
    """Every finding's line and the tally of the paper's findings (the rest apart)."""
    from emogen.analysis.replication.findings import VERDICTS

    paper = [f for f in findings if f.counted]
    counts = {v: sum(f.verdict == v for f in paper) for v in VERDICTS}
    wrote = [str(out / "index.html"), str(out / "README.md")]
    show_result(
        as_json,
        {
            "findings": [
                {
                    "verdict": f.verdict,
                    "paper_finding": f.paper_finding,
                    "counted": f.counted,
                    "line": f.line(),
                }
                for f in findings
            ],
            "counts": counts,
            "ours_apart": len(findings) - len(paper),
            "seconds": seconds,
            "command": command,
            "wrote": wrote,
        },
        [
            *(f.line() for f in findings),
            f"{len(paper)} paper findings: {counts['holds']} hold, {counts['partly']} partly, "
            f"{counts['differs']} differ, {counts['inconclusive']} inconclusive "
            f"({len(findings) - len(paper)} reported apart; {seconds:.0f} s); "
            f"wrote {wrote[0]} and {wrote[1]}",
        ],
    )


analysis_app = typer.Typer(
    help="Analysis: analyse data, replicate the paper, power analysis.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
)
analysis_app.command("analyse")(analyse_command)
analysis_app.command("replicate")(replicate_command)
analysis_app.command("power")(power_command)


if __name__ == "__main__":  # pragma: no cover
    analysis_app(prog_name=Path(sys.argv[0]).name)
