"""``emogen power``: how many participants per group tell two prototypes apart."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from emogen.cli.options import (
    FigureFormatOpt,
    JsonOpt,
    ModelOpt,
    RigOpt,
    SeedOpt,
    friendly_errors,
    parse_named_weights,
    show_result,
)
from emogen.cli.outputs import ForceOpt, check_out_folder, output_folder

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
    float | None,
    typer.Option(
        "--participant-sd",
        min=0.0,
        help="Participants' own spread per gene around the prototype. Not given: 0, flagged as "
        "an assumption (the most optimistic case).",
    ),
]
NoiseOpt = Annotated[
    float | None,
    typer.Option(
        "--noise-temperature",
        min=0.0,
        help="Participants' choice noise T (softmax, in the observer metric's units). Not "
        "given: 0, flagged as an assumption (the most optimistic case).",
    ),
]
StatisticOpt = Annotated[
    str,
    typer.Option(
        "--statistic",
        help="Group difference tested: cd (composition only; blind to intensity) or ed "
        "(Euclidean distance of the mean faces; intensity-aware).",
    ),
]
ObserverOpt = Annotated[
    str,
    typer.Option(
        "--observer",
        help="How simulated participants judge similarity: cd (blind to intensity), ed or "
        "vertex_rms (intensity-aware).",
    ),
]
GenerationsOpt = Annotated[int, typer.Option("--generations", help="G of the study.")]
MaxParticipantsOpt = Annotated[
    int, typer.Option("--max-participants", help="Largest n per group tried.")
]
ReplicatesOpt = Annotated[int, typer.Option("--replicates", help="Simulated experiments per n.")]
PermutationsOpt = Annotated[int, typer.Option("--permutations", help="Permutations per test.")]


def check_choices(statistic: str, observer: str) -> None:
    """``--statistic`` and ``--observer`` name a known statistic and observer metric."""
    from emogen.analysis.power import STATISTICS
    from emogen.errors import ConfigError

    if statistic not in STATISTICS or observer not in ("cd", "ed", "vertex_rms"):
        raise ConfigError(
            f"--statistic must be cd or ed, --observer cd, ed or vertex_rms; got "
            f"{statistic!r}, {observer!r}"
        )


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
        "n_required_ci95": [res.required.lo, res.required.hi] if res.required else None,
        "n_required_method": res.required.method if res.required else None,
        "fit_chi2_p": res.required.fit_p if res.required else None,
        "fit_logit_intercept_slope": res.fit,
        "power": power,
        "alpha": alpha,
        "max_false_positive": res.max_false_positive,
        "effect_cd": res.effect_cd,
        "effect_ed": res.effect_ed,
        **res.settings,
    }
    (out / "power.json").write_text(json.dumps(summary, indent=2) + "\n")


def _lines(res: PowerResult, power: float, alpha: float, max_participants: int) -> list[str]:
    lines = []
    for row in res.curve.itertuples():
        fit = float(row.fitted)  # type: ignore[arg-type]
        fitted = f"fitted {fit:.2f}" if math.isfinite(fit) else "no fit"
        lines.append(
            f"  n = {row.n:>4}: power {row.power:.2f} ± {row.se:.2f} ({fitted}); "
            f"false positives {row.false_positive:.3f} ± {row.fp_se:.3f}"
        )
    if res.n_required is None:
        lines.append(f"power {power} not reached within {max_participants} participants per group")
    else:
        said = res.required.text() if res.required else f"{res.n_required} (fit)"
        lines.append(
            f"{said} participants per group reach power {power} (α = {alpha}; smallest "
            f"simulated n at or above it: {res.n_observed})"
        )
    return lines


def assumptions(participant_sd: float | None, noise_temperature: float | None) -> list[str]:
    """The design assumptions left at their most optimistic value, each said in words."""
    said = []
    if participant_sd is None:
        said.append(
            "participant spread assumed 0 (--participant-sd): every participant holds exactly "
            "the group's prototype"
        )
    if noise_temperature is None:
        said.append(
            "choice noise assumed 0 (--noise-temperature): every participant always picks the "
            "faces closest to their prototype"
        )
    return said


def intensity_check(wa: np.ndarray, wb: np.ndarray, statistic: str, observer: str) -> None:
    """Refuse a design that cannot see its own difference: prototypes that differ only in
    intensity (CD 0) tested by CD, or evolved by a CD observer."""
    import numpy as np

    from emogen.errors import ConfigError
    from emogen.metrics import cosine_distance

    if float(cosine_distance(wa, wb)) < 1e-9 and float(np.linalg.norm(wa - wb)) > 1e-9:
        blind = [
            f"--{k} cd" for k, v in (("statistic", statistic), ("observer", observer)) if v == "cd"
        ]
        if blind:
            raise ConfigError(
                "the prototypes differ only in intensity (CD 0), which "
                + " and ".join(blind)
                + " cannot see: use --statistic ed with --observer ed or vertex_rms"
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
    participant_sd: ParticipantSdOpt = None,
    noise_temperature: NoiseOpt = None,
    statistic: StatisticOpt = "cd",
    observer: ObserverOpt = "cd",
    generations: GenerationsOpt = 10,
    max_participants: MaxParticipantsOpt = 200,
    replicates: ReplicatesOpt = 400,
    permutations: PermutationsOpt = 400,
    seed: SeedOpt = 1,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
    force: ForceOpt = False,
    as_json: JsonOpt = False,
    figure_format: FigureFormatOpt = None,
) -> None:
    """How many participants per group tell two prototypes apart, given GA noise: a power
    curve with the test's false-positive rate at every n (OUT/power.csv, OUT/power.png) and the
    number (OUT/power.json). Every simulated experiment draws fresh participants."""
    import numpy as np

    from emogen.analysis import plots
    from emogen.analysis.power import GroupSampler, power_analysis
    from emogen.config import GAConfig, MetricConfig, SimulationConfig
    from emogen.metrics import cosine_distance
    from emogen.model import load_model

    check_group_b(b, difference)  # before loading the model
    check_choices(statistic, observer)
    plots.check_formats(figure_format or ["png", "svg"])  # a bad --format before any work
    check_out_folder(out, force=force)
    model = load_model(model_path, rig=rig)
    wa, wb = prototypes(model.rig, a, b, difference)
    intensity_check(wa, wb, statistic, observer)
    said = assumptions(participant_sd, noise_temperature)
    for line in said:
        typer.echo(f"ASSUMPTION: {line}; the power found is an upper bound", err=True)
    cfg = SimulationConfig(
        ga=GAConfig(generations=generations),
        target={"jawOpen": 1.0},
        noise_temperature=noise_temperature or 0.0,
        metric=MetricConfig.model_validate({"name": observer}),
    )
    samplers = [
        GroupSampler(cfg, model, w, seed + k, participant_sd or 0.0, trials)
        for k, w in enumerate((wa, wb))
    ]
    settings: dict[str, object] = {
        "prototype_cd": float(cosine_distance(wa, wb)),
        "prototype_ed": float(np.linalg.norm(wa - wb)),
        "participant_sd": participant_sd or 0.0,
        "noise_temperature": noise_temperature or 0.0,
        "observer": observer,
        "trials": trials,
        "generations": generations,
        "seed": seed,
        "assumptions": said,
    }
    res = power_analysis(
        samplers[0],
        samplers[1],
        target_power=power,
        alpha=alpha,
        max_n=max_participants,
        replicates=replicates,
        permutations=permutations,
        statistic=statistic,
        seed=seed,
        settings=settings,
    )
    with output_folder(out, force=force) as tmp, plots.formats(figure_format or ["png", "svg"]):
        _write(tmp, res, power, alpha)
    _show(as_json, out, res, power, alpha, max_participants, said)


def _show(
    as_json: bool,
    out: Path,
    res: PowerResult,
    power: float,
    alpha: float,
    max_participants: int,
    said: list[str],
) -> None:
    """The result: the curve and the number (text, or one JSON object with ``--json``)."""
    wrote = [str(out / name) for name in ("power.csv", "power.png", "power.json")]
    curve = res.curve.astype(object).where(res.curve.notna(), None)
    show_result(
        as_json,
        {
            "n_required": res.n_required,
            "n_observed": res.n_observed,
            "power": power,
            "alpha": alpha,
            "max_false_positive": res.max_false_positive,
            "curve": curve.to_dict(orient="records"),
            "assumptions": said,
            "wrote": wrote,
        },
        [
            *_lines(res, power, alpha, max_participants),
            *(f"ASSUMPTION: {line}" for line in said),
            f"wrote {', '.join(wrote)}",
        ],
    )
