"""The GSP analysis against known answers: a simulated population with a planted prototype per
concept (every participant shares it: ``spread = 0``) runs a GSP study; each gene's chain
aggregate must land on what the simulated chooser's choices average to — computed here with a
plain loop over the slider's positions — within its bootstrap interval, and the two concepts'
aggregates must be far apart. The comparison statistic (CD between means, bootstrap over units)
is checked against numpy on data drawn with a known difference."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

from emogen.analysis.analyse import AnalysisOptions, analyse
from emogen.study.config import study_from_dict
from emogen.study.export_stream import export_study
from emogen.study.simulate import SimulationPlan, simulate_study
from emogen.study.storage import Store
from emogen.tasks.gsp.analysis import compare
from emogen.tasks.simulated import SimulatedDesign, population_prototypes

DIMS = [
    "cheekSquint",
    "mouthSmile",
    "browInnerUp",
    "browDown",
    "mouthFrown",
    "jawOpen",
    "noseSneer",
    "eyeWide",
]
NOISE = 0.05


def expected_choice(prototype: float, grid: np.ndarray) -> float:
    """The mean slider value of a softmax chooser (temperature NOISE) whose prototype value of
    the gene is ``prototype``: a plain loop over the positions."""
    weights = [np.exp(-abs(v - prototype) / NOISE) for v in grid]
    return float(sum(w * v for w, v in zip(weights, grid, strict=True)) / sum(weights))


@pytest.fixture(scope="module")
def analysed(tmp_path_factory: pytest.TempPathFactory, ict_model: Any) -> dict[str, Any]:
    tmp = tmp_path_factory.mktemp("gsp-known")
    config = study_from_dict(
        {
            "name": "gsp-known",
            "emotions": ["happy", "sad"],
            "seed": 21,
            "correct": False,
            "blocks": [{"task": "gsp", "chains": 12, "iterations": 6, "dimensions": DIMS}],
        }
    )
    url = f"sqlite:///{tmp / 'known.sqlite'}"
    design = SimulatedDesign(spread=0.0, select_noise=NOISE)
    plan = SimulationPlan(
        config, url, seed=8, participants=40, design=design, shuffle_prototypes=False
    )
    simulate_study(plan, model=ict_model)
    store = Store(url)
    try:
        export_study(store, tmp / "export", "csv")
    finally:
        store.dispose()
    result = analyse(
        tmp / "export",
        tmp / "report",
        model=ict_model,
        options=AnalysisOptions(render=False, exclusions=None),
    )
    truth = population_prototypes(ict_model.rig, ["happy", "sad"], design, config.ga.eye_motion)
    return {"result": result, "truth": truth, "genes": ict_model.rig.gene_names(True)}


def test_each_aggregate_lands_on_the_planted_prototype(analysed: dict[str, Any]) -> None:
    table = pd.read_csv(analysed["result"].out / "tables" / "gsp_aggregates.csv")
    grid = np.linspace(0.0, 1.0, 41)
    covered = []
    for emotion, proto in analysed["truth"].items():
        rows = table[table["emotion"] == emotion].set_index("gene")
        for gene, p in zip(analysed["genes"], proto, strict=True):
            want = expected_choice(p, grid) if gene in DIMS else 0.0
            row = rows.loc[gene]
            if gene not in DIMS:  # never moved: the chains' starts zero it
                assert row["mean"] == 0.0 and row["ci_high"] == 0.0
                continue
            assert row["mean"] == pytest.approx(want, abs=0.06), (emotion, gene)
            covered.append(row["ci_low"] <= want <= row["ci_high"])
    assert np.mean(covered) >= 0.8, covered  # 95% intervals over 16 genes


def test_chains_converge_and_the_concepts_separate(analysed: dict[str, Any]) -> None:
    gsp = analysed["result"].summary["gsp"]
    for emotion, c in gsp["concepts"].items():
        assert c["n_chains"] == 12 and c["nodes"] >= 18, (emotion, c)
        assert c["between_chains_last"] < 0.5 * c["between_chains_first"], (emotion, c)
    (between,) = gsp["between_concepts"]
    grid = np.linspace(0.0, 1.0, 41)
    truth = {
        e: np.array(
            [
                expected_choice(p, grid) if g in DIMS else 0.0
                for g, p in zip(analysed["genes"], proto, strict=True)
            ]
        )
        for e, proto in analysed["truth"].items()
    }
    a, b = truth["happy"], truth["sad"]
    true_cd = 1 - a @ b / (np.linalg.norm(a) * np.linalg.norm(b))
    assert between["cd_low"] <= true_cd <= between["cd_high"], (between, true_cd)
    assert between["cd_low"] > 0.3
    curves = pd.read_csv(analysed["result"].out / "tables" / "gsp_convergence.csv")
    assert set(curves["emotion"]) == {"happy", "sad"} and (curves["n_chains"] <= 12).all()


def test_the_comparison_interval_covers_a_known_difference() -> None:
    """CD between the means of two sets of units, with a bootstrap interval that covers the
    true CD in most of 40 draws (numpy's own cosine as the reference)."""
    rng = np.random.default_rng(4)
    mu_a, mu_b = np.array([0.8, 0.1, 0.5, 0.0]), np.array([0.6, 0.4, 0.5, 0.2])
    true = 1 - mu_a @ mu_b / (np.linalg.norm(mu_a) * np.linalg.norm(mu_b))
    hits = 0
    for _ in range(40):
        a = mu_a + rng.normal(0, 0.1, (30, 4))
        b = mu_b + rng.normal(0, 0.1, (25, 4))
        out = compare(a, b, rng, 0.05)
        ma, mb = a.mean(0), b.mean(0)
        assert out["cd"] == pytest.approx(1 - ma @ mb / (np.linalg.norm(ma) * np.linalg.norm(mb)))
        assert out["ed"] == pytest.approx(np.linalg.norm(ma - mb))
        hits += out["cd_low"] <= true <= out["cd_high"]
    assert hits >= 34  # nominal 95%: 38 of 40 expected


def test_a_study_without_complete_nodes_says_so(tmp_path: Path) -> None:
    from emogen.analysis.results import Section
    from emogen.analysis.study_export import StudyExport
    from emogen.analysis.task_sections import TaskTools
    from emogen.tasks.gsp.analysis_report import gsp_section

    genes = json.dumps([0.0, 0.5])
    rows = pd.DataFrame(
        {
            "participant_id": ["a"],
            "block_name": ["block1"],
            "emotion": ["happy"],
            "chain_id": [1],
            "iteration": [0],
            "member": [0],
            "applied": [True],
            "node_value": [np.nan],
            "dimension_index": [1],
            "genes_before": [genes],
            "identity": ["generic"],
            "g_x": [0.0],
            "g_y": [0.3],
        }
    )
    rows.to_csv(tmp_path / "gsp_iterations.csv", index=False)
    report = gsp_section(
        TaskTools(StudyExport(tmp_path), Section(tmp_path / "out"), AnalysisOptions(), None)
    )
    assert report.data["gsp"]["note"] == "no complete node" and report.results == []
    assert "no chain has a complete node" in " ".join(getattr(b, "text", "") for b in report.blocks)
