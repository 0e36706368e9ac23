"""Perceptive fields: the KDE, bandwidth and overlaps against independent references
(scikit-learn's KernelDensity, closed forms for Gaussians, numerical integration), and the
clustering against planted subpopulations of simulated studies."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy import integrate, stats
from sklearn.metrics import adjusted_rand_score
from sklearn.neighbors import KernelDensity

from emogen.analysis.analyse_options import AnalysisOptions
from emogen.analysis.field_clusters import cluster_fields
from emogen.analysis.fields import (
    BANDWIDTH_GRID,
    bhattacharyya,
    field_individuality,
    loo_loglik,
    overlap_matrix,
    perceptive_fields,
    pooled_bandwidth,
)
from emogen.analysis.fields_report import fields_section
from emogen.analysis.results import write_analysis
from emogen.analysis.simulated_study import PeopleDesign, as_people, simulate_people
from emogen.tasks.simulated import SimulatedDesign

GROUP_SHIFT = {
    "happy": {"browInnerUp": 0.6, "mouthFrown": 0.6},
    "sad": {"mouthSmile": 0.6, "jawOpen": 0.6},
    "angry": {"browInnerUp": 0.6, "mouthSmile": 0.6},
    "fearful": {"mouthSmile": 0.6, "noseSneer": 0.6},
}


@pytest.fixture(scope="module")
def rig(ict_model):  # type: ignore[no-untyped-def]
    return ict_model.rig


def test_leave_one_out_density_matches_sklearn() -> None:
    x = np.random.default_rng(0).normal(size=(6, 3))
    h = 0.7
    ours = loo_loglik(x, h)
    for i in range(6):
        kde = KernelDensity(bandwidth=h).fit(np.delete(x, i, axis=0))
        assert ours[i] == pytest.approx(kde.score_samples(x[i : i + 1])[0], abs=1e-9)


def test_pooled_bandwidth_is_the_argmax_of_a_plain_loop() -> None:
    rng = np.random.default_rng(1)
    fields = [
        rng.normal(rng.normal(0, 2, 2), 0.5, size=(int(rng.integers(2, 5)), 2)) for _ in range(8)
    ]
    h, table = pooled_bandwidth(fields)
    grid = table["bandwidth"].to_numpy()
    assert len(grid) == len(BANDWIDTH_GRID)
    plain = [
        sum(
            KernelDensity(bandwidth=g).fit(np.delete(f, i, 0)).score_samples(f[i : i + 1])[0]
            for f in fields
            for i in range(len(f))
        )
        for g in grid
    ]
    assert table["loo_loglik"].to_numpy() == pytest.approx(plain, rel=1e-9)
    assert h == grid[int(np.argmax(plain))]
    assert 0.25 < h < 1.0  # near the planted within-field SD 0.5


def test_overlap_of_single_faces_is_the_gaussian_closed_form() -> None:
    a, b = np.array([[0.0, 0.0]]), np.array([[0.6, 0.8]])  # |Δ| = 1
    h = 0.4
    assert overlap_matrix([a], [b], h)[0, 0] == pytest.approx(np.exp(-1 / (4 * h**2)))
    assert overlap_matrix([a, b], [a, b], h)[0, 0] == pytest.approx(1.0)


def test_overlap_of_kdes_matches_numerical_integration() -> None:
    p, q, h = np.array([[0.0], [0.5], [1.5]]), np.array([[0.8], [2.0]]), 0.45

    def dens(x: np.ndarray, at: float) -> float:
        return float(np.exp(KernelDensity(bandwidth=h).fit(x).score_samples([[at]]))[0])

    def integral(f: object) -> float:
        return integrate.quad(f, -6, 8, limit=200)[0]  # type: ignore[arg-type]

    pq = integral(lambda t: dens(p, t) * dens(q, t))
    pp, qq = integral(lambda t: dens(p, t) ** 2), integral(lambda t: dens(q, t) ** 2)
    assert overlap_matrix([p], [q], h)[0, 0] == pytest.approx(pq / np.sqrt(pp * qq), rel=1e-6)


def test_monte_carlo_bhattacharyya_and_min_overlap_match_closed_forms() -> None:
    h, delta = 0.5, 0.9
    a, b = np.array([[0.0, 0.0, 0.0]]), np.array([[delta, 0.0, 0.0]])
    bc, mn = bhattacharyya([a, b], h, rng=np.random.default_rng(2), samples=4000)
    se = 1 / np.sqrt(2 * 4000)
    assert bc[0, 1] == pytest.approx(np.exp(-(delta**2) / (8 * h**2)), abs=4 * se)
    assert mn[0, 1] == pytest.approx(2 * stats.norm.cdf(-delta / (2 * h)), abs=4 * se)
    assert bc[0, 0] == 1.0


def test_bhattacharyya_of_many_fields_is_a_plain_loop_over_pairs(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The batched estimate (every pair from one matrix over fields × draw sets, in blocks of
    two fields' draws here) against a loop over pairs with scipy's normal densities, on the
    same draws."""
    from emogen.analysis import fields as module

    rng = np.random.default_rng(5)
    k, h, samples = 3, 0.6, 40
    fields = [rng.normal(rng.normal(0, 1, k), 0.5, (int(rng.integers(1, 5)), k)) for _ in range(7)]
    monkeypatch.setattr(module, "_BLOCK_VALUES", 2 * 7 * samples)
    bc, mn = bhattacharyya(fields, h, rng=np.random.default_rng(9), samples=samples)
    again = np.random.default_rng(9)
    draws = []
    for x in fields:
        c = x[again.integers(0, len(x), samples)]
        draws.append(c + again.normal(0.0, h, c.shape))

    def density(x: np.ndarray, at: np.ndarray) -> np.ndarray:
        return np.mean([stats.multivariate_normal(c, h**2).pdf(at) for c in x], axis=0)

    for i in range(len(fields)):
        for j in range(len(fields)):
            at = np.vstack([draws[i], draws[j]])
            p, q = density(fields[i], at), density(fields[j], at)
            assert bc[i, j] == pytest.approx(np.mean(np.sqrt(p * q) / ((p + q) / 2)), abs=1e-12)
            assert mn[i, j] == pytest.approx(np.mean(np.minimum(p, q) / ((p + q) / 2)), abs=1e-12)


