"""``emogen simulate --dynamic``: the settings it reads and what it writes beside a simulation."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

if TYPE_CHECKING:
    import pandas as pd

    from emogen.config import SimulationConfig
    from emogen.model.face import FaceModel
    from emogen.simulate.backends import Backend
    from emogen.simulate.runner import SimulationResult

DynamicOpt = Annotated[
    bool | None,
    typer.Option(
        "--dynamic/--static",
        help="Dynamic faces: the target moves (give --target-timing) and the GA evolves time "
        "courses; also runs held timing and static with the same seed (convergence.png).",
    ),
]
TargetTimingOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--target-timing",
        help="A target gene's timing NAME=ONSET,ACCELERATION,PEAK,DECELERATION,OFFSET (each in "
        "[0, 1]; docs/ga.md); one per gene of the target, repeatable.",
    ),
]
HoldTimingOpt = Annotated[
    bool | None,
    typer.Option("--hold-timing", help="Dynamic: evolve amplitudes only, timing the target's."),
]


def parse_timing(items: list[str]) -> dict[str, list[float]]:
    """``["jawOpen=0.1,0.3,0.4,0.5,0.5"]`` → ``{"jawOpen": [0.1, …]}``; errors name the item."""
    from emogen.errors import ConfigError

    out: dict[str, list[float]] = {}
    for item in items:
        name, sep, values = item.partition("=")
        parts = values.split(",")
        if not sep or not name.strip() or len(parts) != 5:
            raise ConfigError(
                "--target-timing must look like NAME=ONSET,ACCELERATION,PEAK,DECELERATION,"
                f"OFFSET (five numbers in [0, 1]); got {item!r}"
            )
        try:
            out[name.strip()] = [float(p) for p in parts]
        except ValueError:
            raise ConfigError(
                f"--target-timing {item!r}: {values!r} are not five numbers"
            ) from None
    return out


def dynamic_settings(
    data: dict[str, Any], dynamic: bool | None, timing: list[str] | None, hold: bool | None
) -> dict[str, Any]:
    """The config table ``data`` with the command line's dynamic settings laid over it."""
    from emogen.errors import ConfigError

    if dynamic is False:
        if timing or hold:
            raise ConfigError("--target-timing and --hold-timing are for --dynamic, not --static")
        data.pop("dynamic", None)
        return data
    if dynamic is None and "dynamic" not in data and (timing or hold):
        raise ConfigError("--target-timing and --hold-timing need --dynamic")
    if dynamic is None and "dynamic" not in data:
        return data
    table = dict(data.get("dynamic") or {})
    if timing:
        table["timing"] = parse_timing(timing)
    if hold is not None:
        table["hold_timing"] = hold
    return {**data, "dynamic": table}


def simulate(
    cfg: SimulationConfig, model: FaceModel, backend: Backend, **kwargs: Any
) -> tuple[SimulationResult, pd.DataFrame | None]:
    """The simulation; a dynamic one with its comparison (held timing, static; same seed): the
    result (its record holding the comparison's last generation) and the convergence table."""
    from dataclasses import replace

    from emogen.rng import fresh_seed
    from emogen.simulate.convergence import compare_dynamic, convergence_table, final_rows
    from emogen.simulate.runner import run_simulation

    kwargs.update(model_name=model.name, model_hash=model.model_hash)
    if cfg.dynamic is None:
        return run_simulation(cfg, model, backend=backend, **kwargs), None
    if cfg.seed is None:
        cfg = cfg.model_copy(update={"seed": fresh_seed()})
    results = compare_dynamic(cfg, model, backend=backend, **kwargs)
    table = convergence_table(results)
    comparison = final_rows(table).to_dict(orient="records")
    result = results["dynamic"]
    return replace(result, record={**result.record, "comparison": comparison}), table


def write(result: SimulationResult, table: pd.DataFrame | None, folder: Path) -> list[Path]:
    """The simulation's files in ``folder``; for a dynamic one also ``convergence.csv`` (the
    table) and ``convergence.png`` (+ ``.svg``, its figure)."""
    from emogen.simulate.runner import write_simulation

    paths = write_simulation(result, folder)
    if table is None:
        return paths
    csv = folder / "convergence.csv"
    table.to_csv(csv, index=False)
    runs = len(result.record["run_seeds"])
    png = convergence_figure(
        table, folder / "convergence.png", title=f"{runs} runs, seed {result.record['seed']}"
    )
    return [*paths, csv, png, png.with_suffix(".svg")]


def convergence_figure(table: pd.DataFrame, path: Path, *, title: str = "") -> Path:
    """Three panels (total, peak shape, timing): mean elite error per generation with a band of
    ± 1 sd over runs (the paper's μ ± σ), one line per run kind (static dashed: it runs under
    held timing's line where they agree); the legend below. Returns the PNG's path."""
    from matplotlib.lines import Line2D
    from matplotlib.ticker import MaxNLocator

    from emogen.analysis.plots import colour, marker, new_figure, save_figure
    from emogen.simulate.convergence import PARTS, RUNS

    fig = new_figure(10.5, 3.2)
    axes = fig.subplots(1, len(PARTS))
    for ax, (part, (label, unit)) in zip(axes, PARTS.items(), strict=True):
        for i, kind in enumerate(RUNS):
            rows = table[(table["run_kind"] == kind) & (table["part"] == part)]
            if rows.empty:
                continue
            g = rows["generation"].to_numpy()
            mean, sd = rows["mean"].to_numpy(), rows["sd"].to_numpy()
            style = "--" if kind == "static" else "-"  # static under held timing: both show
            ax.plot(g, mean, style, color=colour(i), marker=marker(i + i // 2), ms=3, lw=1.2)
            ax.fill_between(g, mean - sd, mean + sd, color=colour(i), alpha=0.15, lw=0)
        ax.set_title(label, fontsize=8)
        ax.set_xlabel("generation", fontsize=8)
        ax.set_ylabel(f"elite error to the target ({unit})", fontsize=8)
        ax.set_ylim(bottom=0)
        ax.set_xlim(-0.3, float(table["generation"].max()) + 0.3)
        ax.xaxis.set_major_locator(MaxNLocator(nbins=6, integer=True))
    handles = [
        Line2D(
            [],
            [],
            ls="--" if k == "static" else "-",
            color=colour(i),
            marker=marker(i + i // 2),
            ms=3,
        )
        for i, k in enumerate(RUNS)
    ]
    fig.legend(
        handles, list(RUNS.values()), loc="outside lower center", ncol=3, fontsize=7, frameon=False
    )
    if title:
        fig.suptitle(title, fontsize=9)
    return save_figure(fig, path)


def with_convergence(
    table: pd.DataFrame | None, data: dict[str, Any], lines: list[str]
) -> tuple[dict[str, Any], list[str]]:
    """The summary with a dynamic run's last generation, each run kind and part, added."""
    from emogen.simulate.convergence import PARTS, RUNS, final_rows

    if table is None:
        return data, lines
    rows = final_rows(table)
    more = ["last generation, elite error (mean ± sd over runs):"]
    for kind in RUNS:
        for part, (label, unit) in PARTS.items():
            hit = rows[(rows["run_kind"] == kind) & (rows["part"] == part)]
            if len(hit):
                r = hit.iloc[0]
                more.append(f"  {kind:<12} {label:<44} {r['mean']:.3f} ± {r['sd']:.3f} {unit}")
    data = {**data, "convergence": rows.to_dict(orient="records")}
    return data, [*lines[:-1], *more, lines[-1]]
