"""The engine corrects every population before it is shown, and records the correctives apart."""

from __future__ import annotations

import numpy as np

from emogen.config import GAConfig
from emogen.correct import correct_faces
from emogen.ga.engine import Engine, correctives_of


def test_populations_carry_their_correctives(ict_model) -> None:
    corrector = correctives_of(ict_model)
    plain = Engine(GAConfig(), ict_model.rig, 11)
    corrected = Engine(GAConfig(), ict_model.rig, 11, corrector=corrector)
    for _ in range(3):
        p, c = plain.ask(), corrected.ask()
        # the core weights are the GA's own, untouched by the correction
        np.testing.assert_array_equal(p.weights, c.weights)
        assert p.correctives is None
        ref = correct_faces(ict_model, c.weights)  # independent call of the model's corrector
        assert c.corrective_names == tuple(ref.corrective_names)
        np.testing.assert_array_equal(c.correctives, ref.correctives)
        assert c.correctives.shape == (10, len(c.corrective_names))
        elite, others = int(c.ids[0]), [int(i) for i in c.ids[1:3]]
        plain.tell(elite, others)
        corrected.tell(elite, others)

    # JSON round trip and replay give the same corrected population
    resumed = Engine.from_json(corrected.to_json(), ict_model.rig, corrector=corrector)
    np.testing.assert_array_equal(resumed.ask().correctives, corrected.ask().correctives)
    replayed = Engine.replay(
        GAConfig(), ict_model.rig, 11, corrected.selections, corrector=corrector
    )
    np.testing.assert_array_equal(replayed.ask().correctives, corrected.ask().correctives)
    # a row keeps its correctives
    row = corrected.ask().row(2)
    np.testing.assert_array_equal(row.correctives[0], corrected.ask().correctives[2])


def test_a_restored_engine_corrects_only_what_it_shows(ict_model) -> None:
    """A server restores the engine for each selection: the population being told about is
    not corrected again (only the next one, once), and the result carries its correctives."""
    base = correctives_of(ict_model)
    batches: list[int] = []

    def counting(weights: np.ndarray) -> tuple[tuple[str, ...], np.ndarray]:
        batches.append(len(weights))
        return base(weights)

    config = GAConfig(generations=2)
    reference = Engine(config, ict_model.rig, 5, corrector=base)
    state = Engine(config, ict_model.rig, 5, corrector=counting).to_json()
    assert batches == []  # nothing asked for yet: nothing corrected
    for g in range(3):
        shown = reference.ask()
        engine = Engine.from_json(state, ict_model.rig, corrector=counting)
        elite, others = int(shown.ids[g]), [int(shown.ids[(g + 1) % 10])]
        engine.tell(elite, others)
        reference.tell(elite, others)
        if g < 2:
            nxt = engine.ask()
            np.testing.assert_array_equal(nxt.correctives, reference.ask().correctives)
        state = engine.to_json()
    assert batches == [10, 10]  # one batch per shown generation, none for the restored ones
    done = Engine.from_json(state, ict_model.rig, corrector=counting)
    result = done.result  # corrected on its own when read: the same bits as in its batch
    assert batches == [10, 10, 1]
    np.testing.assert_array_equal(result.correctives, reference.result.correctives)
    np.testing.assert_array_equal(result.weights, reference.result.weights)
