"""Where each identity came in a participant's session: the design's block order, read from
the data (never assumed).

An identity effect is also an order effect (practice, fatigue) when every participant meets
the identities in the same order. :func:`identity_positions` counts, per identity, the
participants who made it in their first, second, … face-making block; :func:`order_sentence`
says what the design did in words for the report: confounded (one order for everyone),
counterbalanced (every identity equally often at every position, within one participant),
or varied but unbalanced (the counts given).
"""

from __future__ import annotations

import pandas as pd


def identity_positions(trials: pd.DataFrame) -> pd.DataFrame:
    """Participants per identity (rows) and block position (columns ``1``, ``2``, …: the
    identity's rank among the participant's face-making blocks by their first trial).

    ``trials``: face-making trials with ``participant_id``, ``identity``, ``trial`` (position
    in the session) and ``block`` (else each identity is its own block)."""
    if trials.empty:
        return pd.DataFrame()
    block = trials["block"] if "block" in trials.columns else trials["identity"]
    t = trials.assign(_block=block.astype(str))
    first = t.groupby(["participant_id", "_block"], sort=False)["trial"].min().reset_index()
    first["position"] = first.groupby("participant_id")["trial"].rank(method="first").astype(int)
    ident = t.groupby(["participant_id", "_block"], sort=False)["identity"].first().reset_index()
    placed = first.merge(ident, on=["participant_id", "_block"])
    table = pd.crosstab(placed["identity"], placed["position"])
    table.columns = [str(c) for c in table.columns]
    return table


def order_sentence(trials: pd.DataFrame) -> str:
    """What the design did with the identities' block order, in words, from the data."""
    table = identity_positions(trials)
    if table.empty or len(table.index) < 2 or len(table.columns) < 2:
        return "The identities were not shown in separate blocks: no block order to balance."
    counts = "; ".join(
        f"{ident}: " + ", ".join(f"{n} at position {pos}" for pos, n in row.items())
        for ident, row in table.iterrows()
    )
    values = table.to_numpy()
    if ((values > 0).sum(axis=1) == 1).all():
        return (
            "The block order was **not counterbalanced**: every participant met the identities "
            f"in the same order ({counts}), so an identity effect is also an order effect "
            "(practice, fatigue)."
        )
    if int(values.max() - values.min()) <= 1:
        return f"The identities' block order was counterbalanced over participants ({counts})."
    return (
        "The identities' block order varied but is **not balanced** over participants "
        f"({counts}): an identity effect is partly an order effect."
    )
