"""The vectorised runner reproduces the engine-driven runs exactly, for every option."""

from __future__ import annotations

import types

import numpy as np
import pytest

from emogen.config import GAConfig, InitConfig, SimulationConfig
from emogen.correct import evaluate_corrected
from emogen.errors import ConfigError
from emogen.metrics import vertex_rms
from emogen.rng import spawn_seeds
from emogen.simulate.observer import choice_order
from emogen.simulate.problem import RunArrays
from emogen.simulate.runner import build_problem
from emogen.simulate.vectorised import engine_run, simulate_runs

TARGET = {"jawOpen": 1.0, "noseSneer": 0.4}
FIELDS = ("distance", "error", "rank", "operators", "weights", "fixed_options")


def assert_same_as_engine(problem, runs: int = 8, seed: int = 3) -> RunArrays:
    """Bit for bit, corrected faces included (see simulate/vectorised.py)."""
    seeds = spawn_seeds(seed, runs)
    fast = simulate_runs(problem, np.arange(runs), np.array(seeds))
    for r in range(runs):
        ref = engine_run(problem, r, seeds[r])
        for f in FIELDS:
            np.testing.assert_array_equal(getattr(fast, f)[r], getattr(ref, f)[0], err_msg=f)
    return fast


@pytest.mark.parametrize(
    "options",
    [
        {},
        {"metric": "ed"},
        {"noise_temperature": 0.05},
        {"selections": [3]},
        {"ga": GAConfig(variant="classical")},
        {"ga": GAConfig(init=InitConfig(kind="fixed"))},
        {"ga": GAConfig(init=InitConfig(kind="fixed", fixed_option=2), eye_motion=False)},
        {
            "ga": GAConfig(
                population_size=6,
                random_faces=2,
                max_selections=6,
                init=InitConfig(faces_per_emotion=1),
            ),
            "selections": [2, 3],
        },
    ],
    ids=["cd", "ed", "noise", "three", "classical", "fixed", "fixed2-no-eyes", "small"],
)
def test_vectorised_runs_equal_engine_runs(ict_model, options) -> None:
    cfg = SimulationConfig(target=TARGET, runs=8, seed=3, **options)
    assert_same_as_engine(build_problem(cfg, ict_model.rig, all_weights=True))


@pytest.mark.slow
@pytest.mark.parametrize("variant", ["emogen", "classical"])
def test_a_thousand_runs_equal_the_engine(ict_model, variant) -> None:
    """The engine participants use and the vectorised runner make the same 1,000 runs."""
    cfg = SimulationConfig(
        target=TARGET, runs=1000, seed=11, noise_temperature=0.03, ga=GAConfig(variant=variant)
    )
    assert_same_as_engine(build_problem(cfg, ict_model.rig, all_weights=True), runs=1000, seed=11)


@pytest.mark.slow
def test_corrected_runs_equal_the_engine(ict_model) -> None:
    """Corrections on (combinational + collision, every shown face), both variants."""
    for variant in ("emogen", "classical"):
        cfg = SimulationConfig(
            target={"jawOpen": 0.9, "mouthFunnel": 0.6},
            runs=100,
            seed=8,
            correct=True,
            ga=GAConfig(generations=3, variant=variant),
        )
        assert_same_as_engine(build_problem(cfg, ict_model, all_weights=True), runs=100, seed=8)


def test_vertex_rms_observer_equals_engine(ict_model) -> None:
    cfg = SimulationConfig(target=TARGET, runs=4, seed=5, metric="vertex_rms")
    fast = assert_same_as_engine(build_problem(cfg, ict_model, all_weights=True), runs=4)
    # the observer follows vertex RMS: the elite is the closest face
    elite = (fast.rank == 0).argmax(2)[..., None]
    np.testing.assert_array_equal(
        np.take_along_axis(fast.distance, elite, 2)[..., 0], fast.distance.min(2)
    )


def test_corrections_are_applied_to_every_shown_face(ict_model) -> None:
    """Real correctives (correct_faces): the vectorised runs still equal the engine's (bit for
    bit: a face's correction does not depend on the batch it is corrected in), the
    metrics see the corrected full weight vectors, and vertex RMS stays exact."""
    cfg = SimulationConfig(
        target={"jawOpen": 0.9, "mouthFunnel": 0.6},
        runs=2,
        seed=2,
        correct=True,
        metric="vertex_rms",
        ga=GAConfig(generations=2),
    )
    problem = build_problem(cfg, ict_model, all_weights=True)
    names = problem.columns
    n_shapes = ict_model.n_shapes
    assert names[:n_shapes] == ict_model.shape_names and len(names) > n_shapes
    fast = assert_same_as_engine(problem, runs=2)
    shown = fast.weights.reshape(-1, len(names))
    # the shown weights are correct_faces': effective weights, then every corrective
    jaw, close = names.index("jawOpen"), names.index("mouthClose")
    assert np.all(shown[:, close] <= shown[:, jaw] + 1e-12)
    # vertex RMS on corrected weights = eq. 13 on the model's corrected vertices
    faces = ict_model.rig.expand(np.random.default_rng(1).random((5, 30)) * 0.6)
    faces[:, jaw] = [0.2, 0.5, 0.8, 1.0, 0.9]  # open jaws: collisions to correct
    corrected = problem.correction(faces)
    verts = evaluate_corrected(ict_model, faces).astype(np.float64)
    np.testing.assert_allclose(
        problem.metric(corrected, corrected[0]), vertex_rms(verts, verts[0]), rtol=1e-4, atol=1e-6
    )
    with pytest.raises(ConfigError, match="needs the face model"):
        build_problem(cfg, ict_model.rig)
    with pytest.raises(ConfigError, match="needs a FaceModel"):
        build_problem(cfg, types.SimpleNamespace(rig=ict_model.rig))  # type: ignore[arg-type]


def test_results_do_not_depend_on_chunking(ict_model) -> None:
    cfg = SimulationConfig(target=TARGET, runs=10, seed=4, noise_temperature=0.02)
    problem = build_problem(cfg, ict_model.rig)
    seeds = np.array(spawn_seeds(4, 10))
    whole = simulate_runs(problem, np.arange(10), seeds)
    parts = [
        simulate_runs(problem, np.arange(10)[s], seeds[s]) for s in (slice(6, 10), slice(0, 6))
    ]
    joined = RunArrays.concatenate(parts)
    for f in ("runs", "seeds", "distance", "rank", "operators"):
        np.testing.assert_array_equal(getattr(whole, f), getattr(joined, f))


def test_choice_noise_is_a_softmax() -> None:
    d = np.array([[0.1, 0.2, 0.4]])
    t = 0.1
    rng = np.random.default_rng(0)
    n = 40000
    gumbel = rng.gumbel(size=(n, 3))
    order = choice_order(np.repeat(d, n, axis=0), t, gumbel)
    p = np.exp(-d[0] / t) / np.exp(-d[0] / t).sum()
    freq = np.bincount(order[:, 0], minlength=3) / n
    np.testing.assert_allclose(freq, p, atol=0.01)
    # second pick from the remaining faces (Plackett–Luce): P(second = 1 | first = 0)
    first0 = order[:, 0] == 0
    p2 = p[1] / (p[1] + p[2])
    assert np.mean(order[first0, 1] == 1) == pytest.approx(p2, abs=0.015)
    # T = 0 is the ranking, ties in slot order
    assert choice_order(np.array([[0.3, 0.1, 0.1]])).tolist() == [[1, 2, 0]]
