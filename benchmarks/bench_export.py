"""Export of a large study: peak memory and time of ``emogen study export`` (and the dashboard).

``python benchmarks/bench_export.py [--sessions 1000] [--database-url URL]`` fills a database
with that many completed sessions of the load benchmark's study (one session run through the
real study service — GA, correction, storage — then its rows copied with new ids, tokens and
participant ids), then runs ``python -m emogen study export`` (Parquet and CSV) under
``/usr/bin/time -v`` and prints its wall time and peak resident memory (the whole process:
Python, pandas, pyarrow and the data). ``--in-memory`` also measures the one-table-at-once
path (:func:`emogen.study.export.export_tables` + ``write_export``), for comparison.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO), str(REPO / "src")]

from benchmarks.bench_study import BENCH_STUDY, model_path, write_study_toml  # noqa: E402

_TABLES = (
    "sessions",
    "trials",
    "populations",
    "faces",
    "selections",
    "restarts",
    "ratings",
    "steps",
)
#: Foreign keys to remap in each table's copies: column → the table it points into.
_REFS = {
    "trials": {"session_id": "sessions"},
    "populations": {"trial_id": "trials"},
    "faces": {"population_id": "populations"},
    "selections": {"population_id": "populations", "trial_id": "trials"},
    "restarts": {"population_id": "populations", "trial_id": "trials"},
    "ratings": {"trial_id": "trials"},
    "steps": {"session_id": "sessions"},
}


def _template(database_url: str, config: Path) -> None:
    """One session through the study service, to the end."""
    import random

    from emogen.model import load_model
    from emogen.study.config import load_study_config
    from emogen.study.sessions import StudyService
    from emogen.study.storage import Store

    cfg = load_study_config(config)
    model = load_model(model_path(), rig=cfg.rig)
    store = Store(database_url)
    service = StudyService(
        cfg, store, model.rig, model_name=model.name, model_hash=model.model_hash, model=model
    )
    rng = random.Random(0)
    token, _ = service.create_session("export-template")
    state = service.step(token, {"command": "begin", "key": "template-key-begin"})
    for k in range(200):
        if state["stage"] == "done":
            break
        key = f"template-key-{k:04d}"
        trial = state["progress"]["trial"]
        if state["trial"]["status"] == "active":
            ids = [f["id"] for f in state["view"]["population"]["faces"]]
            chosen = rng.sample(ids, 3)
            state = service.step(
                token,
                {
                    "command": "select",
                    "key": key,
                    "trial": trial,
                    "attempt": state["trial"]["attempt"],
                    "generation": state["view"]["generation"],
                    "elite": chosen[0],
                    "others": chosen[1:],
                    "response_ms": 1500.0,
                    "load_ms": 5.0,
                },
            )
        else:
            state = service.step(
                token,
                {"command": "rate", "key": key, "trial": trial, "value": 5, "response_ms": 900.0},
            )
    store.dispose()


def fill(database_url: str, config: Path, sessions: int) -> None:
    """``sessions`` completed sessions in an empty database (see the module docstring)."""
    from sqlalchemy import MetaData, insert, select, text

    from emogen.study.storage import Store

    _template(database_url, config)
    store = Store(database_url)
    meta = MetaData()
    meta.reflect(store.engine, only=list(_TABLES))
    with store.engine.connect() as conn:
        rows = {
            t: [dict(r._mapping) for r in conn.execute(select(meta.tables[t]))] for t in _TABLES
        }
    span = {t: max((r["id"] for r in rows[t]), default=0) for t in _TABLES}
    batch = 50
    for start in range(1, sessions, batch):
        copies = range(start, min(start + batch, sessions))
        with store.engine.begin() as conn:
            for t in _TABLES:
                out = []
                for k in copies:
                    for r in rows[t]:
                        new = {**r, "id": r["id"] + k * span[t]}
                        for col, target in _REFS.get(t, {}).items():
                            new[col] = r[col] + k * span[target]
                        if t == "sessions":
                            new |= {
                                "token": f"{k:08d}{r['token'][8:]}",
                                "number": k + 1,
                                "participant_id": f"export-{k:06d}",
                            }
                        out.append(new)
                if out:
                    conn.execute(insert(meta.tables[t]), out)
    if not store.is_sqlite:  # explicit ids: move the sequences past them
        with store.engine.begin() as conn:
            for t in _TABLES:
                conn.execute(
                    text(
                        f"SELECT setval(pg_get_serial_sequence('{t}', 'id'), "
                        f"(SELECT max(id) FROM {t}))"
                    )
                )
    store.dispose()


_IN_MEMORY = """
import sys
from emogen.study.export import export_tables, write_export
from emogen.study.storage import Store
store = Store(sys.argv[1])
write_export(export_tables(store), sys.argv[2], sys.argv[3])
"""


def measure(args: list[str], env: dict[str, str]) -> dict[str, Any]:
    """Wall time and peak RSS (MB) of a command, by /usr/bin/time -v."""
    t0 = time.perf_counter()
    out = subprocess.run(["/usr/bin/time", "-v", *args], capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    if out.returncode != 0:
        raise RuntimeError(out.stderr[-2000:])
    kb = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", out.stderr).group(1))
    return {"wall_s": wall, "peak_mb": kb / 1024}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sessions", type=int, default=1000)
    parser.add_argument(
        "--database-url",
        default=None,
        help="an empty database (default: SQLite in a temporary folder)",
    )
    parser.add_argument("--in-memory", action="store_true", help="also the old path")
    args = parser.parse_args()
    env = {**os.environ, "PYTHONPATH": str(REPO / "src"), "EMOGEN_MODEL": str(model_path())}
    with tempfile.TemporaryDirectory(prefix="emogen-export-bench-") as tmp:
        folder = Path(tmp)
        url = args.database_url or f"sqlite:///{folder / 'study.sqlite'}"
        config = write_study_toml(BENCH_STUDY, folder / "bench.toml")
        t0 = time.perf_counter()
        fill(url, config, args.sessions)
        faces = args.sessions * 12 * 10
        print(
            f"study export: {args.sessions} completed sessions ({faces} face rows) in "
            f"{url.split(':')[0]}, filled in {time.perf_counter() - t0:.0f} s"
        )
        for fmt in ("parquet", "csv"):
            cmd = [
                sys.executable,
                "-m",
                "emogen",
                "study",
                "export",
                "--database-url",
                url,
                "--format",
                fmt,
                "--out",
                str(folder / f"out-{fmt}"),
            ]
            r = measure(cmd, env)
            print(
                f"  emogen study export --format {fmt:<8} {r['wall_s']:6.1f} s   "
                f"peak {r['peak_mb']:6.0f} MB"
            )
            if args.in_memory:
                r = measure(
                    [sys.executable, "-c", _IN_MEMORY, url, str(folder / f"mem-{fmt}"), fmt], env
                )
                print(
                    f"  in memory (export_tables)  {fmt:<8} {r['wall_s']:6.1f} s   "
                    f"peak {r['peak_mb']:6.0f} MB"
                )


if __name__ == "__main__":
    main()
