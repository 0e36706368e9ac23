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
