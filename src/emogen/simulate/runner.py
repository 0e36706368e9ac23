"""Simulated studies: many runs, seeds spawned per run, tidy tables, a record.

:func:`run_simulation` spawns one child seed per run from the simulation's seed, groups the
runs into tasks and has a backend compute them (:mod:`emogen.simulate.backends`; vectorised
across runs, :mod:`emogen.simulate.vectorised`). It returns two tidy tables:

* ``table`` — one row per run and generation: ``run, generation, elite_error`` (CD of the
  elite to the target, the paper's convergence measure), ``elite_distance`` (the selection
  metric's distance of the elite), ``n_selected``, ``run_seed``;
* ``faces`` — one row per shown face: ``run, generation, slot, operator, distance, error,
  rank`` (0 elite, 1… other selections in choice order, NA not selected), and with
  ``all_weights`` one column ``w_<shape>`` per shape holding the shown full weights (named as
  in study exports; the table is itself a face table for targets and training sets);

and a record (schema, package version, model, resolved config, seeds, target, metric),
written as ``simulation.json`` and into every Parquet file's metadata. Column types and the CSV
form (seeds as ``s<digits>``) follow :mod:`emogen.columns`; every column is in docs/data.md.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from emogen import columns as tidy
from emogen.config import SimulationConfig
from emogen.errors import ConfigError
from emogen.ga.draws import CURRENT_STREAM
from emogen.ga.genome import PARAMS
from emogen.ga.init import read_fixed_sets
from emogen.model.rig import Rig
from emogen.rng import fresh_seed, spawn_seeds
from emogen.simulate.backends import Backend, LocalBackend, Task
from emogen.simulate.dynamic import DynamicView, dynamic_view
from emogen.simulate.observer import make_metric, selection_count
from emogen.simulate.problem import Problem, RunArrays, make_correction
from emogen.simulate.targets import resolve_target
from emogen.simulate.vectorised import engine_run

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

#: ``/3``: the record names the GA stream (``ga_stream``, :mod:`emogen.ga.draws`) its runs drew.
#: ``/4``: faces' weight columns are ``w_<shape>`` (as study exports), ``rank`` NA (not −1) for
#: a face not selected, the record in every Parquet file's metadata. ``/3`` outputs still read.
RECORD_SCHEMA = "emogen.simulate/4"
COLUMNS = ("run", "generation", "elite_error", "elite_distance", "n_selected", "run_seed")
#: A dynamic simulation's table also has these (its faces: ``peak_error``, ``timing_error``).
DYNAMIC_COLUMNS = ("elite_peak_error", "elite_timing_error")
DYNAMIC_ERROR = (
    " over the trajectory (every shape at every sampled time); elite_peak_error the CD of the "
    "peak profiles, elite_timing_error the latencies' weighted RMS difference in seconds "
    "(emogen.metrics.dynamic)"
)
FACE_COLUMNS = ("run", "generation", "slot", "operator", "distance", "error", "rank")


@dataclass(frozen=True)
class SimulationResult:
    """table: one row per run and generation (``COLUMNS``); faces: one row per shown face
    (``FACE_COLUMNS`` + shape weights with ``all_weights``); record: how it was made."""

    table: pd.DataFrame
    record: dict[str, Any]
    faces: pd.DataFrame | None = None


def _split(source: Rig | FaceModel) -> tuple[Rig, FaceModel | None]:
    if isinstance(source, Rig):
        return source, None
    return source.rig, source


def build_problem(
    config: SimulationConfig,
    source: Rig | FaceModel,
    *,
    all_weights: bool = False,
    training: np.ndarray | None = None,
) -> Problem:
    """Resolve a config against a rig or face model: target, metric, fixed sets, corrections.

    Vertex metrics and corrections need a FaceModel; a non-generic ``ga.identity`` evaluates
    that identity's faces. ``training`` (n, n_shapes) overrides ``metric.training``.
    """
    rig, model = _split(source)
    if config.dynamic is not None and (config.metric.name != "cd" or config.correct):
        raise ConfigError(
            "a dynamic simulation's observer selects by CD over the trajectory: it needs "
            f"metric 'cd' and correct = false; got metric '{config.metric.name}', correct = "
            f"{str(config.correct).lower()}"
        )
    if model is not None and config.ga.identity != "generic":
        model = model.with_identity(config.ga.identity)
    target = resolve_target(config, rig)
    correction = make_correction(model) if config.correct else None
    metric = make_metric(
        config.metric,
        rig,
        model=model,
        eye_motion=config.ga.eye_motion,
        training=training,
        correctives=correction.deltas if correction is not None else None,
    )
    fixed = None
    if config.ga.init.kind == "fixed":
        fixed = read_fixed_sets(
            config.ga.init.fixed_file,
            rig,
            eye_motion=config.ga.eye_motion,
            population_size=config.ga.population_size,
        )
    shown_target = target.weights if correction is None else correction(target.weights[None])[0]
    view = None
    if config.dynamic is not None:
        view = dynamic_view(config.dynamic, rig, target.weights, config.ga.eye_motion)
    return Problem(
        config, rig, shown_target, metric, fixed, correction, all_weights, target.source, view
    )


def run_tasks(problem: Problem, seeds: list[int], backend: Backend) -> list[Task]:
    """The runs cut into tasks of ``backend.chunk_size`` runs."""
    size = backend.chunk_size(len(seeds))
    runs = np.arange(len(seeds))
    seed_arr = np.array(seeds, dtype=np.int64)
    return [
        Task(problem, runs[lo : lo + size], seed_arr[lo : lo + size])
        for lo in range(0, len(seeds), size)
    ]


def run_simulation(
    config: SimulationConfig,
    source: Rig | FaceModel,
    *,
    model_name: str = "",
    model_hash: str = "",
    backend: Backend | None = None,
    progress: bool = False,
    all_weights: bool = False,
    training: np.ndarray | None = None,
) -> SimulationResult:
    """``config.runs`` independent runs; run r uses the r-th spawned child of the seed.

    ``source`` is the rig (enough for CD and ED) or the face model (vertex metrics, corrections).
    A config without a seed gets a fresh one, recorded in the result's resolved config.
    """
    seed = config.seed if config.seed is not None else fresh_seed()
    config = config.model_copy(update={"seed": seed})
    problem = build_problem(config, source, all_weights=all_weights, training=training)
    seeds = spawn_seeds(seed, config.runs)
    backend = backend or LocalBackend()
    tasks = run_tasks(problem, seeds, backend)
    start = time.perf_counter()
    with progress_bar(progress, config.runs * problem.n_generations, "simulating") as advance:
        arrays = RunArrays.concatenate([r for _, r in backend.run(tasks, advance)])
    seconds = time.perf_counter() - start
    return make_result(
        problem,
        arrays,
        model_name=model_name,
        model_hash=model_hash,
        extra={
            "backend": backend.name,
            "compute_seconds": seconds,
        },
    )


def make_result(
    problem: Problem,
    arrays: RunArrays,
    *,
    model_name: str = "",
    model_hash: str = "",
    extra: dict[str, Any] | None = None,
) -> SimulationResult:
    """Tables and record from the arrays of every run."""
    from emogen import __version__

    config, rig = problem.config, problem.rig
    table, faces = tables(problem, arrays)
    record = {
        "schema": RECORD_SCHEMA,
        "emogen_version": __version__,
        "model": {"name": model_name, "hash": model_hash},
        "rig": {"name": rig.name, "genes": list(rig.gene_names(config.ga.eye_motion))},
        "config": config.model_dump(mode="json"),
        "seed": config.seed,
        "run_seeds": [int(s) for s in arrays.seeds],
        "ga_stream": CURRENT_STREAM,
        "target_weights": {
            s: float(w) for s, w in zip(problem.columns, problem.target, strict=True) if w != 0
        },
        "target_source": problem.target_source,
        "metric": problem.metric.description,
        "metric_details": problem.metric.details,
        "error": "elite_error is the CD (eq. 12) of the elite to the target"
        + ("" if problem.dynamic is None else DYNAMIC_ERROR),
        "corrected": problem.correction is not None,
        "observer": {
            "noise_temperature": config.noise_temperature,
            "selections": [
                selection_count(config, g, config.ga.population_size)
                for g in range(problem.n_generations)
            ],
        },
        **(extra or {}),
    }
    if problem.dynamic is not None:
        record["dynamic_target"] = dynamic_record(problem, problem.dynamic)
    if config.ga.init.kind == "fixed":
        record["fixed_options"] = [int(o) for o in arrays.fixed_options]
    return SimulationResult(table, record, faces)


def tables(problem: Problem, a: RunArrays) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(per run and generation, per face) tidy tables."""
    r, n_gen, n = a.distance.shape
    elite = np.argmax(a.rank == 0, axis=2)  # (R, G+1)
    ri, gi = np.meshgrid(np.arange(r), np.arange(n_gen), indexing="ij")
    table = pd.DataFrame(
        {
            "run": np.repeat(a.runs, n_gen),
            "generation": np.tile(np.arange(n_gen), r),
            "elite_error": a.error[ri, gi, elite].reshape(-1),
            "elite_distance": a.distance[ri, gi, elite].reshape(-1),
            "n_selected": (a.rank >= 0).sum(axis=2).reshape(-1).astype(np.int64),
            "run_seed": np.repeat(a.seeds, n_gen),
        }
    )
    faces = pd.DataFrame(
        {
            "run": np.repeat(a.runs, n_gen * n),
            "generation": np.tile(np.repeat(np.arange(n_gen), n), r),
            "slot": np.tile(np.arange(n), r * n_gen),
            "operator": pd.Categorical(a.operators.reshape(-1)),
            "distance": a.distance.reshape(-1),
            "error": a.error.reshape(-1),
            "rank": pd.array(a.rank.reshape(-1), dtype="Int64"),
        }
    )
    if a.peak_error is not None and a.timing_error is not None:
        table["elite_peak_error"] = a.peak_error[ri, gi, elite].reshape(-1)
        table["elite_timing_error"] = a.timing_error[ri, gi, elite].reshape(-1)
        faces["peak_error"] = a.peak_error.reshape(-1)
        faces["timing_error"] = a.timing_error.reshape(-1)
    faces.loc[faces["rank"] < 0, "rank"] = pd.NA
    faces["operator"] = faces["operator"].astype("string")
    if a.weights is not None:
        w = a.weights.reshape(-1, a.weights.shape[-1])
        weights = pd.DataFrame(w, columns=[f"w_{c}" for c in problem.columns])
        faces = pd.concat([faces, weights], axis=1)
    return tidy.typed(table), tidy.typed(faces)


