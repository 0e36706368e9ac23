"""Targets analogous to the paper's (Figs. 6 and 18) on our rig, and simulated participants.

The paper's targets, counted in its model's blendshapes: target 1 has one (an open jaw),
target 3 three (target 1 plus a nose wrinkle and one more), target 2 twelve, and the users'
mean "happy" face 125 (32 above 0.1). Our rig's gene space has 30 genes (a left/right pair is
one gene; the paper's had 45–55 unique core shapes), so the analogues are counted in **genes**:

* ``target 1`` — jawOpen (1 gene, 1 shape);
* ``target 3`` — jawOpen + noseSneer + mouthUpperUp (3 genes, 5 shapes): target 1 with a nose
  wrinkle and a raised upper lip, deliberately similar to target 1, as in the paper;
* ``target 2`` — 12 genes across brows, eyes and mouth (22 shapes);
* ``dense happy`` — every gene active (52 shapes), the happy building blocks strongly (the
  analogue of the paper's 125-shape users' mean happy face).

These are the targets of ``tests/simulate/test_trends.py``, ``benchmarks/bench_simulate.py``
and docs/ga.md's table, so every figure we publish refers to the same faces.

**Simulated participants** (for the empirical metrics' training set and the demonstrations):
participant p's internal target for an emotion is drawn from the emotion's building blocks in
the rig — every core gene with a weight U(0.4, 1), each optional gene with probability 0.4 and
weight U(0.1, 0.6) — so participants agree on an emotion's core and differ in its details.
"""

from __future__ import annotations

import numpy as np

from emogen.model.rig import Rig

TARGET_1 = {"jawOpen": 1.0}
TARGET_3 = {"jawOpen": 1.0, "noseSneer": 0.6, "mouthUpperUp": 0.3}
TARGET_2 = {
    "browInnerUp": 0.7,
    "browOuterUp": 0.6,
    "eyeWide": 0.5,
    "jawOpen": 0.4,
    "mouthStretch": 0.5,
    "mouthLowerDown": 0.4,
    "mouthFrown": 0.3,
    "noseSneer": 0.3,
    "cheekSquint": 0.2,
    "mouthUpperUp": 0.3,
    "mouthFunnel": 0.2,
    "browDown": 0.2,
}
HAPPY = {
    "mouthSmile": 0.9,
    "cheekSquint": 0.6,
    "cheekRaiser": 0.7,
    "eyeSquint": 0.45,
    "mouthUpperUp": 0.3,
    "mouthLowerDown": 0.3,
    "jawOpen": 0.25,
    "mouthDimple": 0.35,
}


def dense_happy(rig: Rig) -> dict[str, float]:
    """Every gene a little (0.02–0.08), the happy building blocks strongly."""
    base = {g.name: 0.02 + 0.06 * ((i * 7) % 10) / 9 for i, g in enumerate(rig.genes)}
    return base | HAPPY


#: Table V's targets counted in *shapes*, as the paper counts them (a left/right pair is two
#: shapes): 1, 3 and 12 active shapes; with :func:`dense_happy` they make the Table V analogue
#: of tests/simulate/test_trends.py and benchmarks/bench_simulate.py.
TABLE_V_BY_SHAPES = {
    "1-shape": {"jawOpen": 1.0},
    "3-shape": {"jawOpen": 1.0, "noseSneer": 0.6},  # target 1 with a nose wrinkle
    "12-shape": {  # brows, cheeks and mouth, not one emotion's building blocks
        "browOuterUp": 0.6,
        "cheekPuff": 0.4,
        "mouthDimple": 0.5,
        "mouthPress": 0.4,
        "noseSneer": 0.3,
        "mouthPucker": 0.5,
        "jawForward": 0.3,
    },
}


def table_v_by_shapes(rig: Rig) -> dict[str, dict[str, float]]:
    """Targets of 1, 3 and 12 active shapes and the dense happy face (52 shapes)."""
    return {**{k: dict(v) for k, v in TABLE_V_BY_SHAPES.items()}, "dense": dense_happy(rig)}


def paper_targets(rig: Rig) -> dict[str, dict[str, float]]:
    """The Fig. 6 / Fig. 18 analogues, in the paper's order of complexity."""
    return {
        "target 1": dict(TARGET_1),
        "target 3": dict(TARGET_3),
        "target 2": dict(TARGET_2),
        "dense happy": dense_happy(rig),
    }


def count_active(rig: Rig, named: dict[str, float]) -> tuple[int, int]:
    """(genes, shapes) with a non-zero weight."""
    w = rig.weights_from_names(named)
    genes = sum(1 for g in rig.genes if any(w[rig.shape_names.index(s)] > 0 for s in g.shapes))
    return genes, int((w > 0).sum())


def participant_target(
    rig: Rig, emotion: str, *, rng: np.random.Generator, optional_p: float = 0.4
) -> dict[str, float]:
    """A simulated participant's internal target for ``emotion`` (see the module docstring)."""
    spec = rig.emotions[emotion]
    out = {g: float(rng.uniform(0.4, 1.0)) for g in spec.core}
    for g in spec.optional:
        if rng.random() < optional_p:
            out[g] = float(rng.uniform(0.1, 0.6))
    return out
