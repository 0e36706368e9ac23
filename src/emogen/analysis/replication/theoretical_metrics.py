"""Section IV-B, first half: the targets (Fig. 6) and the theoretical metrics — separability
and accuracy of ED(α′), vrtx_rms(F) and CD(α) (Table I, Figs. 8–9)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from emogen.analysis import paper
from emogen.analysis.paper_targets import count_active, paper_targets
from emogen.analysis.replication.baselines import (
    Chance,
    chance_faces,
    matched_correct,
    permutation_chance,
)
from emogen.analysis.replication.conditions import Condition, ConditionRunner, ConditionSpec
from emogen.analysis.replication.findings import Finding, pm
from emogen.analysis.replication.geometry import FaceGeometry
from emogen.analysis.replication.intervals import Equivalence, Evidence, judged
from emogen.analysis.replication.mean_faces import MeanFaceTest
from emogen.analysis.replication.table_i_findings import table_i_findings
from emogen.analysis.separability import Separability, gmm_separability

METRIC_NAMES = {
    "ed": "ED(α′)",
    "vertex_rms": "vrtx_rms(F)",
    "cd": "CD(α)",
    "pca_ed": "ED(β)",
    "std_ed": "std_ED(β)",
    "mahalanobis": "MD(F)",
}
TABLE_I_TARGETS = ("target 1", "target 2", "target 3")
THEORETICAL = ("ed", "vertex_rms", "cd")


@dataclass(frozen=True, eq=False)
class Targets:
    """The targets' table (genes, shapes, the paper's analogue, largest weights) and their
    full weights (T, S) in the table's order."""

    table: pd.DataFrame
    names: list[str]
    weights: np.ndarray


def targets_summary(runner: ConditionRunner) -> Targets:
    targets = paper_targets(runner.rig)
    rows = []
    for name, named in targets.items():
        genes, shapes = count_active(runner.rig, named)
        rows.append(
            {
                "target": name,
                "genes": genes,
                "shapes": shapes,
                "paper": paper.TABLE_V[name][0],
                "weights": ", ".join(
                    f"{k} {v:.2f}" for k, v in sorted(named.items(), key=lambda kv: -kv[1])[:8]
                )
                + (" …" if len(named) > 8 else ""),
            }
        )
    weights = np.stack([runner.weights(t) for t in targets.values()])
    return Targets(pd.DataFrame(rows), list(targets), weights)


@dataclass(frozen=True, eq=False)
class TheoreticalMetrics:
    """conditions[metric][target]; separability in 2 PCA components and in 90% of the
    variance, per metric; ``summary`` (Table I analogue) and ``accuracy`` (Fig. 9: RMS of the
    mean face to the target, nose-wrinkle ratio) tables; the findings."""

    conditions: dict[str, dict[str, Condition]]
    separability: dict[str, Separability]
    separability_90: dict[str, Separability]
    summary: pd.DataFrame
    accuracy: pd.DataFrame
    findings: list[Finding]
    chance: dict[str, Chance] = field(default_factory=dict)  # per metric, 2 PCs


def _separability(sims: dict[str, Condition], n_pca: float, seed: int) -> Separability:
    x = np.concatenate([sims[t].final for t in TABLE_I_TARGETS])
    labels = np.repeat(np.arange(3), [len(sims[t].final) for t in TABLE_I_TARGETS])
    targets = np.stack([sims[t].target for t in TABLE_I_TARGETS])
    return gmm_separability(
        x,
        labels,
        TABLE_I_TARGETS,
        targets=targets,
        n_pca=n_pca,
        seed=seed,
        n_init=10 if n_pca >= 1 else 3,
    )