def dynamic_record(problem: Problem, view: DynamicView) -> dict[str, Any]:
    """A dynamic target's genes in the record: per gene shown, amplitude and timing."""
    names = problem.rig.gene_names(problem.config.ga.eye_motion)
    return {
        "genes": {
            names[k]: dict(zip(PARAMS, map(float, view.target[k]), strict=True))
            for k in np.flatnonzero(view.target[:, 0] > 0)
        },
        "sample_times_s": [float(t) for t in view.times],
        "genome": problem.genome.to_dict(),
    }


def simulate_run(
    config: SimulationConfig, rig: Rig, target: np.ndarray, seed: int
) -> tuple[np.ndarray, np.ndarray]:
    """One run through the engine (the reference): (elite CD error per generation (G+1,),
    faces selected per generation (G+1,)). The metric must work on a rig (cd, ed)."""
    problem = replace(build_problem(config, rig), target=np.asarray(target, dtype=np.float64))
    a = engine_run(problem, 0, seed)
    elite = np.argmax(a.rank[0] == 0, axis=1)
    return a.error[0, np.arange(len(elite)), elite], (a.rank[0] >= 0).sum(axis=1)


def summary(table: pd.DataFrame) -> pd.DataFrame:
    """Mean and standard deviation of the elite error per generation."""
    return table.groupby("generation")["elite_error"].agg(["mean", "std"])


