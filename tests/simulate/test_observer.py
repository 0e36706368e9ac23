"""The cosine-distance observer: ranking and the paper's selection schedule."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.distance import cosine

from emogen.config import GAConfig, SimulationConfig
from emogen.errors import ShapeError
from emogen.ga.engine import Engine
from emogen.simulate.observer import CosineObserver, rank_by_cosine


def test_rank_by_cosine() -> None:
    target = np.array([1.0, 0.0, 0.0])
    weights = np.array([[0.0, 1.0, 0.0], [0.5, 0.1, 0.0], [1.0, 0.0, 0.0], [0, 0, 0], [0.2, 0, 0]])
    order, d = rank_by_cosine(weights, target)
    assert order.tolist() == [2, 4, 1, 0, 3]  # ties (CD 1) keep slot order
    np.testing.assert_allclose(d[:3], [cosine(w, target) for w in weights[:3]], atol=1e-12)
    with pytest.raises(ShapeError):
        rank_by_cosine(weights, np.ones(4))


def test_observer_follows_the_paper_schedule(ict_model) -> None:
    rig = ict_model.rig
    sim = SimulationConfig(target={"jawOpen": 1.0})
    target = rig.weights_from_names(sim.target)
    engine = Engine(GAConfig(), rig, seed=3)
    observer = CosineObserver(target, sim.selections_at, final=10)
    counts = []
    while not engine.done:
        pop = engine.ask()
        elite, others, error = observer.choose(pop)
        order, d = rank_by_cosine(pop.weights, target)
        assert elite == pop.ids[order[0]] and error == d.min()
        assert others == pop.ids[order[1 : 1 + len(others)]].tolist()
        counts.append(1 + len(others))
        engine.tell(elite, others)
    assert counts == [2, 4, 4, 4, 4, 4, 5, 5, 5, 5, 1]  # only the last elite counts


def test_ranking_observer_for_the_classical_variant(ict_model) -> None:
    rig = ict_model.rig
    target = rig.weights_from_names({"mouthSmile": 0.7})
    engine = Engine(GAConfig(variant="classical"), rig, seed=3)
    observer = CosineObserver(target, lambda g: 2, final=10, ranking=True)
    elite, others, _ = observer.choose(engine.ask())
    assert len(others) == 9 and elite not in others
