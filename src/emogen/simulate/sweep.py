"""Sweeps: a grid of simulations (targets × metrics × init × selection schedules × GA variant)
run as one job, resumable, each cell written as soon as it finishes.

A sweep file (TOML)::

    runs = 500                    # any simulation setting but target/metric/selections
    seed = 1                      # required: a sweep resumes from its seed
    [ga]
    generations = 10
    [metric]                      # settings shared by the grid's metrics (training, …)
    training = "faces.parquet"

    [targets]                     # named targets: weights, or a row of a face table
    one = {jawOpen = 1.0}
    happy = {file = "happy.parquet", row = 0}

    [grid]
    metrics = ["cd", "ed"]
    init = ["protocol", "fixed"]
    variants = ["emogen", "classical"]
    [grid.selections]             # named schedules
    paper = [2, 4, 4, 4, 4, 4, 5, 5, 5, 5, 5]
    three = [3]

Relative paths are relative to the sweep file. Every cell uses the sweep's seed (common random
numbers: cells differ only by their settings, which sharpens comparisons between them). The
classical variant ranks the whole population, so it gets one cell per (target, metric, init),
with schedule ``ranking``.

Layout of the output folder: ``cells/<target>__<metric>__<init>__<schedule>__<variant>/``
holding ``simulation.parquet``, ``faces.parquet`` and ``simulation.json`` (whose
``config_hash`` covers the resolved config, the model hash, the bytes of every file the cell
reads and the output options); ``summary.parquet``/``.csv`` (one row per cell) and
``sweep.json``. A cell whose folder exists with a matching hash is skipped, so an interrupted
sweep resumes where it stopped; a cell is written to a temporary folder and renamed, so a
crash never leaves half a cell.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import pandas as pd
from pydantic import BaseModel, ConfigDict, Field

from emogen import columns as tidy
from emogen.config import (
    PAPER_SELECTIONS,
    MetricName,
    SimulationConfig,
    merge,
    read_toml,
    validate_config,
)
from emogen.errors import ConfigError
from emogen.model.rig import Rig
from emogen.rng import spawn_seeds
from emogen.simulate.backends import Backend, LocalBackend
from emogen.simulate.problem import RunArrays
from emogen.simulate.runner import (
    RECORD_SCHEMA,
    build_problem,
    make_result,
    progress_bar,
    run_tasks,
    write_simulation,
)
from emogen.simulate.targets import file_digest

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

SWEEP_SCHEMA = "emogen.sweep/1"
NAME = re.compile(r"^[A-Za-z0-9_-]+$")


class SweepGrid(BaseModel):
    """The grid's axes (the ``[grid]`` table)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    metrics: tuple[MetricName, ...] = Field(default=("cd",), min_length=1)
    init: tuple[Literal["protocol", "fixed"], ...] = Field(default=("protocol",), min_length=1)
    selections: dict[str, tuple[int, ...]] = Field(
        default_factory=lambda: {"paper": PAPER_SELECTIONS}, min_length=1
    )
    variants: tuple[Literal["emogen", "classical"], ...] = Field(default=("emogen",), min_length=1)


@dataclass(frozen=True)
class Cell:
    """One simulation of the grid: its name, its labels and its resolved config."""

    name: str
    labels: dict[str, str]
    config: SimulationConfig
    files: tuple[Path, ...] = ()


@dataclass(frozen=True)
class Sweep:
    cells: tuple[Cell, ...]
    source: str
    spec: dict[str, Any] = field(default_factory=dict)


def _resolve(path: Any, base: Path) -> str:
    p = Path(str(path))
    return str(p if p.is_absolute() else base / p)


def load_sweep(path: Path) -> Sweep:
    """Read and validate a sweep file: every cell's config is checked before anything runs."""
    path = Path(path)
    data = read_toml(path)
    return make_sweep(data, path.parent, str(path))


