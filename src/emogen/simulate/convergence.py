"""Convergence of a dynamic simulation beside its static counterparts (the paper's Fig. 18).

:func:`compare_dynamic` runs, with one seed, the dynamic simulation as configured, the same
with every gene's timing held at the target's, and the static simulation of the target's peak
profile. Held timing uses the static operators and draws, so it differs from the static run
only in what the observer compares (CD over the trajectory, not of the peaks). Its peak error
should follow the static run's error: the paper's static result reproduced when timing is
fixed. :func:`convergence_table` summarises each part per generation (mean, sd over runs) and
``emogen simulate --dynamic`` draws them (:mod:`emogen.cli.simulate_dynamic`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from emogen.config import SimulationConfig
from emogen.errors import ConfigError
from emogen.simulate.runner import SimulationResult, run_simulation

if TYPE_CHECKING:
    from emogen.model.face import FaceModel
    from emogen.model.rig import Rig
    from emogen.simulate.backends import Backend

#: The runs compared, in order: label → what it is.
RUNS = {
    "dynamic": "dynamic: amplitudes and timing evolve",
    "held_timing": "dynamic, timing held at the target's",
    "static": "static: the target's peak profile",
}
#: The parts of the error: column of the run table → (label, unit).
PARTS = {
    "elite_error": ("total: CD over the trajectory", "CD"),
    "elite_peak_error": ("peak shape: CD of the peak profiles", "CD"),
    "elite_timing_error": ("timing: latencies' weighted RMS difference", "s"),
}


def compare_dynamic(
    config: SimulationConfig,
    source: Rig | FaceModel,
    *,
    backend: Backend | None = None,
    **kwargs: Any,
) -> dict[str, SimulationResult]:
    """The three runs of :data:`RUNS` with ``config``'s seed (``config.dynamic`` required;
    with ``hold_timing`` the first two are the same run, made once). ``kwargs`` go to
    :func:`run_simulation`."""
    if config.dynamic is None:
        raise ConfigError("compare_dynamic needs a dynamic simulation config (dynamic = {…})")
    if config.seed is None:
        raise ConfigError("compare_dynamic needs a seed: its three runs must share it")
    held = config.model_copy(
        update={"dynamic": config.dynamic.model_copy(update={"hold_timing": True})}
    )
    static = config.model_copy(update={"dynamic": None})
    out = {"dynamic": run_simulation(config, source, backend=backend, **kwargs)}
    if config.dynamic.hold_timing:
        out["held_timing"] = out["dynamic"]
    else:
        out["held_timing"] = run_simulation(held, source, backend=backend, **kwargs)
    out["static"] = run_simulation(static, source, backend=backend, **kwargs)
    return out


def convergence_table(results: dict[str, SimulationResult]) -> pd.DataFrame:
    """One row per run kind, part and generation: ``run_kind, part, generation, mean, sd,
    runs`` (mean and sd of the elite's error over runs; a static run has a peak part only,
    its CD; runs with no timing distance, the elite sharing no shown gene with the target, are left
    out of the timing part's mean and counted in ``runs``)."""
    rows: list[pd.DataFrame] = []
    for kind, result in results.items():
        table = result.table
        if "elite_peak_error" not in table:  # a static run: its CD is the peak shape's only
            table = pd.DataFrame(
                {"generation": table["generation"], "elite_peak_error": table["elite_error"]}
            )
        for part in PARTS:
            if part not in table:
                continue
            stats = table.groupby("generation")[part].agg(["mean", "std", "count"])
            rows.append(
                pd.DataFrame(
                    {
                        "run_kind": kind,
                        "part": part,
                        "generation": stats.index.to_numpy(dtype=np.int64),
                        "mean": stats["mean"].to_numpy(),
                        "sd": stats["std"].to_numpy(),
                        "runs": stats["count"].to_numpy(dtype=np.int64),
                    }
                )
            )
    return pd.concat(rows, ignore_index=True)


def final_rows(table: pd.DataFrame) -> pd.DataFrame:
    """The last generation's rows of :func:`convergence_table`."""
    last = table["generation"].max()
    return table[table["generation"] == last].reset_index(drop=True)