def _grouped(participants: int, groups: bool) -> PeopleDesign:
    return PeopleDesign(
        participants=participants,
        categorise=False,
        participant=SimulatedDesign(spread=0.15),
        groups=("a", "b") if groups else (),
        shifts={"b": GROUP_SHIFT} if groups else {},
    )


def test_clustering_recovers_two_planted_subpopulations(rig) -> None:  # type: ignore[no-untyped-def]
    for seed in (0, 1):
        sim = simulate_people(_grouped(30, True), rig, seed=seed)
        c = cluster_fields(
            perceptive_fields(as_people(sim)), rng=np.random.default_rng(seed), n_null=39
        )
        assert c.structure and c.k == 2
        assert adjusted_rand_score(sim.group, c.labels) > 0.8


def test_one_population_mostly_reads_as_no_structure(rig) -> None:  # type: ignore[no-untyped-def]
    """4 studies in CI (the 100-study rate: benchmarks/calibrate_fields.py); a test that found
    structure everywhere (the silhouette's bias) fails here."""
    found = [
        cluster_fields(
            perceptive_fields(as_people(simulate_people(_grouped(30, False), rig, seed=100 + s))),
            rng=np.random.default_rng(s),
            n_null=39,
        ).structure
        for s in range(4)
    ]
    assert sum(found) <= 1
    with pytest.raises(Exception, match="6 participants"):
        small = simulate_people(_grouped(4, False), rig, seed=1)
        cluster_fields(perceptive_fields(as_people(small)), rng=np.random.default_rng(0))


def test_fields_are_their_owners_when_participants_differ(rig) -> None:  # type: ignore[no-untyped-def]
    design = PeopleDesign(
        participants=20,
        categorise=False,
        repetitions=4,
        identities=("female-medium",),
        emotions=("happy", "sad"),
        participant=SimulatedDesign(spread=0.5),
    )
    people = as_people(simulate_people(design, rig, seed=3))
    ind = field_individuality(people, perceptive_fields(people))
    for _, part in ind.groupby("emotion"):
        diff = part["self"] - part["others"]
        assert diff.mean() > 0 and stats.ttest_1samp(diff, 0).pvalue < 0.01
        assert part["identified"].mean() >= 2 / len(part)  # twice chance (1 / participants)


