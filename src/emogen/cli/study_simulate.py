"""``emogen study simulate STUDY.toml --participants N``: pilot a study with simulated
participants through the real study service and database (:mod:`emogen.study.simulate`)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from emogen.cli.options import JsonOpt, friendly_errors, show_result, stage_printer
from emogen.errors import ConfigError

if TYPE_CHECKING:
    from emogen.study.config import StudyConfig


ArrivalsOpt = Annotated[
    tuple[str, int],
    typer.Option(
        "--arrivals",
        help="How participants arrive: 'sequential 1' (one after another) or 'concurrent N' "
        "(waves of N at once, as a panel's launch: nobody in a wave finishes before the "
        "others reach a labelling block).",
    ),
]


def wave_size(arrivals: tuple[str, int]) -> int:
    """The participants who arrive at once, from ``--arrivals`` (1: one after another)."""
    how, wave = arrivals
    if how not in ("sequential", "concurrent") or wave < 1 or (how == "sequential" and wave != 1):
        raise ConfigError(
            f"--arrivals must be 'sequential 1' or 'concurrent N' (N >= 1); got '{how} {wave}'"
        )
    return wave


@friendly_errors
def simulate_study_command(
    config: Annotated[Path, typer.Argument(help="The study TOML.", exists=False)],
    participants: Annotated[
        int, typer.Option("--participants", "-n", help="How many simulated participants.")
    ] = 20,
    database_url: Annotated[
        str | None,
        typer.Option(
            "--database-url",
            help="Where to record them: a database of their own (default: the SQLite file "
            "'<study name>-simulated.sqlite' in the current folder; never the study's own).",
        ),
    ] = None,
    seed: Annotated[int, typer.Option("--seed", help="Seed: same seed, same data.")] = 0,
    workers: Annotated[int, typer.Option("--workers", help="Worker processes.")] = 1,
    spread: Annotated[
        float, typer.Option("--spread", help="SD of participants' prototypes (gene units).")
    ] = 0.5,
    select_noise: Annotated[
        float, typer.Option("--select-noise", help="Softmax temperature of GA choices.")
    ] = 0.05,
    label_noise: Annotated[
        float, typer.Option("--label-noise", help="Softmax temperature of labels.")
    ] = 0.15,
    shuffle_prototypes: Annotated[
        bool,
        typer.Option(
            "--shuffle-prototypes",
            help="Each participant labels faces with another participant's prototypes (a null "
            "control: own faces are then no easier than others').",
        ),
    ] = False,
    model: Annotated[
        Path | None, typer.Option("--model", help="Face model (default: as in the config).")
    ] = None,
    arrivals: ArrivalsOpt = ("sequential", 1),
    as_json: JsonOpt = False,
) -> None:
    """Simulated participants run the whole study (every block, categorisation included)
    through the real study service into a database of their own, marked 'simulated'; then
    `emogen study export` and `emogen analyse` work on it as on a real study."""
    from emogen.study.simulate import SimulationPlan, simulate_study
    from emogen.tasks.simulated import SimulatedDesign

    wave = wave_size(arrivals)
    study, url = _study_and_database(config, seed, database_url)
    plan = SimulationPlan(
        config=study,
        database_url=url,
        seed=seed,
        participants=participants,
        design=SimulatedDesign(spread=spread, select_noise=select_noise, label_noise=label_noise),
        shuffle_prototypes=shuffle_prototypes,
        model_path=model,
        concurrent=wave,
    )
    show = stage_printer()
    if show is not None:
        show(f"simulating {participants} participants of study '{study.name}' into {url}")
    summary = simulate_study(
        plan,
        workers=workers,
        progress=None if show is None else lambda k, n: show(f"{k} of {n} participants done"),
    )
    steps = ", ".join(f"{n} {kind}" for kind, n in sorted(summary.by_task.items()))
    show_result(
        as_json,
        summary.to_dict(),
        [
            f"{summary.participants} simulated participants of study '{study.name}' recorded "
            f"in {summary.database} ({summary.seconds} s; steps: {steps})",
            f"next: emogen study export --database-url {url} --out OUT",
        ],
    )


def _study_and_database(
    config: Path, seed: int, database_url: str | None
) -> tuple[StudyConfig, str]:
    """The study config (seeded with ``seed`` when it names none: simulated sessions must
    replay from the seed they were given) and the database URL the simulation writes to."""
    from emogen.study.config import load_study_config

    if not config.is_file():
        raise ConfigError(f"study config {config} does not exist")
    study = load_study_config(config)
    if study.seed is None:
        study = study.model_copy(update={"seed": seed})
    url = database_url or f"sqlite:///{Path.cwd() / f'{study.name}-simulated.sqlite'}"
    if study.database_url and url == study.database_url:
        raise ConfigError(
            f"--database-url is the study's own database ({url}): simulated participants go "
            "into a database of their own"
        )
    return study, url