def theoretical_metrics(runner: ConditionRunner, geometry: FaceGeometry) -> TheoreticalMetrics:
    """Each metric's observer toward targets 1, 2 and 3; GMM separability of the pooled final
    elites; the mean faces' geometric accuracy."""
    targets = paper_targets(runner.rig)
    sims = {
        m: {
            t: runner.condition(f"{m} {t}", targets[t], ConditionSpec(metric=m))
            for t in TABLE_I_TARGETS
        }
        for m in THEORETICAL
    }
    seed = runner.settings.seed
    seps = {m: _separability(s, 2, seed) for m, s in sims.items()}
    seps90 = {m: _separability(s, 0.9, seed) for m, s in sims.items()}
    summary = pd.DataFrame(
        [
            {
                "metric": METRIC_NAMES[m],
                "accuracy": sep.accuracy,
                "matched accuracy": float(matched_correct(sep.labels, sep.predicted).mean()),
                "paper accuracy": paper.TABLE_I_ACCURACY[m],
                "one cluster per target": sep.one_to_one,
                "ARI": sep.ari,
                "accuracy, 90% variance": seps90[m].accuracy,
                **{f"{t} final CD": pm(*sims[m][t].stats()) for t in TABLE_I_TARGETS},
            }
            for m, sep in seps.items()
        ]
    )
    rms = {
        (m, t): geometry.rms_cm(sims[m][t].mean_face, sims[m][t].target)
        for m in sims
        for t in TABLE_I_TARGETS
    }
    accuracy = pd.DataFrame(
        [
            {
                "metric": METRIC_NAMES[m],
                "target": t,
                "RMS to target [cm]": rms[(m, t)],
                "noseSneer / jawOpen": _nose_ratio(geometry, sims[m][t].mean_face),
            }
            for (m, t) in rms
        ]
    )
    rng = np.random.default_rng(seed)
    chance = {m: permutation_chance(sep.labels, sep.predicted, rng) for m, sep in seps.items()}
    said = "; ".join(f"{METRIC_NAMES[m]}: {c.text()}" for m, c in chance.items())
    chance_mean = chance_faces(runner.rig, 500, np.random.default_rng(seed * 1000 + 9)).mean(0)
    chance_ratio = _nose_ratio(geometry, chance_mean)
    findings = table_i_findings(sims, seps, seps90, said) + _accuracy_findings(
        sims, rms, geometry, chance_ratio
    )
    return TheoreticalMetrics(sims, seps, seps90, summary, accuracy, findings, chance)


def _nose_ratio(geometry: FaceGeometry, w: np.ndarray) -> float:
    return geometry.gene_ratio(w, "noseSneer", over="jawOpen")


