"""A stated, pre-registrable exclusion rule, applied before every analysis of people.

:class:`ExclusionRule` holds the thresholds (a ``None`` switches a criterion off); write its
values into the pre-registration. :func:`apply_exclusions` computes each participant's quality
measures (over all their sessions), flags the criteria they meet, and returns the people without
the excluded ones plus a table of everyone with the reasons.

The defaults are chosen so that a participant who chooses faces by their content (the simulated
participants of ``emogen study simulate``) is essentially never excluded — each chance criterion
has a per-participant false-alarm probability below ~10⁻³ under uniformly placed faces — while a
participant who clicks without looking (always the same tile, at a glance) is:

* ``min_median_rt_ms`` = 300: the median time to choose among ten faces below 300 ms is faster
  than looking at them (only where a response time is recorded: see
  :mod:`emogen.analysis.quality`);
* ``max_same_tile_share`` = 0.75 (with ``min_events`` = 8): the elite of generation 0 — a
  shuffled population, so position-neutral — on one tile in more than 75 % of the trials
  (uniform over 10 tiles, 8 trials: P(≥ 7 of 8 on one tile) = 10 · P(Binomial(8, 0.1) ≥ 7)
  ≈ 7·10⁻⁶);
* ``max_keep_tile0_share`` = 0.9 (with ``min_elites`` = 20): the elite on tile 0 in > 90 % of
  all generations — tile 0 holds the carried elite from generation 1 on, so this participant
  (almost) never changed their face;
* ``min_finished_share`` = 0.75: fewer than 75 % of the participant's GA trials finished.

Categorisation (the ``categorise_responses`` of categorise blocks; a participant without any is
not judged on them; each judged with at least ``min_categorise_answers`` = 10 answers):

* ``max_categorise_label_share`` = 0.9: one answer (a label, or "none of these") given in more
  than 90 % of the trials — one key pressed throughout (a participant answering by the faces'
  emotions spreads over the labels: with 4 labels + none, P(≥ 10 of 10 on one) ≈ 5·10⁻⁶ even at
  random);
* ``min_categorise_accuracy_over_chance`` = 0: accuracy on the faces with a known intended
  emotion (``correct``) at or below chance — the mean over those trials of 1 / the number of
  emotion labels offered, k (not counting "none of these": 1/k, not 1/(k+1), the stricter
  level — a participant between the two is treated as at chance);
* ``min_categorise_median_rt_ms`` = 400: the median time from the face drawn to the answer sent
  (``client_response_ms``: the browser's; simulated participants have none and are not judged)
  below 400 ms — faster than seeing a face and finding its label.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from emogen.analysis.people import People
from emogen.analysis.quality import selection_positions
from emogen.errors import ConfigError


@dataclass(frozen=True)
class ExclusionRule:
    """Thresholds of the exclusion rule (see the module docstring); ``None``: not applied."""

    min_median_rt_ms: float | None = 300.0
    max_same_tile_share: float | None = 0.75
    min_events: int = 8
    max_keep_tile0_share: float | None = 0.9
    min_elites: int = 20
    min_finished_share: float | None = 0.75
    max_categorise_label_share: float | None = 0.9
    min_categorise_accuracy_over_chance: float | None = 0.0
    min_categorise_median_rt_ms: float | None = 400.0
    min_categorise_answers: int = 10

    def __post_init__(self) -> None:
        for name in (
            "max_same_tile_share",
            "max_keep_tile0_share",
            "min_finished_share",
            "max_categorise_label_share",
        ):
            v = getattr(self, name)
            if v is not None and not 0 <= v <= 1:
                raise ConfigError(f"exclusion rule {name} must be a share in [0, 1]; got {v}")

    def describe(self) -> list[str]:
        """The rule in words, one line per criterion applied."""
        out = []
        if self.min_median_rt_ms is not None:
            out.append(f"median selection response time < {self.min_median_rt_ms:g} ms")
        if self.max_same_tile_share is not None:
            out.append(
                f"generation-0 elite on one tile in > {self.max_same_tile_share:.0%} of trials "
                f"(judged with >= {self.min_events} trials)"
            )
        if self.max_keep_tile0_share is not None:
            out.append(
                f"elite on tile 0 (the carried elite) in > {self.max_keep_tile0_share:.0%} of "
                f"generations (judged with >= {self.min_elites} generations)"
            )
        if self.min_finished_share is not None:
            out.append(f"< {self.min_finished_share:.0%} of GA trials finished")
        judged = f"(judged with >= {self.min_categorise_answers} categorise answers)"
        if self.max_categorise_label_share is not None:
            out.append(
                f"one categorise answer in > {self.max_categorise_label_share:.0%} of trials {judged}"
            )
        if self.min_categorise_accuracy_over_chance is not None:
            margin = self.min_categorise_accuracy_over_chance
            above = f" + {margin:g}" if margin else ""
            out.append(
                f"categorise accuracy <= chance{above} (chance: 1 / the emotion labels offered) "
                f"{judged}"
            )
        if self.min_categorise_median_rt_ms is not None:
            out.append(f"median categorise response time < {self.min_categorise_median_rt_ms:g} ms")
        return out


def participant_measures(people: People) -> pd.DataFrame:
    """One row per participant: ``median_rt_ms``, ``g0_events``, ``g0_top_tile_share``,
    ``elites``, ``elite_tile0_share``, ``finished_share`` (NaN where not recorded)."""
    t = people.trials
    done = (t["status"] == "done").groupby(t["participant_id"].astype(str)).mean()
    out = pd.DataFrame({"finished_share": done})
    out.index.name = "participant_id"
    sel = selection_positions(people)
    cols = ["median_rt_ms", "g0_events", "g0_top_tile_share", "elites", "elite_tile0_share"]
    if sel is None:
        return out.assign(**{str(c): np.nan for c in cols}).reset_index()[
            ["participant_id", *cols, "finished_share"]
        ]
    out["median_rt_ms"] = sel.groupby("participant_id")["rt_ms"].median()
    elite = sel[sel["role"] == "elite"] if "role" in sel.columns else sel
    elite = elite[elite["position"].notna()]
    g0 = elite[elite["generation"] == 0]
    out["g0_events"] = g0.groupby("participant_id").size()
    top = g0.groupby(["participant_id", "position"]).size().groupby("participant_id").max()
    out["g0_top_tile_share"] = top / out["g0_events"]
    out["elites"] = elite.groupby("participant_id").size()
    out["elite_tile0_share"] = (elite["position"] == 0).groupby(elite["participant_id"]).mean()
    return out.reset_index()[["participant_id", *cols, "finished_share"]]


#: The categorisation measures (NaN for a participant without categorise answers).
CATEGORISE = ["cat_answers", "cat_top_label_share", "cat_scored", "cat_accuracy", "cat_chance",
              "cat_median_rt_ms"]  # fmt: skip


def categorise_measures(people: People) -> pd.DataFrame:
    """One row per participant with categorise answers: their count, the most-given answer's
    share, the trials scored (intended emotion known), the accuracy on them and its chance
    level, the median browser response time."""
    r = people.responses
    if r is None or r.empty or "label" not in r.columns:
        return pd.DataFrame(columns=["participant_id", *CATEGORISE])
    r = r[r["label"].notna()].assign(participant_id=lambda d: d["participant_id"].astype(str))
    by = r.groupby("participant_id")
    out = pd.DataFrame({"cat_answers": by.size()})
    out["cat_top_label_share"] = by["label"].agg(lambda x: x.value_counts().iloc[0] / len(x))
    scored = r[r["correct"].notna()]
    offered = scored["labels"].astype(str).map(lambda labels: len(labels.split("|")))
    scored = scored.assign(hit=scored["correct"].astype(bool).astype(float), chance=1.0 / offered)
    out["cat_scored"] = scored.groupby("participant_id").size()
    out["cat_accuracy"] = scored.groupby("participant_id")["hit"].mean()
    out["cat_chance"] = scored.groupby("participant_id")["chance"].mean()
    rt = r["client_response_ms"] if "client_response_ms" in r.columns else None
    out["cat_median_rt_ms"] = np.nan if rt is None else rt.groupby(r["participant_id"]).median()
    out["cat_scored"] = out["cat_scored"].fillna(0)
    return out.reset_index()[["participant_id", *CATEGORISE]]


def _flags(m: pd.DataFrame, rule: ExclusionRule) -> pd.DataFrame:
    """Boolean flags per criterion (False where the measure is missing or too thin)."""
    f = pd.DataFrame({"participant_id": m["participant_id"]})
    f["fast"] = (
        m["median_rt_ms"].lt(rule.min_median_rt_ms) if rule.min_median_rt_ms is not None else False
    )
    enough = m["g0_events"].fillna(0) >= rule.min_events
    f["one_tile"] = (
        enough & m["g0_top_tile_share"].gt(rule.max_same_tile_share)
        if rule.max_same_tile_share is not None
        else False
    )
    many = m["elites"].fillna(0) >= rule.min_elites
    f["keeps_tile0"] = (
        many & m["elite_tile0_share"].gt(rule.max_keep_tile0_share)
        if rule.max_keep_tile0_share is not None
        else False
    )
    f["incomplete"] = (
        m["finished_share"].lt(rule.min_finished_share)
        if rule.min_finished_share is not None
        else False
    )
    answers = m["cat_answers"].fillna(0) >= rule.min_categorise_answers
    share = rule.max_categorise_label_share
    f["one_label"] = answers & m["cat_top_label_share"].gt(share) if share is not None else False
    margin = rule.min_categorise_accuracy_over_chance
    scored = m["cat_scored"].fillna(0) >= rule.min_categorise_answers
    f["at_chance"] = (
        scored & m["cat_accuracy"].le(m["cat_chance"] + margin) if margin is not None else False
    )
    floor = rule.min_categorise_median_rt_ms
    f["fast_labels"] = m["cat_median_rt_ms"].lt(floor) if floor is not None else False
    return f


REASONS = {
    "fast": "median response time {median_rt_ms:.0f} ms",
    "one_tile": "generation-0 elite on one tile in {g0_top_tile_share:.0%} of trials",
    "keeps_tile0": "elite on tile 0 in {elite_tile0_share:.0%} of generations",
    "incomplete": "finished {finished_share:.0%} of GA trials",
    "one_label": "one categorise answer in {cat_top_label_share:.0%} of trials",
    "at_chance": "categorise accuracy {cat_accuracy:.0%} (chance {cat_chance:.0%})",
    "fast_labels": "median categorise response time {cat_median_rt_ms:.0f} ms",
}


def apply_exclusions(people: People, rule: ExclusionRule) -> tuple[People, pd.DataFrame]:
    """``people`` without the participants ``rule`` excludes, and one row per participant:
    the measures of :func:`participant_measures`, a boolean per criterion, ``excluded`` and
    ``reasons`` (text; empty when kept)."""
    m = participant_measures(people).merge(
        categorise_measures(people), on="participant_id", how="left"
    )
    flags = _flags(m, rule)
    table = m.merge(flags, on="participant_id")
    crit = list(REASONS)
    table["excluded"] = table[crit].any(axis=1)
    table["reasons"] = [
        "; ".join(REASONS[c].format(**{str(k): v for k, v in row.items()}) for c in crit if row[c])
        for row in table.to_dict("records")
    ]
    out = set(table.loc[table["excluded"], "participant_id"].astype(str))
    return drop_participants(people, out), table


def drop_participants(people: People, ids: set[str]) -> People:
    """``people`` without the participants ``ids`` in any of its tables."""
    if not ids:
        return people

    def keep(df: pd.DataFrame) -> pd.DataFrame:
        if df.empty or "participant_id" not in df.columns:
            return df
        return df[~df["participant_id"].astype(str).isin(ids)].reset_index(drop=True)

    def maybe(df: pd.DataFrame | None) -> pd.DataFrame | None:
        return None if df is None else keep(df)

    return replace(
        people,
        faces=keep(people.faces),
        trials=keep(people.trials),
        selections=keep(people.selections),
        responses=maybe(people.responses),
        ratings=maybe(people.ratings),
        sessions=maybe(people.sessions),
    )


#: The rule's minimum counts (numbers, never ``none``).
COUNTS = ("min_events", "min_elites", "min_categorise_answers")


def rule_from_options(changes: list[str]) -> ExclusionRule:
    """The default rule with ``KEY=VALUE`` changes (``none`` turns a criterion off)."""
    fields = {f.name: f for f in dataclasses.fields(ExclusionRule)}
    values: dict[str, object] = {}
    for change in changes:
        key, sep, raw = change.partition("=")
        key, raw = key.strip(), raw.strip()
        if not sep or key not in fields:
            raise ConfigError(
                f"--exclusion must be KEY=VALUE with KEY one of {', '.join(fields)}; got {change!r}"
            )
        if raw.lower() == "none":
            if key in COUNTS:
                raise ConfigError(f"--exclusion {key} needs a number; got {raw!r}")
            values[key] = None
            continue
        try:
            values[key] = int(raw) if key in COUNTS else float(raw)
        except ValueError:
            raise ConfigError(f"--exclusion {key} needs a number or 'none'; got {raw!r}") from None
    return ExclusionRule(**values)  # type: ignore[arg-type]
