"""Block order as a design factor: which blocks trade places per participant, and how.

::

    block_order = "latin_square"                   # fixed (default) | latin_square | random
    reordered_blocks = ["make_female", "make_male"]  # default: every block

The reordered blocks must follow one another in the config (a run): they trade places within
the positions of that run, the other blocks keep theirs. ``latin_square`` takes the row of
Williams' balanced Latin square over the run from the session's assignment slot
(:func:`emogen.study.design.assignment_slot`: a keyed hash of the participant id, or with
``counterbalance = "arrival"`` the arrival number — then the k-th session gets block row
k mod B, exact within one session for any number of sessions, and the trials' own Latin
squares take row (k // B) mod R, so that the two orders are crossed);
``random`` draws a permutation from the session's order seed. A session's trial rows record
the order (``trials.block`` by ``position``); the export's ``sessions`` table spells it out
(``block_order``: block names in the order shown).

A block whose trials or check depend on the blocks before it (a block showing the
participant's own faces) cannot trade places with those blocks: the check refuses it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

#: Blocks reordered at most (``random``: every permutation of the run is checked).
MAX_REORDERED = 8


def block_names_of(blocks: Sequence[Any]) -> list[str]:
    """Each block's name (``block<k>`` from 1 where none is given)."""
    return [b.name or f"block{k + 1}" for k, b in enumerate(blocks)]


def reordered(config: Any) -> list[int]:
    """The indices of the blocks that trade places (empty: a fixed block order)."""
    if config.block_order == "fixed":
        return []
    names = block_names_of(config.study_blocks())
    wanted = config.reordered_blocks or tuple(names)
    return [names.index(n) for n in wanted]


def check_block_order(config: Any) -> None:
    """Raise ValueError naming the key where ``block_order`` / ``reordered_blocks`` cannot work."""
    blocks = config.study_blocks()
    names = block_names_of(blocks)
    if config.reordered_blocks and config.block_order == "fixed":
        raise ValueError(
            "reordered_blocks is set but block_order is 'fixed': set block_order = "
            "'latin_square' or 'random' (or leave reordered_blocks out)"
        )
    unknown = [n for n in config.reordered_blocks if n not in names]
    if unknown:
        raise ValueError(
            f"reordered_blocks: {unknown} are not block names of this study ({', '.join(names)})"
        )
    if config.block_order == "fixed":
        return
    run = reordered(config)
    if len(run) < 2 or len(run) > MAX_REORDERED:
        raise ValueError(
            f"block_order = {config.block_order!r} reorders {len(run)} block(s): it needs 2 to "
            f"{MAX_REORDERED} (add [[blocks]] or name them in reordered_blocks)"
        )
    if sorted(run) != list(range(min(run), max(run) + 1)):
        raise ValueError(
            f"reordered_blocks {[names[k] for k in run]} must follow one another in the config "
            "(they trade places within their run of positions)"
        )
    _independent(config, blocks, names, sorted(run))


def _independent(config: Any, blocks: Sequence[Any], names: list[str], run: list[int]) -> None:
    """Every reordered block must stand without the other reordered blocks before it: its
    check passes and it has the same trials with only the blocks before the run."""
    first = run[0]
    conditions = config.conditions()
    before = [c for c in conditions if c.block < first]
    for k in run:
        block = blocks[k]
        try:
            block.check(k + 1, config.emotions, tuple(blocks[:first]))
        except ValueError as exc:
            raise ValueError(
                f"block {k + 1} ({names[k]}) cannot be reordered: it needs blocks before it "
                f"that block_order may move after it ({exc})"
            ) from None
        mine = [c for c in conditions if c.block == k]
        alone = block.trials(k, config, list(before), None)
        if len(alone) != len(mine):
            raise ValueError(
                f"block {k + 1} ({names[k]}) cannot be reordered: its trials depend on the "
                f"blocks before it ({len(mine)} trials after them, {len(alone)} without them)"
            )