def _accuracy_findings(
    sims: dict[str, dict[str, Condition]],
    rms: dict[tuple[str, str], float],
    geometry: FaceGeometry,
    chance_ratio: float,
) -> list[Finding]:
    worst = max(rms[("vertex_rms", t)] for t in TABLE_I_TARGETS)
    cd_worst = max(rms[("cd", t)] for t in TABLE_I_TARGETS)
    ed_worst = max(rms[("ed", t)] for t in TABLE_I_TARGETS)
    ratios = {m: _nose_ratio(geometry, sims[m]["target 3"].mean_face) for m in sims}

    def faces(kind: str, m1: str, m2: str, t: str, sign: int = 1, level: float = 0) -> Evidence:
        target = np.broadcast_to(sims[m1][t].target, sims[m1][t].final.shape)
        test = MeanFaceTest(kind, sign, level, seed=9, geometry=geometry)
        return Evidence(test, (sims[m1][t].final, sims[m2][t].final, target))

    lowest = [
        faces("rms", m, "vertex_rms", t, sign=+1) for t in TABLE_I_TARGETS for m in ("cd", "ed")
    ]
    t3 = "target 3"
    nose = [
        faces("ratio_gap", "cd", "ed", t3, sign=-1, level=0.6),
        faces("ratio_gap", "cd", "vertex_rms", t3, sign=-1, level=0.6),
        faces("ratio", "vertex_rms", "cd", t3, sign=-1),
    ]
    boot = "bootstrap of the mean faces over runs (95%, the metrics' runs paired)"
    return [
        judged(
            "Fig. 9",
            "vrtx_rms(F) minimises the overall geometric error of the mean face",
            "< 0.6 cm for all targets, the lowest",
            f"vrtx_rms max {worst:.2f} cm (CD: {cd_worst:.2f}, ED: {ed_worst:.2f} cm)",
            lowest,
            f"ci, {boot}: per target RMS(CD) − RMS(vrtx_rms) > 0 and RMS(ED) − RMS(vrtx_rms) "
            "> 0 (SESOI 0.05 cm); parts joined (rule join). The paper's < 0.6 cm is a "
            "model-specific absolute level: reported in the note, not judged",
            note=f"vrtx_rms(F)'s largest RMS {worst:.2f} cm against the paper's < 0.6 cm (our "
            "mesh, not the paper's)",
            value=worst,
            value_label="vrtx_rms worst RMS, cm",
        ),
        judged(
            "Fig. 9",
            "only CD(α) keeps target 3's nose wrinkle; vrtx_rms(F) drops it",
            "wrinkle error ≈ 0 cm (CD), 0.5 cm (ED), missing (vrtx_rms)",
            "noseSneer/jawOpen of the mean face (target 0.6): "
            + ", ".join(f"{METRIC_NAMES[m]} {v:.2f}" for m, v in ratios.items()),
            nose,
            f"ci, {boot}, target 3: CD's ratio closer to 0.6 than ED's and than vrtx_rms's; "
            "vrtx_rms's ratio below CD's (SESOI 0.05); parts joined (rule join)",
            note=f"chance (the mean of 500 faces as protocol initialisation draws them): ratio "
            f"{chance_ratio:.2f}",
            value=abs(ratios["cd"] - 0.6),
            value_label="|CD ratio − 0.6|",
        ),
        _jaw_finding(sims, geometry),
        judged(
            "Fig. 9",
            "ED(α′) and CD(α) perform similarly in mean accuracy (final CD error)",
            "ED and CD similar in mean accuracy",
            "μ10 CD / ED: "
            + ", ".join(
                f"{t} {sims['cd'][t].stats()[0]:.3f} / {sims['ed'][t].stats()[0]:.3f}"
                for t in TABLE_I_TARGETS
            ),
            [
                Evidence(
                    Equivalence(margin_sd=0.2),
                    (sims["ed"][t].final_errors, sims["cd"][t].final_errors),
                )
                for t in TABLE_I_TARGETS
            ],
            "tost, paired per run, per target: μ10 ED − CD within ±0.2 pooled SD; parts "
            "joined (rule join)",
            value_label="μ10 ED − CD, first target",
        ),
    ]


def _jaw_finding(sims: dict[str, dict[str, Condition]], geometry: FaceGeometry) -> Finding:
    """Fig. 9's local jaw error of target 1's mean face: ED ≈ 2 cm, CD ≈ 1 cm."""
    t1 = "target 1"
    jaw = {m: geometry.max_cm(sims[m][t1].mean_face, sims[m][t1].target) for m in ("ed", "cd")}
    target = np.broadcast_to(sims["ed"][t1].target, sims["ed"][t1].final.shape)
    test = MeanFaceTest("jaw", +1, seed=9, resamples=100, geometry=geometry)
    return judged(
        "Fig. 9",
        "ED(α′) leaves a larger jaw error than CD(α) (target 1's mean face)",
        "local error ≈ 2 cm (ED) vs ≈ 1 cm (CD)",
        f"largest vertex error: ED {jaw['ed']:.2f} cm, CD {jaw['cd']:.2f} cm",
        [Evidence(test, (sims["ed"][t1].final, sims["cd"][t1].final, target))],
        "ci, bootstrap of the mean faces over runs (95%, paired): largest vertex error ED − CD > 0",
        note="the cm themselves are model-specific (the paper's mesh is not ours): shown, not "
        "scored",
        value=jaw["ed"] - jaw["cd"],
        value_label="ED − CD jaw error, cm",
    )
