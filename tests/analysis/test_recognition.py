"""Recognition statistics of categorise answers (emogen.analysis.recognition), each against an
independent reference: plain counting loops, Wagner's (1993) formula written out cell by cell,
scipy's t-tests and Holm's procedure by hand."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from emogen.analysis import recognition as rec
from emogen.errors import DataError

EMOTIONS = ("angry", "happy", "sad")


def responses(seed: int = 0, participants: int = 8) -> pd.DataFrame:
    """Answers of a made-up study: own/other/file faces with an intended emotion, random faces,
    a few fallbacks, ``none`` answers and unanswered trials; labels right ~60% of the time."""
    rng = np.random.default_rng(seed)
    rows = []
    for p in range(participants):
        for t in range(40):
            source = rng.choice(["own", "other", "file", "random"], p=[0.3, 0.3, 0.2, 0.2])
            intended = None if source == "random" else str(rng.choice(EMOTIONS))
            if rng.uniform() < 0.6 and intended is not None:
                label: str | None = intended
            else:
                label = str(rng.choice([*EMOTIONS, "none"], p=[0.3, 0.3, 0.3, 0.1]))
            if rng.uniform() < 0.05:
                label = None  # unanswered
            rows.append(
                {
                    "participant_id": f"P{p}",
                    "trial": t,
                    "source": source,
                    "fallback": bool(source == "other" and rng.uniform() < 0.1),
                    "intended": intended,
                    "label": label,
                }
            )
    return pd.DataFrame(rows)


def scored(r: pd.DataFrame) -> list[dict[str, object]]:
    """Answered rows as dicts, with fallback and random faces' intended set to None by hand."""
    out = []
    for row in r.to_dict(orient="records"):
        if pd.isna(row["label"]):
            continue
        if row["fallback"] or row["source"] == "random" or pd.isna(row["intended"]):
            row["intended"] = None
        out.append(row)
    return out


def test_confusion_counts_and_row_shares_match_a_plain_count() -> None:
    r = responses()
    got = rec.confusion_table(r)
    rows = scored(r)
    count: Counter[tuple[str, str, str]] = Counter()
    for row in rows:
        if row["intended"] is not None:
            count[("all", str(row["intended"]), str(row["label"]))] += 1
            count[(str(row["source"]), str(row["intended"]), str(row["label"]))] += 1
        elif row["source"] == "random":
            count[("random", rec.RANDOM_ROW, str(row["label"]))] += 1
    assert len(got) == len(count)
    for g in got.itertuples():
        assert g.count == count[(g.source, g.intended, g.label)]
        total = sum(v for k, v in count.items() if k[:2] == (g.source, g.intended))
        assert g.proportion == pytest.approx(g.count / total)
    assert set(got["source"]) == {"all", "own", "other", "file", "random"}


def test_unbiased_hit_rates_match_wagners_formula_cell_by_cell() -> None:
    r = responses(1)
    got = rec.unbiased_hit_rates(r).set_index(["participant_id", "emotion"])
    rows = [x for x in scored(r) if x["intended"] is not None]
    for pid in sorted({str(x["participant_id"]) for x in rows}):
        mine = [x for x in rows if x["participant_id"] == pid]
        labels = sorted({str(x["label"]) for x in mine} | set(EMOTIONS))
        matrix = {(i, j): 0 for i in EMOTIONS for j in labels}
        for x in mine:
            matrix[(str(x["intended"]), str(x["label"]))] += 1
        n = sum(matrix.values())
        for e in EMOTIONS:
            row_total = sum(matrix[(e, j)] for j in labels)
            col_total = sum(matrix[(i, e)] for i in EMOTIONS)
            if row_total == 0:
                assert (pid, e) not in got.index
                continue
            hit = matrix[(e, e)]
            hu = 0.0 if col_total == 0 else (hit / row_total) * (hit / col_total)
            pc = (row_total / n) * (col_total / n)
            assert got.loc[(pid, e), "hu"] == pytest.approx(hu)
            assert got.loc[(pid, e), "pc"] == pytest.approx(pc)
            assert got.loc[(pid, e), "n_answers"] == n


def holm_by_hand(p: list[float]) -> list[float]:
    order = sorted(range(len(p)), key=lambda i: p[i])
    out, running = [0.0] * len(p), 0.0
    for rank, i in enumerate(order):
        running = max(running, min(1.0, (len(p) - rank) * p[i]))
        out[i] = running
    return out


def test_hit_rate_tests_are_arcsine_t_tests_with_holm() -> None:
    hu = rec.unbiased_hit_rates(responses(2, participants=12))
    got = rec.hu_tests(hu, alpha=0.05).set_index("emotion")
    ps = []
    for e in EMOTIONS:
        part = hu[hu["emotion"] == e]
        diff = np.arcsin(np.sqrt(part["hu"])) - np.arcsin(np.sqrt(part["pc"]))
        ref = stats.ttest_1samp(diff, 0.0)
        assert got.loc[e, "t"] == pytest.approx(ref.statistic)
        assert got.loc[e, "p"] == pytest.approx(ref.pvalue)
        ci = ref.confidence_interval(0.95)
        assert (got.loc[e, "ci_low"], got.loc[e, "ci_high"]) == pytest.approx((ci.low, ci.high))
        ps.append(float(ref.pvalue))
    assert list(got.loc[list(EMOTIONS), "p_holm"]) == pytest.approx(holm_by_hand(ps))
    # labels right ~60% of the time with 3 emotions: far above chance for every emotion
    assert got["above_chance"].all()


def test_accuracy_by_source_is_paired_over_participants() -> None:
    r = responses(3, participants=10)
    per = rec.accuracy_per_participant(r)
    rows = [x for x in scored(r) if x["intended"] is not None]
    acc: dict[tuple[str, str], list[float]] = {}
    for x in rows:
        key = (str(x["participant_id"]), str(x["source"]))
        acc.setdefault(key, []).append(float(x["label"] == x["intended"]))
    assert len(per) == len(acc)
    for g in per.itertuples():
        assert g.accuracy == pytest.approx(np.mean(acc[(g.participant_id, g.source)]))
    pairs = rec.source_comparisons(per).set_index(["source_a", "source_b"])
    assert list(pairs.index) == [("own", "other"), ("own", "file"), ("other", "file")]
    people = sorted({k[0] for k in acc})
    own = [np.mean(acc[(p, "own")]) for p in people]
    other = [np.mean(acc[(p, "other")]) for p in people]
    ref = stats.ttest_rel(own, other)
    assert pairs.loc[("own", "other"), "t"] == pytest.approx(ref.statistic)
    assert pairs.loc[("own", "other"), "p"] == pytest.approx(ref.pvalue)


def test_a_responses_table_without_its_columns_is_a_plain_error() -> None:
    with pytest.raises(DataError, match="lacks column"):
        rec.confusion_table(pd.DataFrame({"participant_id": ["a"], "label": ["happy"]}))
