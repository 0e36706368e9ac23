"""The engine with dynamic genes: records its genome, replays exactly, a static state as before."""

from __future__ import annotations

import json

import numpy as np
import pytest

from emogen.config import GAConfig, InitConfig
from emogen.errors import ConfigError
from emogen.ga.engine import Engine
from emogen.ga.genome import DynamicGenome

GENOME = DynamicGenome(clip_s=1.5, hold_s=0.5)


def run(engine: Engine, seed: int = 0) -> Engine:
    rng = np.random.default_rng(seed)
    while not engine.done:
        ids = rng.permutation(engine.ask().ids)[: int(rng.integers(1, 6))]
        engine.tell(int(ids[0]), [int(i) for i in ids[1:]])
    return engine


@pytest.mark.parametrize("variant", ["emogen", "classical"])
def test_a_dynamic_run_replays_exactly_and_survives_its_json_state(ict_model, variant) -> None:
    config = GAConfig(variant=variant, generations=4)
    engine = run(Engine(config, ict_model.rig, 11, genome=GENOME))
    result = engine.result
    assert result.genes.shape == (1, len(engine.gene_names), 6)
    again = Engine.replay(config, ict_model.rig, 11, engine.selections, genome=GENOME)
    assert again.result.genes.tobytes() == result.genes.tobytes()
    state = json.loads(engine.to_json())
    assert state["genome"] == {
        "kind": "dynamic",
        "clip_s": 1.5,
        "hold_s": 0.5,
        "min_segment_s": 0.08,
        "keyframes": 21,
    }
    restored = Engine.from_json(engine.to_json(), ict_model.rig)
    assert restored.genome == GENOME
    assert restored.result.genes.tobytes() == result.genes.tobytes()
    # the shown weights are the amplitudes, expanded as a static face's genes
    expanded = ict_model.rig.expand(result.genes[..., 0], True)
    assert np.array_equal(result.weights, expanded)


def test_a_restored_mid_run_engine_breeds_as_the_one_that_saved_it(ict_model) -> None:
    config = GAConfig(generations=3)
    a = Engine(config, ict_model.rig, 3, genome=GENOME)
    a.tell(int(a.ask().ids[4]), [int(a.ask().ids[7]), int(a.ask().ids[1])])
    b = Engine.from_json(a.to_json(), ict_model.rig)
    pop = a.ask()
    for e in (a, b):
        e.tell(int(pop.ids[0]), [int(pop.ids[2])])
    assert a.ask().genes.tobytes() == b.ask().genes.tobytes()


def test_generation_0_keeps_the_static_initialisation_and_adds_timing(ict_model) -> None:
    static = Engine(GAConfig(), ict_model.rig, 9).ask()
    dynamic = Engine(GAConfig(), ict_model.rig, 9, genome=GENOME).ask()
    assert np.array_equal(dynamic.genes[..., 0], static.genes)
    assert list(dynamic.operators) == list(static.operators)
    timing = dynamic.genes[..., 1:]
    assert ((timing > 0) & (timing < 1)).all()


def test_keep_on_reset_keeps_the_curves_too(ict_model) -> None:
    config = GAConfig(init=InitConfig(on_reset="keep"))
    engine = Engine(config, ict_model.rig, 2, genome=GENOME)
    first = engine.ask().genes
    assert np.array_equal(engine.reset().genes, first)


def test_a_static_state_records_no_genome(ict_model) -> None:
    state = json.loads(Engine(GAConfig(), ict_model.rig, 1).to_json())
    assert "genome" not in state


def test_a_state_with_a_bad_genome_is_refused_by_name(ict_model) -> None:
    state = json.loads(Engine(GAConfig(), ict_model.rig, 1, genome=GENOME).to_json())
    state["genome"]["clip_s"] = 99
    with pytest.raises(ConfigError, match=r"clip_s must be in \[0.2, 10\] seconds; got 99"):
        Engine.from_json(json.dumps(state), ict_model.rig)


def test_a_corrected_dynamic_population_carries_its_keyframe_correctives(ict_model) -> None:
    from emogen.ga.corrector import correctives_of

    engine = Engine(
        GAConfig(), ict_model.rig, 4, genome=GENOME, corrector=correctives_of(ict_model)
    )
    pop = engine.ask()
    keyed = pop.keyframe_correctives
    assert keyed is not None and keyed.shape == (10, GENOME.keyframes, len(pop.corrective_names))
    assert keyed[:, 0].max() == 0 and keyed[:, -1].max() == 0  # every clip starts and ends at rest
    restored = Engine.from_json(
        engine.to_json(), ict_model.rig, corrector=correctives_of(ict_model)
    )
    assert restored.ask().keyframe_correctives.tobytes() == keyed.tobytes()
    assert pop.row(3).keyframe_correctives.shape == (1, GENOME.keyframes, keyed.shape[2])
