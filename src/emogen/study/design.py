"""Trial order: random (seeded per session), balanced Latin square (row by participant), fixed.

Trials are the conditions emotions × identities × repetitions (``StudyConfig.conditions``).
A participant's seed comes from a keyed hash of the study seed and the participant id
(:func:`participant_seed`), never from the order of arrival: sessions made by others
(anonymous or not) shift nobody's seeds. The Latin-square row comes from that hash too
(``counterbalance = "hash"``: balanced in expectation only — three participants may get rows
3, 1, 7) or, with ``counterbalance = "arrival"``, from the order of arrival (exact: rows 0, 1,
2 …; :func:`assignment_slot`). Either way the row is stored with the session, and replay reads
the stored order.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from emogen.rng import fresh_seed
from emogen.study.block_order import reordered
from emogen.study.config import StudyConfig
from emogen.tasks.blocks import Condition

#: Domain of the keyed hashes (changing it would change every new participant's assignment).
ASSIGNMENT_KEY = b"emogen.study/assignment/1"


def _digest(purpose: str, key: str, participant_id: str) -> bytes:
    message = "\x1f".join((purpose, key, participant_id)).encode()
    return hashlib.blake2b(message, key=ASSIGNMENT_KEY, digest_size=16).digest()


def participant_seed(study_seed: int | None, participant_id: str) -> int:
    """The seed of a participant's session: a keyed hash of the study seed and the participant
    id (the same participant always gets the same seed); a fresh seed when the study has none."""
    if study_seed is None:
        return fresh_seed()
    words = np.frombuffer(_digest("seed", str(study_seed), participant_id), dtype="<u4")
    entropy = [int(study_seed), *(int(w) for w in words)]
    return int(np.random.SeedSequence(entropy).generate_state(2, np.uint64)[0] >> np.uint64(1))


def participant_slot(config: StudyConfig, participant_id: str) -> int:
    """A participant's assignment slot (a large non-negative int; the Latin-square row is it
    modulo the number of rows): uniform over participants, so rows stay balanced in expectation."""
    key = str(config.seed) if config.seed is not None else "name:" + config.name
    return int.from_bytes(_digest("order", key, participant_id)[:8], "little")


def assignment_slot(config: StudyConfig, participant_id: str, *, arrival: int) -> int:
    """The slot a new session's Latin-square rows come from: :func:`participant_slot` (the
    default, ``counterbalance = "hash"``), or with ``counterbalance = "arrival"`` the session's
    arrival number (0, 1, 2 … in the study, counted under the study's lock): the k-th session
    gets row k modulo the rows, so every row is used equally often up to one session."""
    if config.counterbalance == "arrival":
        return arrival
    return participant_slot(config, participant_id)


@dataclass(frozen=True)
class TrialOrder:
    """order: condition indices in presentation order; row: the Latin-square row used (or -1)."""

    order: tuple[int, ...]
    kind: str
    row: int
    #: the blocks in the order shown, and the block order's Latin-square row (-1: none)
    blocks: tuple[int, ...] = ()
    block_row: int = -1


def balanced_latin_square(n: int) -> list[list[int]]:
    """Williams' balanced Latin square: every condition precedes every other equally often.

    n rows for even n; 2n rows (each row and its mirror) for odd n.
    """
    if n < 1:
        return []
    # 0, 1, n-1, 2, n-2, ... then each row shifted by one
    first = [0] + [(j + 1) // 2 if j % 2 == 1 else n - j // 2 for j in range(1, n)]
    rows = [[(c + r) % n for c in first] for r in range(n)]
    if n % 2 == 1:
        rows += [list(reversed(row)) for row in rows]
    return rows


def _block_order(order: str, n: int, slot: int, rng: np.random.Generator) -> TrialOrder:
    """One block's order of its ``n`` trials."""
    if order == "fixed":
        return TrialOrder(tuple(range(n)), "fixed", -1)
    if order == "latin_square":
        rows = balanced_latin_square(n)
        row = slot % len(rows) if rows else -1
        return TrialOrder(tuple(rows[row]) if rows else (), "latin_square", row)
    return TrialOrder(tuple(int(i) for i in rng.permutation(n)), "random", -1)


def block_sequence(
    config: StudyConfig, slot: int, rng: np.random.Generator
) -> tuple[list[int], int, int]:
    """The session's blocks in the order shown, the block order's row (-1: none) and the slot
    the trials' own Latin squares take their rows from (:mod:`emogen.study.block_order`).

    ``latin_square``: block row = ``slot`` mod the block rows B (by arrival: exact for any
    number of sessions, within one), and the trials' slot ``slot // B``, so that every block
    order meets every row of the trials' squares (crossed every B × their rows sessions);
    ``random`` draws the order with ``rng``; a fixed order leaves ``slot`` as it is."""
    n = len(config.study_blocks())
    run = sorted(reordered(config))
    if not run:
        return list(range(n)), -1, slot
    if config.block_order == "random":
        local, row = [int(i) for i in rng.permutation(len(run))], -1
    else:
        rows = balanced_latin_square(len(run))
        row, slot = slot % len(rows), slot // len(rows)
        local = rows[row]
    out = list(range(n))
    out[run[0] : run[-1] + 1] = [run[j] for j in local]
    return out, row, slot


def trial_order(
    config: StudyConfig,
    conditions: Sequence[Condition] | None = None,
    *,
    slot: int,
    rng: np.random.Generator,
) -> TrialOrder:
    """The order of a session's trials (indices into ``conditions``): block after block, each
    block's trials in its own order, drawn with ``rng`` in block order. A counterbalanced
    block's Latin-square row is ``slot`` modulo its rows (``slot`` is :func:`participant_slot`;
    sessions recorded before it used their number). ``kind`` and ``row`` are those of the first
    counterbalanced block (another block's order is ``random`` or ``fixed``)."""
    conditions = config.conditions() if conditions is None else conditions
    blocks = config.study_blocks()
    sequence, block_row, slot = block_sequence(config, slot, rng)
    order: list[int] = []
    kind, row = "", -1
    for k in sequence:
        block = blocks[k]
        indices = [i for i, c in enumerate(conditions) if c.block == k]
        local = _block_order(block.order or "random", len(indices), slot, rng)
        order += [indices[j] for j in local.order]
        if not kind and block.counterbalanced:
            kind, row = local.kind, local.row
    return TrialOrder(tuple(order), kind or "random", row, tuple(sequence), block_row)