def make_sweep(data: dict[str, Any], base_dir: Path, source: str = "(sweep)") -> Sweep:
    """A sweep from its parsed TOML (``base_dir``: where relative paths start)."""
    data = dict(data)
    targets = data.pop("targets", None)
    grid = validate_config(SweepGrid, data.pop("grid", {}), f"{source} [grid]")
    for key in ("target", "target_file", "target_row", "selections"):
        if key in data:
            raise ConfigError(
                f"invalid sweep {source}: '{key}' is set per cell; use [targets] and [grid]"
            )
    if data.get("seed") is None:
        raise ConfigError(f"invalid sweep {source}: a sweep needs a seed (seed = …) to resume")
    if not isinstance(targets, dict) or not targets:
        raise ConfigError(f"invalid sweep {source}: [targets] must name at least one target")
    base_metric = dict(data.pop("metric", {}) or {})
    if isinstance(base_metric, str):
        raise ConfigError(f"invalid sweep {source}: metric names go in [grid] metrics")
    if "training" in base_metric:
        base_metric["training"] = _resolve(base_metric["training"], base_dir)
    for name in [*targets, *grid.selections]:
        if not NAME.match(name):
            raise ConfigError(
                f"invalid sweep {source}: names must use letters, digits, _ and -; got {name!r}"
            )
    cells = []
    for t_name, t_spec in targets.items():
        if not isinstance(t_spec, dict):
            raise ConfigError(f"invalid sweep {source}: target '{t_name}' must be a table")
        if "file" in t_spec:
            extra = set(t_spec) - {"file", "row"}
            if extra:
                raise ConfigError(
                    f"invalid sweep {source}: target '{t_name}' has file and {sorted(extra)}"
                )
            target: dict[str, Any] = {"target_file": _resolve(t_spec["file"], base_dir)}
            if "row" in t_spec:
                target["target_row"] = t_spec["row"]
        else:
            target = {"target": t_spec}
        for metric in grid.metrics:
            for init in grid.init:
                for variant in grid.variants:
                    schedules = (
                        {"ranking": PAPER_SELECTIONS} if variant == "classical" else grid.selections
                    )
                    for s_name, schedule in schedules.items():
                        cell_data = merge(
                            data,
                            {
                                **target,
                                "metric": {**base_metric, "name": metric},
                                "selections": list(schedule),
                                "ga": {"init": {"kind": init}, "variant": variant},
                            },
                        )
                        labels = {
                            "target": t_name,
                            "metric": metric,
                            "init": init,
                            "schedule": s_name,
                            "variant": variant,
                        }
                        name = "__".join(labels.values())
                        cfg = validate_config(SimulationConfig, cell_data, f"{source} cell {name}")
                        files = [p for p in (cfg.target_file, cfg.metric.training) if p]
                        cells.append(Cell(name, labels, cfg, tuple(files)))
    return Sweep(tuple(cells), source, {"grid": grid.model_dump(mode="json"), "targets": targets})


def cell_hash(cell: Cell, *, model_hash: str, all_weights: bool) -> str:
    """What a cell's output depends on: config, model, the files it reads, output options."""
    payload = {
        "schema": RECORD_SCHEMA,
        "config": cell.config.model_dump(mode="json"),
        "model": model_hash,
        "files": {str(p): file_digest(p) for p in cell.files},
        "all_weights": all_weights,
    }
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()


def _done(folder: Path, digest: str) -> bool:
    meta = folder / "simulation.json"
    if not (meta.is_file() and (folder / "simulation.parquet").is_file()):
        return False
    try:
        return json.loads(meta.read_text()).get("config_hash") == digest
    except (OSError, json.JSONDecodeError):
        return False


@dataclass(frozen=True)
class SweepResult:
    summary: pd.DataFrame
    ran: list[str]
    skipped: list[str]


def _pending(
    sweep: Sweep, cells_dir: Path, model_hash: str, all_weights: bool
) -> tuple[dict[str, str], list[Cell]]:
    """Each cell's hash, and the cells not yet done under it."""
    hashes = {
        c.name: cell_hash(c, model_hash=model_hash, all_weights=all_weights) for c in sweep.cells
    }
    pending = [c for c in sweep.cells if not _done(cells_dir / c.name, hashes[c.name])]
    return hashes, pending


