"""Where a categorise block's faces come from: pure draws over arrays and a Generator.

The study layer reads the candidates (the participant's own finished faces, other participants'
finished faces, a face table's rows) and stores what these functions pick; every pick is a
function of the block's recorded seeds, so a session's stimuli replay.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from emogen.config import GAConfig
from emogen.ga.init import ARBITRARY, protocol_init
from emogen.model.rig import Rig

UNIFORM = "random_uniform"


def label_order(labels: Sequence[str], rng: np.random.Generator) -> list[str]:
    """The labels in the order a trial offers them (a permutation drawn per trial)."""
    return [labels[int(i)] for i in rng.permutation(len(labels))]


def random_faces(
    rig: Rig,
    ga: GAConfig,
    *,
    kind: str,
    n: int,
    genes_range: tuple[int, int],
    rng: np.random.Generator,
) -> tuple[np.ndarray, list[str]]:
    """``n`` random faces as genes (n, n_genes) and a label per face saying what made it.

    protocol : faces of the GA's protocol initialisation (its emotion building-block faces and
    arbitrary faces; the neutral face left out), drawn a population at a time, in its order.
    uniform : U{lo..hi} distinct genes active per face, values U(0, 1) (a reverse-correlation
    design: every gene equally likely)."""
    names = rig.gene_names(ga.eye_motion)
    if kind == "uniform":
        lo, hi = genes_range
        genes = np.zeros((n, len(names)))
        for i in range(n):
            k = min(int(rng.integers(lo, hi + 1)), len(names))
            chosen = rng.choice(len(names), size=k, replace=False)
            genes[i, chosen] = rng.random(k)
        return genes, [UNIFORM] * n
    rows: list[np.ndarray] = []
    labels: list[str] = []
    while len(rows) < n:
        batch, made = protocol_init(
            rig,
            eye_motion=ga.eye_motion,
            activation_range=ga.init.activation_range,
            emotions=ga.init.emotions,
            faces_per_emotion=max(1, ga.init.faces_per_emotion),
            arbitrary=max(1, ga.arbitrary_faces()),
            rng=rng,
        )
        for face, label in zip(batch, made, strict=True):
            if face.any() and len(rows) < n:  # the neutral face is no expression to label
                rows.append(face)
                labels.append(str(label) if label != ARBITRARY else "init_arbitrary")
    return np.stack(rows) if rows else np.zeros((0, len(names))), labels


def balanced_pick(
    emotions: Sequence[str], labels: Sequence[str], n: int, rng: np.random.Generator
) -> list[int | None]:
    """``n`` candidates drawn without replacement, balanced over ``labels``: pick k asks for
    the label at k in a shuffled cycle of the labels, and takes a random candidate made for it
    (``emotions[i]``); None where none is left for that label (a fallback face goes there)."""
    pools: dict[str, list[int]] = {label: [] for label in labels}
    for i, emotion in enumerate(emotions):
        if emotion in pools:
            pools[emotion].append(i)
    for pool in pools.values():
        rng.shuffle(pool)
    cycle = label_order(labels, rng)
    picks: list[int | None] = []
    for k in range(n):
        pool = pools[cycle[k % len(cycle)]]
        picks.append(pool.pop() if pool else None)
    return picks


def pick_rows(n_rows: int, count: int, rng: np.random.Generator) -> list[int]:
    """``count`` rows of a table of ``n_rows``: a permutation, cycled when more are asked."""
    if n_rows < 1:
        return []
    out: list[int] = []
    while len(out) < count:
        out += [int(i) for i in rng.permutation(n_rows)]
    return out[:count]
