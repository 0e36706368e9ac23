"""Exports for the tests: a simulated study's tables (:func:`simulated_tables`), and an export as
schema ``emogen.study/5`` wrote it, made from a new one (:func:`as_schema5`: for the tests that
old exports still analyse and replay).

Schema 5 had no ``final_faces`` table, called ``categorise_responses`` ``responses`` and
``evolve_ratings`` ``ratings``, and gave a categorise trial's ``trials.emotion`` the intended
emotion of its face.
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import pandas as pd

from emogen import columns as tidy
from emogen.study.config import study_from_dict
from emogen.study.export import export_tables
from emogen.study.simulate import SimulationPlan, simulate_study
from emogen.study.storage import Store
from emogen.tasks.simulated import SimulatedDesign

#: A small study of both tasks: an evolve block, then a categorise block of own, others' and
#: random faces (faces not corrected: fast).
MIXED: dict[str, Any] = {
    "name": "mixed",
    "seed": 3,
    "emotions": ["happy", "sad"],
    "repetitions": 2,
    "correct": False,
    "ga": {"generations": 3, "min_selections": 1, "max_selections": 5},
    "blocks": [{"task": "evolve"}, {"task": "categorise", "own": True, "others": 2, "random": 1}],
}
RENAMED = {"categorise_responses": "responses", "evolve_ratings": "ratings"}


def read_export_table(path: Path) -> pd.DataFrame:
    return pd.read_parquet(path) if path.suffix == ".parquet" else tidy.read_csv(path)


def write_export_table(df: pd.DataFrame, path: Path) -> None:
    if path.suffix == ".parquet":
        df.to_parquet(path, index=False)
    else:
        path.write_text(tidy.csv_text(df), encoding="utf-8")


def as_schema5(new: Path, old: Path) -> Path:
    """A copy of the export folder ``new`` at ``old``, as schema 5 wrote it (module doc)."""
    shutil.copytree(new, old)
    fmt = "parquet" if (old / "trials.parquet").is_file() else "csv"
    (old / f"final_faces.{fmt}").unlink()
    for now, before in RENAMED.items():
        (old / f"{now}.{fmt}").rename(old / f"{before}.{fmt}")
    types = old / tidy.COL_TYPES
    if types.is_file():
        text = types.read_text()
        for now, before in RENAMED.items():
            text = text.replace(f"\n{now},", f"\n{before},")
        lines = [line for line in text.splitlines() if not line.startswith("final_faces,")]
        types.write_text("".join(line + "\n" for line in lines))
    trials, responses = (
        read_export_table(old / f"trials.{fmt}"),
        read_export_table(old / f"responses.{fmt}"),
    )
    intended = responses.set_index(["session_id", "trial"])["intended"]
    categorise = trials["task"] == "categorise"
    at = pd.MultiIndex.from_frame(trials.loc[categorise, ["session_id", "trial"]])
    trials.loc[categorise, "emotion"] = intended.reindex(at).to_numpy()
    for name in [p.stem for p in old.glob(f"*.{fmt}") if p.name != tidy.COL_TYPES]:
        table = trials if name == "trials" else read_export_table(old / f"{name}.{fmt}")
        table["schema_version"] = "emogen.study/5"
        write_export_table(table, old / f"{name}.{fmt}")
    return old


def simulated_tables(
    root: Path, model: Any, study: dict[str, Any], participants: int, seed: int
) -> dict[str, pd.DataFrame]:
    """The export tables of ``study`` run by simulated participants (``emogen study simulate``)
    in a SQLite database under ``root``."""
    url = f"sqlite:///{root / 'study.sqlite'}"
    plan = SimulationPlan(
        study_from_dict(study),
        url,
        seed=seed,
        participants=participants,
        design=SimulatedDesign(),
        shuffle_prototypes=False,
    )
    simulate_study(plan, model=model)
    store = Store(url)
    try:
        return export_tables(store)
    finally:
        store.dispose()