def write_simulation(result: SimulationResult, out: Path, *, csv: bool = True) -> list[Path]:
    """``simulation.parquet`` (+ ``.csv``), ``simulation.json`` (the record) and
    ``faces.parquet`` (+ ``.csv``) in ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    record = {**result.record, "git_commit": tidy.git_commit()}
    paths = [tidy.write_parquet(result.table, out / "simulation.parquet", record)]
    if csv:
        paths.append(tidy.write_csv(result.table, out / "simulation.csv"))
    paths.append(out / "simulation.json")
    paths[-1].write_text(json.dumps(record, indent=2) + "\n")
    if result.faces is not None:
        paths.append(tidy.write_parquet(result.faces, out / "faces.parquet", record))
        if csv:
            paths.append(tidy.write_csv(result.faces, out / "faces.csv"))
    return paths


@contextmanager
def progress_bar(enabled: bool, total: int, label: str) -> Iterator[Callable[[int], None] | None]:
    """A rich progress bar on stderr, or nothing: yields ``advance(k)`` (or None)."""
    if not enabled:
        yield None
        return
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn

    with Progress(
        "{task.description}",
        BarColumn(),
        MofNCompleteColumn(),
        "run-generations",
        TimeElapsedColumn(),
        console=Console(stderr=True),
        transient=True,
    ) as bar:
        task = bar.add_task(label, total=total)
        yield lambda k: bar.advance(task, k)
