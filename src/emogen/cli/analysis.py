"""Analysis commands: ``emogen analyse``, ``emogen replicate`` (and ``emogen power``).

Plain command functions for the top-level app (``app.command("analyse")(analyse_command)``,
likewise ``replicate_command`` and :func:`~emogen.cli.power.power_command`); ``analysis_app``
holds all three, for tests and for ``python -m emogen.cli.analysis``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Annotated

import typer

from emogen.cli.options import FigureFormatOpt, ModelOpt, RigOpt, SeedOpt, friendly_errors
from emogen.cli.power import power_command

RenderOpt = Annotated[
    bool, typer.Option("--render/--no-render", help="Render mean faces and heatmaps (OpenGL).")
]


@friendly_errors
def analyse_command(
    data: Annotated[
        Path,
        typer.Argument(help="A study export folder (emogen study export) or simulation output."),
    ],
    out: Annotated[Path, typer.Option("--out", "-o", help="Report folder.")],
    config: Annotated[
        Path | None,
        typer.Option(
            "--config",
            help="Study TOML: its [ga] settings for the GA-noise simulation (default: inferred "
            "from the data).",
        ),
    ] = None,
    noise_runs: Annotated[
        int, typer.Option("--noise-runs", help="Simulated runs per group for the GA noise.")
    ] = 500,
    gmm_dims: Annotated[
        float,
        typer.Option(
            "--gmm-dims", help="PCA components for the GMM (an integer, or a variance share < 1)."
        ),
    ] = 2,
    alpha: Annotated[float, typer.Option("--alpha", help="Level of the GA-noise test.")] = 0.05,
    seed: SeedOpt = 1,
    render: RenderOpt = True,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
    figure_format: FigureFormatOpt = None,
) -> None:
    """Analyse a study export or simulation output: error distributions, KL per generation,
    bias and repeatability bins, PCA + GMM separability, GA-noise test, prototypes, renders.

    Writes OUT/index.html and OUT/README.md with figures/ and tables/ (CSV), and analysis.json.
    """
    from emogen.analysis import plots
    from emogen.analysis.analyse import AnalysisOptions, analyse
    from emogen.analysis.data import load_dataset
    from emogen.model import load_model

    plots.check_formats(figure_format or ["png", "svg"])  # a bad --format before any work

    dataset = load_dataset(data)  # fails fast on a folder that is not data
    ga = None
    if config is not None:
        from emogen.study.config import load_study_config

        ga = load_study_config(config).ga
    model = load_model(model_path, rig=rig)
    options = AnalysisOptions(
        render=render, noise_runs=noise_runs, seed=seed, gmm_dims=gmm_dims, alpha=alpha, ga=ga
    )
    with plots.formats(figure_format or ["png", "svg"]):
        result = analyse(dataset, out, model=model, options=options)
    typer.echo(f"wrote {result.html} and {result.markdown}")


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
    seed: SeedOpt = 1,
    render: RenderOpt = True,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
    figure_format: FigureFormatOpt = None,
) -> None:
    """Run the paper's Section IV experiments on our model and write the report, each finding
    beside the paper's numbers with a one-line verdict (holds / partly / differs)."""
    from emogen.analysis import plots
    from emogen.analysis.replication import ReplicateSettings, replicate
    from emogen.model import load_model

    plots.check_formats(figure_format or ["png", "svg"])

    extra: dict[str, object] = {"seed": seed, "render": render}
    if runs is not None:
        extra["runs"] = runs
    settings = (
        ReplicateSettings.quick_settings(**extra)
        if quick
        else ReplicateSettings.full_settings(**extra)
    )
    model = load_model(model_path, rig=rig)
    start = time.perf_counter()

    def progress(name: str) -> None:
        typer.echo(f"[{time.perf_counter() - start:6.1f} s] {name}", err=True)

    with plots.formats(figure_format or ["png", "svg"]):
        findings = replicate(model, out, settings, only=only, progress=progress)
    for f in findings:
        typer.echo(f.line())
    counts = {v: sum(f.verdict == v for f in findings) for v in ("holds", "partly", "differs")}
    typer.echo(
        f"{len(findings)} findings: {counts['holds']} hold, {counts['partly']} partly, "
        f"{counts['differs']} differ ({time.perf_counter() - start:.0f} s); "
        f"wrote {out / 'index.html'} and {out / 'README.md'}"
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
