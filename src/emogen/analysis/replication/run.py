"""Running the replication: each section's experiment (typed inputs → typed result), then its
part of the report written from the result; the findings collected for the closing table."""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

from emogen.analysis.replication import write_ga, write_metrics, write_tools
from emogen.analysis.replication.analysis_tools import participant_tools, power_study
from emogen.analysis.replication.bias_repeatability import bias_repeatability
from emogen.analysis.replication.conditions import ConditionRunner
from emogen.analysis.replication.correctives import correctives, write_correctives
from emogen.analysis.replication.empirical_metrics import (
    TrainingSet,
    empirical_metrics,
    training_set,
)
from emogen.analysis.replication.findings import Finding
from emogen.analysis.replication.ga_settings import (
    activation_ranges,
    complexity_noise,
    selection_pressure,
)
from emogen.analysis.replication.geometry import FaceGeometry
from emogen.analysis.replication.initialisation import initialisation
from emogen.analysis.replication.interpenetration import interpenetration, write_interpenetration
from emogen.analysis.replication.intersample import intersample, write_intersample
from emogen.analysis.replication.settings import ReplicateSettings
from emogen.analysis.replication.theoretical_metrics import targets_summary, theoretical_metrics
from emogen.analysis.replication.verdicts import combine
from emogen.analysis.replication.write_report import FaceFigures, write_closing, write_intro
from emogen.analysis.report import Report

if TYPE_CHECKING:
    from emogen.model.face import FaceModel


@dataclass(eq=False)
class Bench:
    """What the sections share: the condition runner (its cache of simulations), face
    geometry and figures, a scratch folder, and the simulated participants' training set
    (made once, by the first section that needs it)."""

    runner: ConditionRunner
    geometry: FaceGeometry
    figures: FaceFigures
    workdir: Path
    _training: TrainingSet | None = field(default=None, repr=False)

    @property
    def settings(self) -> ReplicateSettings:
        return self.runner.settings

    def training(self) -> TrainingSet:
        if self._training is None:
            self._training = training_set(self.runner)
        return self._training


Section = Callable[[Bench, Report], list[Finding]]


def _targets(b: Bench, r: Report) -> list[Finding]:
    write_metrics.write_targets(r, targets_summary(b.runner), b.figures)
    return []


def _theoretical(b: Bench, r: Report) -> list[Finding]:
    res = theoretical_metrics(b.runner, b.geometry)
    write_metrics.write_theoretical(r, res, b.figures)
    return res.findings


def _empirical(b: Bench, r: Report) -> list[Finding]:
    training = b.training()
    res = empirical_metrics(b.runner, training, b.workdir)
    write_metrics.write_empirical(r, res, training, b.settings, b.figures)
    return res.findings


def _initialisation(b: Bench, r: Report) -> list[Finding]:
    res = initialisation(b.runner, b.geometry)
    write_ga.write_initialisation(r, res, b.figures)
    return res.findings


def _bias(b: Bench, r: Report) -> list[Finding]:
    res = bias_repeatability(b.runner)
    write_ga.write_bias_repeatability(r, res)
    return res.findings


def _ranges(b: Bench, r: Report) -> list[Finding]:
    res = activation_ranges(b.runner)
    write_ga.write_activation_ranges(r, res)
    return res.findings


def _complexity(b: Bench, r: Report) -> list[Finding]:
    res = complexity_noise(b.runner, b.geometry)
    write_ga.write_complexity_noise(r, res, b.figures)
    return res.findings


def _intersample(b: Bench, r: Report) -> list[Finding]:
    res = intersample(b.runner)
    write_intersample(r, res)
    return res.findings


def _selection(b: Bench, r: Report) -> list[Finding]:
    res = selection_pressure(b.runner)
    write_ga.write_selection_pressure(r, res)
    return res.findings


def _tools(b: Bench, r: Report) -> list[Finding]:
    res = participant_tools(b.runner, b.training())
    write_tools.write_participant_tools(r, res, b.settings)
    return res.findings


def _correctives(b: Bench, r: Report) -> list[Finding]:
    res = correctives(b.runner)
    write_correctives(r, res)
    return res.findings


