"""Analysis commands: ``emogen analyse``, ``emogen replicate``, ``emogen power``.

Plain command functions for the top-level app (``app.command("analyse")(analyse_command)``,
likewise ``replicate_command`` and ``power_command``); ``analysis_app`` holds all three, for
tests and for ``python -m emogen.analysis.cli``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Annotated

import typer

from emogen.clitools import ModelOpt, RigOpt, friendly_errors, parse_named_weights

SeedOpt = Annotated[int, typer.Option("--seed", help="Seed of every simulation (recorded).")]
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
) -> None:
    """Analyse a study export or simulation output: error distributions, KL per generation,
    bias and repeatability bins, PCA + GMM separability, GA-noise test, prototypes, renders.

    Writes OUT/index.html and OUT/README.md with figures/ and tables/ (CSV), and analysis.json.
    """
    from emogen.analysis.analyse import AnalysisOptions, analyse
    from emogen.analysis.data import load_dataset
    from emogen.model import load_model

    dataset = load_dataset(data)  # fails fast on a folder that is not data
    ga = None
    if config is not None:
        from emogen.study.config import load_study_config

        ga = load_study_config(config).ga
    model = load_model(model_path, rig=rig)
    options = AnalysisOptions(
        render=render, noise_runs=noise_runs, seed=seed, gmm_dims=gmm_dims, alpha=alpha, ga=ga
    )
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
) -> None:
    """Run the paper's Section IV experiments on our model and write the report, each finding
    beside the paper's numbers with a one-line verdict (holds / partly / differs)."""
    from emogen.analysis.replication import ReplicateSettings, replicate
    from emogen.model import load_model

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

    findings = replicate(model, out, settings, only=only, progress=progress)
    for f in findings:
        typer.echo(f.line())
    counts = {v: sum(f.verdict == v for f in findings) for v in ("holds", "partly", "differs")}
    typer.echo(
        f"{len(findings)} findings: {counts['holds']} hold, {counts['partly']} partly, "
        f"{counts['differs']} differ ({time.perf_counter() - start:.0f} s); "
        f"wrote {out / 'index.html'} and {out / 'README.md'}"
    )


@friendly_errors
def power_command(
    out: Annotated[Path, typer.Option("--out", "-o", help="Output folder.")],
    a: Annotated[
        list[str],
        typer.Option("--a", help="Group A's prototype: NAME=VALUE (gene or shape); repeatable."),
    ],
    b: Annotated[
        list[str] | None,
        typer.Option("--b", help="Group B's prototype, NAME=VALUE; repeatable."),
    ] = None,
    difference: Annotated[
        list[str] | None,
        typer.Option(
            "--difference", help="Or: B = A plus NAME=VALUE (clipped to [0, 1]); repeatable."
        ),
    ] = None,
    power: Annotated[float, typer.Option("--power", help="Wanted power.")] = 0.8,
    alpha: Annotated[float, typer.Option("--alpha", help="Significance level.")] = 0.05,
    trials: Annotated[int, typer.Option("--trials", help="Faces per participant (averaged).")] = 1,
    participant_sd: Annotated[
        float,
        typer.Option(
            "--participant-sd", help="Participants' own spread per gene around the prototype."
        ),
    ] = 0.0,
    noise_temperature: Annotated[
        float, typer.Option("--noise-temperature", help="Simulated choice noise T (CD units).")
    ] = 0.0,
    generations: Annotated[int, typer.Option("--generations", help="G of the study.")] = 10,
    max_participants: Annotated[
        int, typer.Option("--max-participants", help="Largest n per group tried.")
    ] = 200,
    pool: Annotated[int, typer.Option("--pool", help="Simulated participants per group.")] = 500,
    replicates: Annotated[
        int, typer.Option("--replicates", help="Simulated experiments per n.")
    ] = 400,
    permutations: Annotated[
        int, typer.Option("--permutations", help="Permutations per test.")
    ] = 400,
    seed: SeedOpt = 1,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
) -> None:
    """How many participants per group tell two prototypes apart, given GA noise: a power
    curve (OUT/power.csv, OUT/power.png) and the number (OUT/power.json)."""
    import json

    import numpy as np

    from emogen.analysis import plots
    from emogen.analysis.power import final_faces_pool, power_analysis
    from emogen.config import GAConfig, SimulationConfig
    from emogen.errors import ConfigError
    from emogen.metrics import cosine_distance
    from emogen.model import load_model

    if (b is None) == (difference is None):
        raise ConfigError("give group B's prototype with --b or --difference (one of them)")
    model = load_model(model_path, rig=rig)
    r = model.rig
    wa = r.weights_from_names(parse_named_weights(a, "--a"))
    if b is not None:
        wb = r.weights_from_names(parse_named_weights(b, "--b"))
    else:
        wb = np.clip(
            wa + r.weights_from_names(parse_named_weights(difference, "--difference")), 0, 1
        )
    cfg = SimulationConfig(
        ga=GAConfig(generations=generations),
        target={"jawOpen": 1.0},
        noise_temperature=noise_temperature,
    )
    pools = [
        final_faces_pool(cfg, r, w, pool=pool, seed=seed + k, participant_sd=participant_sd)
        for k, w in enumerate((wa, wb))
    ]
    settings: dict[str, object] = {
        "prototype_cd": float(cosine_distance(wa, wb)),
        "participant_sd": participant_sd,
        "noise_temperature": noise_temperature,
        "generations": generations,
        "pool": pool,
        "seed": seed,
    }
    res = power_analysis(
        pools[0],
        pools[1],
        target_power=power,
        alpha=alpha,
        trials=trials,
        max_n=max_participants,
        replicates=replicates,
        permutations=permutations,
        seed=seed,
        settings=settings,
    )
    out.mkdir(parents=True, exist_ok=True)
    res.curve.to_csv(out / "power.csv", index=False)
    plots.power_curve(res.curve, out / "power.png", target=power, n_required=res.n_required)
    summary = {
        "n_required": res.n_required,
        "n_observed": res.n_observed,
        "fit_logit_intercept_slope": res.fit,
        "power": power,
        "alpha": alpha,
        "effect_cd": res.effect_cd,
        **res.settings,
    }
    (out / "power.json").write_text(json.dumps(summary, indent=2) + "\n")
    for row in res.curve.itertuples():
        typer.echo(
            f"  n = {row.n:>4}: power {row.power:.2f} ± {row.se:.2f} (fitted {row.fitted:.2f})"
        )
    if res.n_required is None:
        typer.echo(f"power {power} not reached within {max_participants} participants per group")
    else:
        typer.echo(
            f"{res.n_required} participants per group reach power {power} (α = {alpha}; fitted "
            f"curve; smallest simulated n at or above it: {res.n_observed})"
        )
    typer.echo(f"wrote {out / 'power.csv'}, {out / 'power.png'}, {out / 'power.json'}")


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
