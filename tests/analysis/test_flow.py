"""The participant-flow table (issue #39, report item 7) on a study driven through the study
service with planted dropouts and exclusions, against a plain count over the export's rows and
against the design's known answer.

Eight participants: five finish (one of them answers every selection in 100 ms: excluded as
fast), one stops in the categorise block (both GA trials finished: kept), one stops after one
selection in the GA block (excluded: GA trials unfinished) and one never begins (excluded too:
none of their GA trials finished).
"""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import pandas as pd
import pytest

from emogen.analysis.analyse_options import AnalysisOptions
from emogen.analysis.analyse_people import prepare_people, quality_first
from emogen.analysis.exclusions import ExclusionRule, apply_exclusions
from emogen.analysis.flow import NO_GROUP, participant_flow
from emogen.analysis.people import load_people
from emogen.analysis.report import write_tables
from tests.study.drive import command, run_to_end

STUDY: dict[str, Any] = {
    "name": "flow",
    "emotions": ["happy", "sad"],
    "seed": 4,
    "ga": {"generations": 1, "min_selections": 1, "max_selections": 3},
    "blocks": [
        {"task": "evolve", "name": "make"},
        {"task": "categorise", "name": "label", "own": True},
    ],
}
FINISH = ["P-0", "P-1", "P-2", "P-3", "P-fast"]
GROUPS = {
    "P-0": "a",
    "P-1": "a",
    "P-fast": "a",
    "P-quit-ga": "a",
    "P-2": "b",
    "P-3": "b",
    "P-quit-label": "b",
}  # fmt: skip  (P-never has no row)


@pytest.fixture(scope="module")
def export(ict_model, tmp_path_factory: pytest.TempPathFactory) -> Path:
    from emogen.study.config import study_from_dict
    from emogen.study.export import export_tables, write_export
    from emogen.study.storage import Store
    from tests.study.drive import study_service

    root = tmp_path_factory.mktemp("flow")
    store = Store(f"sqlite:///{root / 'study.sqlite'}")
    service = study_service(study_from_dict(STUDY), store, ict_model)

    def run(pid: str, stop: Any = lambda s: False) -> None:
        token, state = service.create_session(pid)
        run_to_end(state, lambda kind, body: service.step(token, command(kind, body)), stop=stop)

    for pid in FINISH:
        run(pid)
    steps = itertools.count()
    run("P-quit-ga", stop=lambda s: s["stage"] == "trial" and next(steps) >= 1)
    run("P-quit-label", stop=lambda s: s["progress"]["trial"] >= 3)  # one label answered
    service.create_session("P-never")
    write_export(export_tables(store), root / "export", "parquet")
    store.dispose()
    sel = pd.read_parquet(root / "export" / "selections.parquet")
    sel.loc[sel["participant_id"] == "P-fast", "client_response_ms"] = 100.0
    sel.to_parquet(root / "export" / "selections.parquet")
    return root / "export"


def plain_counts(export: Path, table: pd.DataFrame) -> dict[str, int]:
    """Each stage counted row by row over the export's tables and the exclusion table."""
    sessions = pd.read_parquet(export / "sessions.parquet").to_dict("records")
    trials = pd.read_parquet(export / "trials.parquet").to_dict("records")
    out: dict[str, set[str]] = {"arrived": set(), "consented": set(), "finished": set()}
    for s in sessions:
        out["arrived"].add(s["participant_id"])
        if s["consented_at"] is not None and not pd.isna(s["consented_at"]):
            out["consented"].add(s["participant_id"])
        if s["stage"] == "done":
            out["finished"].add(s["participant_id"])
    for t in trials:
        name = f"block {t['block'] + 1}"
        out.setdefault(name, set())
        if t["status"] != "pending":
            out[name].add(t["participant_id"])
    out["excluded"] = set()
    out["fast"] = set()
    out["incomplete"] = set()
    for row in table.to_dict("records"):
        for key in ("excluded", "fast", "incomplete"):
            if row[key]:
                out[key].add(row["participant_id"])
    return {k: len(v) for k, v in out.items()}


def test_the_flow_counts_what_the_export_holds(export: Path) -> None:
    people = load_people(export)
    kept, table = apply_exclusions(people, ExclusionRule())
    analysed = set(kept.faces["participant_id"].astype(str))
    sessions = pd.read_parquet(export / "sessions.parquet")
    trials = pd.read_parquet(export / "trials.parquet")
    flow = participant_flow(sessions, trials, table, analysed).set_index("stage")["participants"]
    plain = plain_counts(export, table)
    assert flow["arrived (a session made)"] == plain["arrived"] == 8
    assert flow["consented"] == plain["consented"] == 8
    assert flow["started block 1 (make)"] == plain["block 1"] == 7  # not P-never
    assert flow["started block 2 (label)"] == plain["block 2"] == 6  # nor P-quit-ga
    assert flow["finished the study"] == plain["finished"] == 5
    assert flow["excluded by the rule"] == plain["excluded"] == 3
    assert flow["excluded: median response time below the floor"] == plain["fast"] == 1
    assert flow["excluded: too few GA trials finished"] == plain["incomplete"] == 2
    assert flow["excluded: elite kept on tile 0"] == 0
    assert flow["analysed (finished faces, not excluded)"] == 5  # 4 finishers + P-quit-label
    assert analysed == {"P-0", "P-1", "P-2", "P-3", "P-quit-label"}
    assert flow["retest sessions (matched to a first session)"] == 0


def test_the_flow_per_group_and_in_the_report(export: Path, tmp_path: Path) -> None:
    groups_file = tmp_path / "participants.csv"
    pd.DataFrame({"participant_id": list(GROUPS), "group": list(GROUPS.values())}).to_csv(
        groups_file, index=False
    )
    opts = AnalysisOptions(participants=groups_file)
    prepared = prepare_people(export, opts)
    quality, flow_sec = quality_first(prepared, tmp_path / "report", opts)[:2]
    write_tables(flow_sec.out, flow_sec.blocks)
    summary = flow_sec.data
    assert list(quality.data) == ["quality"] and list(summary) == ["flow"]
    assert summary["flow"]["finished the study"] == 5
    assert summary["flow"]["excluded by the rule"] == 3
    written = pd.read_csv(tmp_path / "report" / "tables" / "participant_flow.csv")
    assert len(written) > 0
    sessions = pd.read_parquet(export / "sessions.parquet")
    trials = pd.read_parquet(export / "trials.parquet")
    _, table = apply_exclusions(load_people(export), ExclusionRule())
    flow = participant_flow(sessions, trials, table, set(), pd.Series(GROUPS)).set_index("stage")

    # each group's count by hand from the planted design
    def row(stage: str) -> list[int]:
        return [int(flow[g].loc[stage]) for g in ("a", "b", NO_GROUP)]

    assert row("arrived (a session made)") == [4, 3, 1]
    assert row("finished the study") == [3, 2, 0]
    assert row("started block 2 (label)") == [3, 3, 0]
    assert row("excluded by the rule") == [2, 0, 1]
    group_sum = flow[["a", "b", NO_GROUP]].sum(axis=1)
    assert (group_sum == flow["participants"]).all()
