"""Block order as a design factor (``block_order``, ``reordered_blocks``): the example design
counterbalances which identity a participant makes first, each session's order is recorded
and exported, the report says what the design did from the data, and configs where a
reordering cannot work are refused, naming the key."""

from __future__ import annotations

import tomllib
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

from emogen.analysis.block_positions import order_sentence
from emogen.errors import ConfigError
from emogen.study.config import study_from_dict
from emogen.study.dashboard import block_orders
from emogen.study.design import trial_order
from emogen.study.export import export_tables
from emogen.study.replay import replay_session
from emogen.study.simulate import SimulationPlan, simulate_study
from emogen.study.storage import Store
from emogen.tasks.simulated import SimulatedDesign

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "published-design.toml"


def example(**changes: Any) -> dict[str, Any]:
    """The example design, quicker (one generation), with ``changes``."""
    data = tomllib.loads(EXAMPLE.read_text())
    data["ga"] = {**data["ga"], "generations": 1}
    return {**data, **changes}


def simulated(
    tmp_path: Path, model: Any, data: dict[str, Any], n: int
) -> tuple[dict[str, pd.DataFrame], list[dict[str, Any]]]:
    url = f"sqlite:///{tmp_path / 'bo.sqlite'}"
    plan = SimulationPlan(study_from_dict(data), url, 5, n, SimulatedDesign(), False)
    simulate_study(plan, model=model)
    store = Store(url)
    try:
        tables = export_tables(store)
        sid = int(tables["sessions"]["session_id"].iloc[1])
        report = replay_session(store, sid, model.rig, model.model_hash, model=model)
        assert report.ok, report.mismatches
        orders = block_orders(store, plan.config, (1,))  # the dashboard's counts
    finally:
        store.dispose()
    return tables, orders


def positions(trials: pd.DataFrame) -> Counter[tuple[str, int]]:
    """(identity, block position) → participants: a plain loop over the exported trials."""
    out: Counter[tuple[str, int]] = Counter()
    for _, t in trials[trials["task"] == "evolve"].groupby("participant_id"):
        seen: list[str] = []
        for _, row in t.sort_values("trial").iterrows():
            if row["identity"] not in seen:
                seen.append(row["identity"])
        out.update((ident, k + 1) for k, ident in enumerate(seen))
    return out


def test_example_design_balances_identity_over_block_positions(
    tmp_path: Path, ict_model: Any
) -> None:
    tables, dashboard = simulated(tmp_path, ict_model, example(), n=8)
    counts = positions(tables["trials"])
    assert counts == {
        ("female-medium", 1): 4,
        ("female-medium", 2): 4,
        ("male-medium", 1): 4,
        ("male-medium", 2): 4,
    }
    # each session's exported block order is the order its trials were shown in
    orders = tables["sessions"].set_index("participant_id")["block_order"]
    assert Counter(orders) == {
        "make_female>make_male>recognise": 4,
        "make_male>make_female>recognise": 4,
    }
    assert dashboard == [
        {"order": "make_female>make_male>recognise", "sessions": 4, "done": 4},
        {"order": "make_male>make_female>recognise", "sessions": 4, "done": 4},
    ]
    evolve = tables["trials"][tables["trials"]["task"] == "evolve"]
    first = evolve.sort_values("trial").groupby("participant_id")["block_name"].first()
    assert all(orders[p].startswith(first[p]) for p in first.index)
    sentence = order_sentence(evolve)
    assert "counterbalanced over participants" in sentence and "not" not in sentence
    assert "female-medium: 4 at position 1, 4 at position 2" in sentence


def test_a_fixed_block_order_is_reported_as_confounded(tmp_path: Path, ict_model: Any) -> None:
    data = example()
    del data["block_order"], data["reordered_blocks"]
    tables, dashboard = simulated(tmp_path, ict_model, data, n=3)
    assert dashboard == []  # blocks in config order: no block-order table
    evolve = tables["trials"][tables["trials"]["task"] == "evolve"]
    assert positions(tables["trials"]) == {("female-medium", 1): 3, ("male-medium", 2): 3}
    sentence = order_sentence(evolve)
    assert "**not counterbalanced**" in sentence and "order effect" in sentence
    assert set(tables["sessions"]["block_order"]) == {"make_female>make_male>recognise"}


def test_an_unbalanced_order_is_said_to_be_unbalanced() -> None:
    rows = []
    for p, first in enumerate(["f", "f", "f", "m"]):
        second = "m" if first == "f" else "f"
        rows += [
            {"participant_id": f"P{p}", "identity": first, "trial": 0, "block": first},
            {"participant_id": f"P{p}", "identity": second, "trial": 1, "block": second},
        ]
    sentence = order_sentence(pd.DataFrame(rows))
    assert "**not balanced**" in sentence and "f: 3 at position 1, 1 at position 2" in sentence


@pytest.mark.parametrize(
    ("changes", "words"),
    [
        ({"reordered_blocks": ["make_male", "recognise"]}, "(recognise) cannot be reordered"),
        ({"reordered_blocks": ["make_female", "makemale"]}, "['makemale'] are not block names"),
        ({"block_order": "fixed"}, "reordered_blocks is set but block_order is 'fixed'"),
        ({"block_order": "sometimes"}, "'block_order'"),
        ({"reordered_blocks": ["make_female"]}, "reorders 1 block(s)"),
    ],
)
def test_block_orders_that_cannot_work_are_refused(changes: dict[str, Any], words: str) -> None:
    with pytest.raises(ConfigError) as err:
        study_from_dict(example(**changes), "design.toml")
    assert words in str(err.value)


def test_reordered_blocks_must_be_one_run() -> None:
    data = example()
    data["blocks"] = [data["blocks"][0], data["blocks"][2], data["blocks"][1]]
    data["blocks"][1] = {**data["blocks"][1], "own": False}
    with pytest.raises(ConfigError, match="must follow one another"):
        study_from_dict(data, "design.toml")


def test_two_blocks_of_one_name_are_refused() -> None:
    data = example(block_order="fixed", reordered_blocks=[])
    data["blocks"][1] = {**data["blocks"][1], "name": "make_female"}
    with pytest.raises(ConfigError, match="two blocks are named 'make_female'"):
        study_from_dict(data, "design.toml")


def test_arrivals_balance_block_order_for_any_number_and_cross_it_with_emotion_rows() -> None:
    config = study_from_dict(example())
    rng = np.random.default_rng(0)  # not drawn: a Latin square is no draw
    seen = [trial_order(config, slot=k, rng=rng) for k in range(30)]
    for n in range(1, 31):  # every prefix of the arrivals: the two orders within one session
        firsts = Counter(o.blocks[0] for o in seen[:n])
        assert abs(firsts[0] - firsts[1]) <= 1, n
    pairs = [(o.block_row, o.row) for o in seen[:8]]
    assert sorted(pairs) == [(b, r) for b in range(2) for r in range(4)]  # crossed every 8