def _interpenetration(b: Bench, r: Report) -> list[Finding]:
    res = interpenetration(b.runner, b.runner.model)
    write_interpenetration(r, res)
    return res.findings


def _power(b: Bench, r: Report) -> list[Finding]:
    write_tools.write_power(r, power_study(b.runner), b.settings)
    return []


SECTIONS: list[tuple[str, Section]] = [
    ("targets", _targets),
    ("theoretical metrics (Table I, Figs. 8-9)", _theoretical),
    ("empirical metrics (Table II, Figs. 10-13)", _empirical),
    ("initialisation (Figs. 14-17)", _initialisation),
    ("bias and repeatability (Table III)", _bias),
    ("activation ranges (Table IV)", _ranges),
    ("target complexity and GA noise (Table V, Fig. 18)", _complexity),
    ("inter-sample distance against simulation (Section IV-C)", _intersample),
    ("selection pressure", _selection),
    ("correctives (Section III-A)", _correctives),
    ("interpenetration (Section III-A, Figs. 1-3)", _interpenetration),
    ("analysis tools on simulated participants", _tools),
    ("power analysis", _power),
]


#: sections run on the first seed only: no paper findings (targets), or our own tools
SINGLE_SEED = (
    "targets",
    "correctives (Section III-A)",
    "analysis tools on simulated participants",
    "power analysis",
)


def replicate(
    model: FaceModel,
    out: Path,
    settings: ReplicateSettings | None = None,
    *,
    only: list[str] | None = None,
    progress: Callable[[str], None] | None = None,
    command: str | None = None,
) -> list[Finding]:
    """Run the sections (``only``: names containing one of these words) on every seed of
    ``settings``, write the report (tables and figures of the first seed, every verdict
    combined over the seeds) to ``out`` and return the combined findings."""
    from emogen import __version__

    s = settings or ReplicateSettings()
    title = "EmoGen: the paper's Section IV on our model" + (" (quick)" if s.quick else "")
    report = Report(title, Path(out))
    timings: dict[str, float] = {}
    start = time.perf_counter()
    glance_at = write_intro(report, model, s)
    prov = provenance(model, s, command)  # before anything is written into ``out``
    per_seed: list[list[Finding]] = []
    with tempfile.TemporaryDirectory(prefix="emogen-replicate-") as tmp:
        for k, seed in enumerate(s.seed_list):
            si = replace(s, seed=seed, render=s.render and k == 0)
            work = Path(tmp) / f"seed-{seed}"
            work.mkdir()
            bench = Bench(
                ConditionRunner(model, si), FaceGeometry(model), FaceFigures(model, si.render), work
            )
            target = report if k == 0 else Report("scratch", work / "report")
            found: list[Finding] = []
            for name, section in SECTIONS:
                if (only and not any(w in name for w in only)) or (k and name in SINGLE_SEED):
                    continue
                t0 = time.perf_counter()
                if progress:
                    progress(name + ("" if k == 0 else f" (seed {seed})"))
                found += section(bench, target)
                timings[name] = timings.get(name, 0.0) + time.perf_counter() - t0
            per_seed.append(found)
    combined = combine(per_seed)
    write_closing(
        report,
        combined,
        timings,
        glance_at=glance_at,
        seconds=time.perf_counter() - start,
        version=__version__,
        settings=s,
        provenance=prov,
    )
    report.write()
    return [c.as_finding() for c in combined]


def provenance(model: FaceModel, s: ReplicateSettings, command: str | None) -> dict[str, str]:
    """What reproduces the report: the git commit (and whether the tree was clean), the seeds,
    the model hash and the exact command."""
    import subprocess

    here = Path(__file__).resolve().parent
    try:
        commit = subprocess.run(
            ["git", "-C", str(here), "rev-parse", "HEAD"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "-C", str(here), "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        commit += " (uncommitted changes)" if dirty else ""
    except (OSError, subprocess.CalledProcessError):
        commit = "unknown (not a git checkout)"
    quick = " --quick" if s.quick else ""
    return {
        "git commit": commit,
        "seeds": ", ".join(str(x) for x in s.seed_list),
        "model hash": model.model_hash,
        "command": command
        or f"emogen replicate{quick} --seed {s.seed} --seeds {s.seeds} --out DIR",
    }