def test_fields_section_writes_tables_and_skips_what_it_cannot(rig, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    people = as_people(simulate_people(_grouped(12, True), rig, seed=4))
    report = fields_section(people, tmp_path / "a", AnalysisOptions(), None)
    summary = report.data
    write_analysis("t", report.out, [report], {})
    for name in ("fields_bandwidth", "fields_fields", "fields_overlap", "fields_clusters"):
        assert (tmp_path / "a" / "tables" / f"{name}.csv").is_file()
    assert (tmp_path / "a" / "figures" / "fields_pc_maps.svg").is_file()
    assert set(summary["fields"]["bandwidth"]) == set(people.emotions)
    one = PeopleDesign(participants=3, repetitions=1, categorise=False)
    report = fields_section(
        as_people(simulate_people(one, rig, seed=1)), tmp_path / "b", AnalysisOptions(), None
    )
    text = write_analysis("t", report.out, [report], {})[1].read_text()
    assert "Skipped: perceptive fields need at least 6 participants" in text


def test_one_embedding_clusters_as_sklearn_does_for_every_k() -> None:
    """best_clusters embeds once (max_k eigenvectors) and labels each k by cluster_qr on the
    first k: the same partitions as sklearn's SpectralClustering(k, cluster_qr) fitted per k."""
    from sklearn.cluster import SpectralClustering
    from sklearn.manifold import spectral_embedding
    from sklearn.metrics import adjusted_rand_score

    from emogen.analysis.field_clusters import cluster_qr

    rng = np.random.default_rng(0)
    for _ in range(5):
        x = np.concatenate([rng.normal(c, 1.0, (20, 3)) for c in (0.0, 2.0, -2.0)])
        d = np.clip(np.sqrt(((x[:, None] - x[None]) ** 2).sum(-1)) / 4, 0, np.sqrt(2))
        affinity = np.clip(1 - d**2 / 2, 0, 1)
        maps = spectral_embedding(affinity, n_components=6, random_state=0, drop_first=False)
        for k in range(2, 7):
            ref = SpectralClustering(
                k, affinity="precomputed", random_state=0, assign_labels="cluster_qr"
            ).fit_predict(affinity)
            assert adjusted_rand_score(ref, cluster_qr(maps[:, :k])) == 1.0


def test_dense_spectral_maps_equal_sklearns_spectral_embedding() -> None:
    """spectral_maps (scipy's dense eigh) against scikit-learn's ARPACK spectral embedding on
    connected affinities of three planted groups: the same vectors, signs included."""
    from sklearn.manifold import spectral_embedding

    from emogen.analysis.field_clusters import spectral_maps

    rng = np.random.default_rng(3)
    for n, gap in ((30, 1.0), (90, 2.0), (150, 0.5)):
        x = np.concatenate([rng.normal(c, 1.0, (n // 3, 3)) for c in (0.0, gap, -gap)])
        d = np.clip(np.sqrt(((x[:, None] - x[None]) ** 2).sum(-1)) / 4, 0, np.sqrt(2))
        affinity = np.clip(1 - d**2 / 2, 0, 1)
        ref = spectral_embedding(affinity, n_components=6, random_state=0, drop_first=False)
        assert spectral_maps(affinity, 6) == pytest.approx(ref, abs=1e-10)


def test_contact_sheets_show_a_seeded_sample_of_a_large_study(
    rig, ict_model, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:  # type: ignore[no-untyped-def]
    """Beyond SHEET_PARTICIPANTS the sheets hold that many participants' faces, drawn with the
    analysis seed, and the report says so; the sheet's height is that of those faces alone."""
    from PIL import Image

    from emogen.analysis import fields_report
    from emogen.analysis.field_maps import mean_faces
    from emogen.render.images import contact_sheet

    monkeypatch.setattr(fields_report, "SHEET_PARTICIPANTS", 2)
    people = as_people(simulate_people(_grouped(8, False), rig, seed=6))
    opts = AnalysisOptions(render_size=64)
    report = fields_section(people, tmp_path / "a", opts, ict_model)
    assert (
        f"2 of the 8 participants, drawn at random (seed {opts.seed})"
        in write_analysis("t", report.out, [report], {})[1].read_text()
    )
    means = mean_faces(people)
    e = str(means["emotion"].iloc[0])
    n = int((means["emotion"] == e).sum() / 8 * 2)  # two participants' faces of emotion e
    expected = contact_sheet(np.zeros((n, 64, 64, 3), np.uint8), ["x"] * n, columns=8)
    with Image.open(tmp_path / "a" / "figures" / f"fields_faces_{e}.png") as sheet:
        assert sheet.size[1] == expected.shape[0]
