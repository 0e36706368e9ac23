"""``emogen analyse``'s GA-noise section: does each group's spread exceed the GA noise,
simulated on the model with the data's GA settings?"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from emogen.analysis import plots
from emogen.analysis.analyse_options import AnalysisOptions
from emogen.analysis.data import Dataset
from emogen.analysis.elites import final_faces_simulator
from emogen.analysis.face_sheets import model_weights
from emogen.analysis.noise import PAPER_NOISE, latent_spread_test, spread_test
from emogen.analysis.noise_empirical import empirical_spread_test, has_repeats
from emogen.analysis.report import Content
from emogen.analysis.results import Section
from emogen.config import PAPER_SELECTIONS, GAConfig, SimulationConfig

if TYPE_CHECKING:
    from emogen.model.face import FaceModel


def choice_noise(ds: Dataset, group: str, opts: AnalysisOptions) -> tuple[float, str]:
    """The choice noise T the null simulates, and where it comes from: given
    (``opts.choice_noise``), the simulation's own, or — for a study without one — an assumed 0.

    The null must include the choosers' noise: with a noiseless null, a noisy chooser's spread
    toward ONE shared target exceeds the GA noise and the test raises false alarms."""
    if opts.choice_noise is not None:
        return float(opts.choice_noise), "given"
    if ds.kind == "simulation" and group in ds.configs:
        return float(ds.configs[group].get("noise_temperature", 0.0) or 0.0), "the simulation's"
    return 0.0, "ASSUMED (not given)"


def noise_config(ds: Dataset, group: str, opts: AnalysisOptions) -> SimulationConfig:
    """The data's GA settings and choice noise for simulating GA noise (target filled in by
    the caller)."""
    temperature, _ = choice_noise(ds, group, opts)
    if ds.kind == "simulation" and group in ds.configs:
        cfg = dict(ds.configs[group])
        for k in ("target", "target_file", "target_row", "seed", "runs"):
            cfg.pop(k, None)
        cfg["metric"] = {"name": "cd"}
        cfg["noise_temperature"] = temperature
        cfg["correct"] = False
        return SimulationConfig.model_validate(cfg | {"target": {"jawOpen": 1.0}})
    ga = opts.ga or GAConfig(
        generations=ds.generations,
        population_size=ds.population_size,
        max_selections=ds.population_size,
        random_faces=min(4, ds.population_size - 1),
    )
    observed = list(ds.selections)[: ds.generations + 1]
    schedule = observed if len(observed) == ds.generations + 1 else list(PAPER_SELECTIONS)
    schedule = [min(max(int(s), ga.min_selections), ga.max_selections) for s in schedule]
    return SimulationConfig(
        ga=ga,
        target={"jawOpen": 1.0},
        selections=tuple(schedule),
        noise_temperature=temperature,
    )


def noise_section(
    ds: Dataset, out: Path, opts: AnalysisOptions, model: FaceModel | None
) -> Section:
    """Does each group's spread exceed the GA noise (unit: the participant's face)?"""
    report = Section(out)
    report.heading("GA noise: does each group's spread exceed it?")
    if not ds.has_weights:
        report.paragraph("Skipped: needs face weights.")
        return report
    rng = np.random.default_rng(opts.seed)
    rows, notes = [], []
    records: list[dict[str, Any]] = []
    candidates: list[dict[str, object]] = []
    candidate_records: list[dict[str, object]] = []
    for g in ds.groups:
        fw = ds.final_weights(g, one_per_participant=ds.kind == "study")
        if len(fw) < 2:
            notes.append(f"{g}: fewer than 2 final faces")
            continue
        if model is not None:
            faces = model_weights(fw, ds.columns, model)
            sim = final_faces_simulator(noise_config(ds, g, opts), model.rig, opts.seed)
            test, cands = latent_spread_test(
                faces,
                sim,
                group=g,
                alpha=opts.alpha,
                draws=opts.noise_draws,
                pool_runs=opts.noise_runs,
                rng=rng,
            )
            candidates += [{"group": g, **c.row()} for c in cands]
            candidate_records += [{"group": g, **c.record()} for c in cands]
            chosen = next(c for c in cands if c.test.p_value == test.p_value)
            label, noise = chosen.noise.label, chosen.noise
        else:
            test = spread_test(
                fw, PAPER_NOISE, group=g, alpha=opts.alpha, draws=opts.noise_draws, rng=rng
            )
            label, noise = PAPER_NOISE.label, PAPER_NOISE
        row = test.row()
        row["GA noise μ ± σ (to target)"] = label
        t, source = choice_noise(ds, g, opts)
        row["choice noise T"] = t
        row["T source"] = source
        rows.append(row)
        records.append(
            {
                **test.record(),
                "ga_noise_mean_to_target": noise.mean,
                "ga_noise_sd_to_target": noise.sd,
                "choice_noise_t": t,
                "choice_noise_source": source,
            }
        )
    report.paragraph(_method_text(ds, opts, model))
    _assumption_note(report, rows)
    report.bullets([f"Skipped {n}" for n in notes])
    if rows:
        table = pd.DataFrame(rows)
        report.table(
            table, "spread_test", "Group spread against GA noise", data=pd.DataFrame(records)
        )
        report.figure(
            plots.spread(table, report.figures / "spread.png"),
            "Mean proxy error of each group against GA noise at the same n.",
        )
        report.data["spread_test"] = rows
        _register(report, rows, records, _unit(ds))
    if candidates:
        report.table(
            pd.DataFrame(candidates),
            "spread_candidates",
            "Latent-target candidates per group (τ: weights below τ × max zeroed)",
            data=pd.DataFrame(candidate_records),
        )
    if ds.kind == "study":
        empirical_section(ds, report, opts, model)
    return report


def _register(
    report: Section, rows: list[dict[str, object]], records: list[dict[str, Any]], unit: str
) -> None:
    """Each group's spread test in the plan: its row of ``data``, its numbers from the record
    (full precision; the excess over the null with its 95% interval as estimate)."""
    for row, rec in zip(rows, records, strict=True):
        report.add_test(
            f"spread_test[{row['group']}]",
            row,
            test=str(rec["method"]),
            p=rec["p"],
            n=rec["n"],
            unit=unit,
            estimate=rec["excess"],
            interval=(rec["excess_ci_low"], rec["excess_ci_high"]),
            level=0.95,
        )


def _unit(ds: Dataset) -> str:
    return "participant" if ds.kind == "study" else "simulated run"


def empirical_section(
    ds: Dataset, report: Section, opts: AnalysisOptions, model: FaceModel | None
) -> None:
    """Where participants repeated a group: their between-person spread against their own
    within-person spread (the empirical null, :mod:`emogen.analysis.noise_empirical`), added
    to ``sec``."""
    rng = np.random.default_rng(opts.seed)
    rows = []
    records: list[dict[str, Any]] = []
    for g in ds.groups:
        final = ds.final[ds.final["group"] == g]
        who = final["participant"].to_numpy()
        fw = final[list(ds.columns)].to_numpy(dtype=np.float64)
        faces = fw if model is None else model_weights(fw, ds.columns, model)
        if not has_repeats(who, faces):
            continue
        test = empirical_spread_test(faces, who, group=g, alpha=opts.alpha, rng=rng)
        rows.append(test.row())
        records.append(test.record())
    if not rows:
        return
    report.paragraph(
        "**Empirical null: repeated faces of the same participants.** Where participants made "
        "a group's emotion several times, the spread of their own repeated faces is the GA "
        "noise plus their choice noise, measured on them (no simulation, no assumed T). "
        "Between-person CD (faces of two participants) against within-person CD (two faces of "
        "one participant): the excess σ²_b (CD units, between − within) with a jackknife 95% "
        "interval over participants, and a one-sided permutation p (faces shuffled among "
        f"participants, each keeping their number of faces; 999 permutations; α = {opts.alpha})."
    )
    report.table(
        pd.DataFrame(rows),
        "spread_empirical",
        "Between-participant spread against within-participant (repeated) spread",
        data=pd.DataFrame(records),
    )
    report.data["spread_empirical"] = rows
    for row, rec in zip(rows, records, strict=True):
        report.add_test(
            f"spread_empirical[{row['group']}]",
            row,
            test="permutation (faces shuffled among participants)",
            p=rec["p"],
            n=rec["participants"],
            estimate=rec["excess_between_variance"],
            interval=(rec["excess_ci_low"], rec["excess_ci_high"]),
            level=0.95,
        )


def _method_text(ds: Dataset, opts: AnalysisOptions, model: FaceModel | None) -> str:
    """The section's paragraph: what the test compares, and against what."""
    unit = (
        "Unit: the participant — one final face per participant (the same one on every run), "
        "so repeated trials never count as more people. "
        if ds.kind == "study"
        else "Unit: the simulated run. "
    )
    return (
        unit
        + "Spread of a group = mean CD of its final faces to their mean (the proxy target). GA "
        "noise = the same statistic on random subsets of equal size from the final faces of "
        "simulated runs with one consistent target, the data's GA settings and the choosers' "
        "choice noise T (a softmax chooser, CD units: the simulation's own, or given with "
        "--choice-noise). The latent target "
        "is the least favourable of the sparse-to-dense candidates that reproduce the group's mean "
        "face (of all candidates when none does; see emogen.analysis.noise); the null's subsets "
        "are drawn from the group's faces and the simulated runs together; one-sided test at "
        f"α = {opts.alpha}. The paper's threshold for its model is {PAPER_NOISE.label} (CD to "
        "the true target)."
        + ("" if model is not None else " No face model was given: tested against the paper's μ.")
        + (
            " The data carry corrective weights: the test compares shape weights only "
            "(correctives are left out)."
            if model is not None and set(ds.columns) - set(model.rig.shape_names)
            else ""
        )
    )


def _assumption_note(report: Content, rows: list[dict[str, object]]) -> None:
    """Say loudly which groups' null assumed noiseless choosers."""
    assumed = [str(r["group"]) for r in rows if str(r["T source"]).startswith("ASSUMED")]
    if assumed:
        report.paragraph(
            "**Assumption: noiseless choosers (T = 0)** for "
            + ", ".join(assumed)
            + ". The choice noise of these participants is not known; T = 0 gives the "
            "narrowest null (any real choice noise widens the spread of ONE shared target), so "
            "'exceeds noise' here may be choice noise rather than different targets. Give the "
            "participants' T with --choice-noise to test against it."
        )
