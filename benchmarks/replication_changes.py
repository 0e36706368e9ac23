"""The verdicts that moved between two replication reports (``emogen replicate``'s
``tables/findings.csv``): for each finding of the paper whose verdict differs, or that only one
report has, the two verdicts, the count of each seed's own verdicts, the effect over seeds and
the first seed's numbers — what a reader needs to tell a moved verdict that follows the model
from one that follows the seeds.

    git show 6018cdd:docs/replication/tables/findings.csv > /tmp/rig2.csv
    python -m benchmarks.replication_changes /tmp/rig2.csv docs/replication/tables/findings.csv

(docs/analysis.md, "`emogen replicate`": rig 2 on seeds 41–50 against rig 3 on seeds 201–210.)
"""

from __future__ import annotations

import argparse
from collections import Counter
from pathlib import Path

import pandas as pd

KEY = ["section", "paper_finding"]


def seed_counts(row: pd.Series) -> str:
    """Each seed's own verdict counted, e.g. ``partly 7, inconclusive 3``."""
    seeds = [c for c in row.index if c.startswith("verdict_seed_")]
    counts = Counter(str(row[c]) for c in seeds if pd.notna(row[c]))
    return ", ".join(f"{v} {n}" for v, n in counts.most_common())


def moved(old: pd.DataFrame, new: pd.DataFrame) -> pd.DataFrame:
    """One row per finding whose verdict moved, or that one report lacks."""
    rows = []
    both = old.merge(new, on=KEY, how="outer", suffixes=("_old", "_new"), indicator=True)
    for _, r in both.iterrows():
        if r["_merge"] == "both" and r["verdict_old"] == r["verdict_new"]:
            continue
        rows.append(
            {
                "section": r["section"],
                "finding": r["paper_finding"],
                "old": r.get("verdict_old", "absent") if r["_merge"] != "right_only" else "absent",
                "new": r.get("verdict_new", "absent") if r["_merge"] != "left_only" else "absent",
                "old seeds": seed_counts(r.filter(like="_old").rename(lambda c: c[:-4])),
                "new seeds": seed_counts(r.filter(like="_new").rename(lambda c: c[:-4])),
                "effect old → new": f"{number(r.get('effect_mean_old'))} → "
                f"{number(r.get('effect_mean_new'))}",
                "interval old": r.get("pooled_interval_old"),
                "interval new": r.get("pooled_interval_new"),
                "first seed, new": r.get("ours_first_seed_new"),
            }
        )
    return pd.DataFrame(rows)


def tally(table: pd.DataFrame) -> str:
    """The findings' verdicts counted (``findings.csv`` holds the counted findings; those kept
    outside the tally are in ``outside_tally.csv``)."""
    return ", ".join(f"{v} {n}" for v, n in table["verdict"].value_counts().items())


def number(value: object) -> str:
    """A number to 3 significant figures, or '–' where a report has none."""
    try:
        x = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return "–"
    return "–" if x != x else f"{x:.3g}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old", type=Path, help="the earlier report's tables/findings.csv")
    ap.add_argument("new", type=Path, help="the later report's tables/findings.csv")
    args = ap.parse_args()
    for path in (args.old, args.new):
        if not path.is_file():
            raise SystemExit(f"no findings table at {path}: give a report's tables/findings.csv")
    old, new = pd.read_csv(args.old), pd.read_csv(args.new)
    print(f"old: {len(old)} findings ({tally(old)})")
    print(f"new: {len(new)} findings ({tally(new)})")
    table = moved(old, new)
    print(f"{len(table)} moved")
    with pd.option_context("display.max_colwidth", 200, "display.width", 250):
        for _, r in table.iterrows():
            print(f"\n{r['section']} | {r['finding']}: {r['old']} → {r['new']}")
            print(f"  seeds old: {r['old seeds']}; new: {r['new seeds']}")
            print(f"  effect over seeds: {r['effect old → new']}")
            print(f"  first seed (new): {r['first seed, new']}")
            print(f"  deciding interval old: {r['interval old']}")
            print(f"  deciding interval new: {r['interval new']}")


if __name__ == "__main__":
    main()