def run_sweep(
    sweep: Sweep,
    source: Rig | FaceModel,
    out: Path,
    *,
    backend: Backend | None = None,
    progress: bool = False,
    all_weights: bool = False,
    model_name: str = "",
    model_hash: str = "",
) -> SweepResult:
    """Run every cell not already in ``out`` (same hash), writing each as it finishes."""
    out = Path(out)
    cells_dir = out / "cells"
    cells_dir.mkdir(parents=True, exist_ok=True)
    backend = backend or LocalBackend()
    hashes, pending = _pending(sweep, cells_dir, model_hash, all_weights)
    skipped = [c.name for c in sweep.cells if c not in pending]
    tasks, owner, problems = [], [], {}
    for c in pending:
        problem = build_problem(c.config, source, all_weights=all_weights)
        problems[c.name] = problem
        seed = c.config.seed if c.config.seed is not None else 0
        for t in run_tasks(problem, spawn_seeds(seed, c.config.runs), backend):
            tasks.append(t)
            owner.append(c.name)
    parts: dict[str, list[RunArrays]] = {c.name: [] for c in pending}
    left = {c.name: sum(1 for o in owner if o == c.name) for c in pending}
    by_name = {c.name: c for c in pending}
    total = sum(c.config.runs * problems[c.name].n_generations for c in pending)
    with progress_bar(progress, total, f"sweep: {len(pending)} cells") as advance:
        for i, arrays in backend.run(tasks, advance):
            name = owner[i]
            parts[name].append(arrays)
            left[name] -= 1
            if left[name] == 0:
                cell = by_name[name]
                result = make_result(
                    problems[name],
                    RunArrays.concatenate(parts.pop(name)),
                    model_name=model_name,
                    model_hash=model_hash,
                    extra={
                        "cell": name,
                        "labels": cell.labels,
                        "config_hash": hashes[name],
                        "backend": backend.name,
                    },
                )
                tmp = cells_dir / f".{name}.tmp{os.getpid()}"
                shutil.rmtree(tmp, ignore_errors=True)
                write_simulation(result, tmp, csv=False)
                shutil.rmtree(cells_dir / name, ignore_errors=True)
                tmp.rename(cells_dir / name)
    summary = sweep_summary(sweep, cells_dir)
    record = {
        "schema": SWEEP_SCHEMA,
        "source": sweep.source,
        "spec": sweep.spec,
        "model": {"name": model_name, "hash": model_hash},
        "cells": [{"name": c.name, **c.labels, "config_hash": hashes[c.name]} for c in sweep.cells],
    }
    tidy.write_parquet(summary, out / "summary.parquet", record)
    tidy.write_csv(summary, out / "summary.csv")
    (out / "sweep.json").write_text(json.dumps(record, indent=2) + "\n")
    return SweepResult(summary, [c.name for c in pending], skipped)


def sweep_summary(sweep: Sweep, cells_dir: Path) -> pd.DataFrame:
    """One row per cell: labels, runs, elite CD error at generation 0 and G (mean, sd)."""
    rows = []
    for c in sweep.cells:
        path = cells_dir / c.name / "simulation.parquet"
        if not path.is_file():
            continue
        t = pd.read_parquet(path)
        last = int(t["generation"].max())
        first_e = t.loc[t["generation"] == 0, "elite_error"].to_numpy()
        last_e = t.loc[t["generation"] == last, "elite_error"].to_numpy()
        rows.append(
            {
                "cell": c.name,
                **c.labels,
                "runs": int(t["run"].nunique()),
                "mu_0": float(np.mean(first_e)),
                "sigma_0": float(np.std(first_e, ddof=1)) if len(first_e) > 1 else float("nan"),
                "mu_final": float(np.mean(last_e)),
                "sigma_final": float(np.std(last_e, ddof=1)) if len(last_e) > 1 else float("nan"),
            }
        )
    return pd.DataFrame(rows)
