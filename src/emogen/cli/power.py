"""``emogen power``: how many participants per group tell two prototypes apart."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from emogen.cli.options import (
    FigureFormatOpt,
    ModelOpt,
    RigOpt,
    SeedOpt,
    friendly_errors,
    parse_named_weights,
)

if TYPE_CHECKING:
    import numpy as np

    from emogen.analysis.power import PowerResult
    from emogen.model.rig import Rig

__all__ = ["power_command"]

OutOpt = Annotated[Path, typer.Option("--out", "-o", help="Output folder.")]
GroupAOpt = Annotated[
    list[str],
    typer.Option("--a", help="Group A's prototype: NAME=VALUE (gene or shape); repeatable."),
]
GroupBOpt = Annotated[
    list[str] | None,
    typer.Option("--b", help="Group B's prototype, NAME=VALUE; repeatable."),
]
DifferenceOpt = Annotated[
    list[str] | None,
    typer.Option("--difference", help="Or: B = A plus NAME=VALUE (clipped to [0, 1]); repeatable."),
]
PowerOpt = Annotated[float, typer.Option("--power", help="Wanted power.")]
AlphaOpt = Annotated[float, typer.Option("--alpha", help="Significance level.")]
TrialsOpt = Annotated[int, typer.Option("--trials", help="Faces per participant (averaged).")]
ParticipantSdOpt = Annotated[
    float,
    typer.Option(
        "--participant-sd", help="Participants' own spread per gene around the prototype."
    ),
]
NoiseOpt = Annotated[
    float, typer.Option("--noise-temperature", help="Simulated choice noise T (CD units).")
]
GenerationsOpt = Annotated[int, typer.Option("--generations", help="G of the study.")]
MaxParticipantsOpt = Annotated[
    int, typer.Option("--max-participants", help="Largest n per group tried.")
]
PoolOpt = Annotated[int, typer.Option("--pool", help="Simulated participants per group.")]
ReplicatesOpt = Annotated[int, typer.Option("--replicates", help="Simulated experiments per n.")]
PermutationsOpt = Annotated[int, typer.Option("--permutations", help="Permutations per test.")]


def check_group_b(b: list[str] | None, difference: list[str] | None) -> None:
    """Group B is given one way: its prototype (``--b``) or its difference from A."""
    from emogen.errors import ConfigError

    if (b is None) == (difference is None):
        raise ConfigError("give group B's prototype with --b or --difference (one of them)")


def prototypes(
    rig: Rig, a: list[str], b: list[str] | None, difference: list[str] | None
) -> tuple[np.ndarray, np.ndarray]:
    """Group A's and group B's prototype weights (B given, or A plus a difference)."""
    import numpy as np

    check_group_b(b, difference)
    wa = rig.weights_from_names(parse_named_weights(a, "--a"))
    if b is not None:
        return wa, rig.weights_from_names(parse_named_weights(b, "--b"))
    step = rig.weights_from_names(parse_named_weights(difference, "--difference"))
    return wa, np.clip(wa + step, 0, 1)


def _write(out: Path, res: PowerResult, power: float, alpha: float) -> None:
    from emogen import columns as tidy
    from emogen.analysis import plots

    out.mkdir(parents=True, exist_ok=True)
    tidy.write_csv(res.curve, out / "power.csv")
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


def _print(res: PowerResult, power: float, alpha: float, max_participants: int) -> None:
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


@friendly_errors
def power_command(
    out: OutOpt,
    a: GroupAOpt,
    b: GroupBOpt = None,
    difference: DifferenceOpt = None,
    power: PowerOpt = 0.8,
    alpha: AlphaOpt = 0.05,
    trials: TrialsOpt = 1,
    participant_sd: ParticipantSdOpt = 0.0,
    noise_temperature: NoiseOpt = 0.0,
    generations: GenerationsOpt = 10,
    max_participants: MaxParticipantsOpt = 200,
    pool: PoolOpt = 500,
    replicates: ReplicatesOpt = 400,
    permutations: PermutationsOpt = 400,
    seed: SeedOpt = 1,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
    figure_format: FigureFormatOpt = None,
) -> None:
    """How many participants per group tell two prototypes apart, given GA noise: a power
    curve (OUT/power.csv, OUT/power.png) and the number (OUT/power.json)."""
    from emogen.analysis import plots
    from emogen.analysis.power import final_faces_pool, power_analysis
    from emogen.config import GAConfig, SimulationConfig
    from emogen.metrics import cosine_distance
    from emogen.model import load_model

    check_group_b(b, difference)  # before loading the model
    plots.check_formats(figure_format or ["png", "svg"])
    r = load_model(model_path, rig=rig).rig
    wa, wb = prototypes(r, a, b, difference)
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
    with plots.formats(figure_format or ["png", "svg"]):
        _write(out, res, power, alpha)
    _print(res, power, alpha, max_participants)
    typer.echo(f"wrote {out / 'power.csv'}, {out / 'power.png'}, {out / 'power.json'}")
