"""Server CPU of one study step (a selection of a corrected ten-face generation).

``python benchmarks/bench_step.py [--participants 8] [--no-http] [--against SRC] [--dynamic]`` runs
participants one at a time through the bench study (two trials, G = 5, corrected faces, three faces chosen per
generation) and prints the CPU time of every selection, p50/p95/mean:

* **over HTTP** — the real server (``emogen serve``, one worker, SQLite in a temporary folder);
  a selection's CPU is the server process's CPU (every thread: the request's, the event loop's
  and the database writer's) read from ``/proc/<pid>/task/*/schedstat`` (nanoseconds) before
  and after the request. One request at a time, so nothing else runs in the server meanwhile;
* **in process** — the study service itself (no HTTP), with the process's CPU per selection and
  where it goes: the write transaction on the database writer thread (``writer``), of which the
  selection's own work (``select``: the engine restored from its stored state, told, its next
  generation made, corrected and stored), of that the correction (``correct``) and of that
  ``collisions`` — the detect–solve loop, ray casting and eq. 5, compiled.

``--dynamic`` runs the study in process with static faces and with dynamic ones (docs/ga.md,
"Dynamic faces"), alternating twice, and prints the ratio of the dynamic step's p50 to the
static one's (issue #44: at most 2), with the load average before and after.

``--against SRC`` (another checkout's ``src`` folder, e.g. a ``git worktree`` of main; one with
the single step route of #38, as both servers are driven through it) runs a second server with
that code beside this one, in the same virtual environment, and alternates participants
between the two: the only fair comparison of two versions on a machine whose
speed drifts from one run to the next (on the 2-core VM of the figures in docs/study.md, ±15%
and more; two runs of the same code minutes apart can differ by 2 ms).

Machine: BLAS on one thread (as the server runs). Linux only (``/proc``).
"""

from __future__ import annotations

import argparse
import os
import random
import sys
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import Any

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import httpx
import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO), str(REPO / "src")]

from benchmarks.bench_study import (  # noqa: E402
    BENCH_STUDY,
    DYNAMIC_STUDY,
    ServerProcess,
    model_path,
    selection_body,
    write_study_toml,
)


def _server_cpu_ns(pids: list[int]) -> int:
    """CPU nanoseconds of every thread of these processes (``schedstat``: exact, not ticks)."""
    total = 0
    for pid in pids:
        for task in Path(f"/proc/{pid}/task").iterdir():
            try:
                total += int((task / "schedstat").read_text().split()[0])
            except (OSError, ValueError, IndexError):
                continue
    return total


def _selection(state: Any, rng: random.Random) -> dict[str, Any]:
    """Three of the shown faces, at random (the first the elite)."""
    faces = state["view"]["population"]["faces"]
    return selection_body(state, rng.sample([f["id"] for f in faces], 3))


def over_http(participants: int, against: Path | None = None) -> dict[str, np.ndarray]:
    """Server CPU (ms) of each selection over HTTP, one request at a time: ``{"this": …}``.

    ``against``: the ``src`` folder of another checkout; a second server runs that code side
    by side (its own database) and the participants alternate between the two, so that both
    are measured in the same minutes of this machine, whose speed drifts by ±15% and more from
    one run to the next: ``{"this": …, "against": …}``.
    """
    roots = {"this": REPO / "src"} | ({} if against is None else {"against": against})
    with tempfile.TemporaryDirectory(prefix="emogen-step-") as tmp:
        folder = Path(tmp)
        config = write_study_toml(BENCH_STUDY, folder / "bench.toml")
        servers = {name: _server(config, folder, name, root) for name, root in roots.items()}
        rng, out, n = random.Random(0), {name: [] for name in roots}, 0
        try:
            for server in servers.values():
                server.start()
            for p in range(participants + 1):  # the first one warms the servers up
                order = list(servers) if p % 2 else list(reversed(servers))
                for name in order:
                    n = _participant(servers[name], f"{name}-{p}", n, rng, out[name] if p else [])
        finally:
            for server in servers.values():
                server.stop()
    return {name: np.array(ms) for name, ms in out.items()}


def _server(config: Path, folder: Path, name: str, src: Path) -> ServerProcess:
    """``emogen serve`` of the code in ``src``, SQLite in ``folder``; no session limit (many
    sessions from one address are not a flood here)."""
    url = f"sqlite:///{folder / name}.sqlite"
    log = folder / f"{name}.log"
    env = {"PYTHONPATH": str(src)}
    return ServerProcess(config, url, model_path(), log, extra=("--session-limit", "off"), env=env)


def _participant(
    server: ServerProcess, participant: str, n: int, rng: random.Random, out: list[float]
) -> int:
    """One participant through the study; each selection's server CPU appended to ``out``.
    Returns the step count so far (``n``: before)."""
    pids = server.pids()
    with httpx.Client(base_url=server.url, timeout=30.0) as client:

        def post(path: str, body: dict[str, Any]) -> dict[str, Any]:
            r = client.post(path, json=body)
            r.raise_for_status()
            return r.json()  # type: ignore[no-any-return]

        token = post("/api/sessions", {"participant_id": participant})["token"]
        step = f"/api/s/{token}/step"
        state = post(step, {"command": "begin", "key": f"begin-{n:06d}"})
        while state["stage"] != "done":
            n += 1
            key = f"step-{n:06d}"
            if state["trial"]["status"] != "active":
                body = {
                    "command": "rate",
                    "key": key,
                    "trial": state["progress"]["trial"],
                    "value": 4,
                }
                state = post(step, body)
                continue
            body = {"key": key, **_selection(state, rng)}
            t0 = _server_cpu_ns(pids)
            state = post(step, body)
            out.append((_server_cpu_ns(pids) - t0) / 1e6)
    return n


def _timed(acc: dict[str, float], phase: dict[str, bool], label: str) -> Callable[[Any], Any]:
    """Adds the calling thread's CPU in ``fn`` to ``acc[label]`` when the call began during a
    counted selection (``phase["on"]``, read at entry: the writer thread's job for a selection
    starts while the selection waits for it, and may end after the selection has returned)."""

    def wrap(fn: Any) -> Any:
        def timed(*args: Any, **kwargs: Any) -> Any:
            counted = phase["on"]
            t0 = time.thread_time()
            try:
                return fn(*args, **kwargs)
            finally:
                if counted:
                    acc[label] += time.thread_time() - t0

        return timed

    return wrap


def in_process(
    participants: int, study: dict[str, Any] = BENCH_STUDY
) -> tuple[np.ndarray, dict[str, float]]:
    """Process CPU (ms) of each selection of the study service, and the mean ms per part."""
    import emogen.correct.apply as apply
    from emogen.model import load_model
    from emogen.study import storage
    from emogen.study.config import load_study_config
    from emogen.study.sessions import StudyService
    from emogen.study.storage import Store
    from emogen.tasks.evolve.task import EvolveTask

    acc: dict[str, float] = defaultdict(float)
    phase = {"on": False}
    patches = [
        (EvolveTask, "_select", "select"),
        (apply.Corrector, "correct", "correct"),
        (apply, "solve_collisions", "collisions"),
        (storage._GroupCommit, "_execute", "writer"),
    ]
    saved = [(owner, name, getattr(owner, name)) for owner, name, _ in patches]
    for owner, name, label in patches:
        setattr(owner, name, _timed(acc, phase, label)(getattr(owner, name)))
    times: list[float] = []
    try:
        with tempfile.TemporaryDirectory(prefix="emogen-step-") as tmp:
            folder = Path(tmp)
            config = load_study_config(write_study_toml(study, folder / "bench.toml"))
            model = load_model(model_path(), rig=config.rig)
            store = Store(f"sqlite:///{folder / 'bench.sqlite'}")
            service = StudyService(
                config,
                store,
                model.rig,
                model_name=model.name,
                model_hash=model.model_hash,
                model=model,
            )
            rng, n = random.Random(0), 0
            for p in range(participants + 1):
                token, _ = service.create_session(f"step-{p}")
                state = service.step(token, {"command": "begin", "key": f"begin-{p:06d}"})
                while state["stage"] != "done":
                    n += 1
                    key = f"step-{n:06d}"
                    if state["trial"]["status"] != "active":
                        rate = {
                            "command": "rate",
                            "key": key,
                            "trial": state["progress"]["trial"],
                            "value": 4,
                        }
                        state = service.step(token, rate)
                        continue
                    select = {**_selection(state, rng), "key": key, "load_ms": 5.0}
                    phase["on"] = p > 0  # the first participant warms up, not counted
                    t0 = time.process_time()
                    state = service.step(token, select)
                    phase["on"] = False
                    if p:
                        times.append((time.process_time() - t0) * 1000)
            store.dispose()
    finally:
        for owner, name, fn in saved:
            setattr(owner, name, fn)
    return np.array(times), {k: 1000 * v / max(len(times), 1) for k, v in acc.items()}


def _line(label: str, ms: np.ndarray) -> str:
    return (
        f"{label:<12} {len(ms):>4} selections  p50 {np.median(ms):5.1f} ms  "
        f"p95 {np.percentile(ms, 95):5.1f} ms  mean {ms.mean():5.1f} ms"
    )


def _figures(ms: np.ndarray) -> dict[str, float]:
    return {
        "p50_ms": round(float(np.median(ms)), 2),
        "p95_ms": round(float(np.percentile(ms, 95)), 2),
        "mean_ms": round(float(ms.mean()), 2),
        "selections": len(ms),
    }


def run(participants: int = 8, http: bool = True, against: Path | None = None) -> dict[str, Any]:
    """Print and return the figures (``http=False``: in process only; ``against``: see
    :func:`over_http`)."""
    print(f"study step CPU: {os.cpu_count()} cores, bench study {BENCH_STUDY['ga']}, corrected")
    result: dict[str, Any] = {}
    if http:
        runs = over_http(participants, against)
        print(_line("over HTTP", runs["this"]))
        result["http"] = _figures(runs["this"])
        if "against" in runs:
            print(_line("  against", runs["against"]) + f"  ({against})")
            result["http_against"] = _figures(runs["against"])
    ms, parts = in_process(participants)
    print(_line("in process", ms))
    print(
        "  per selection: "
        + ", ".join(f"{k} {v:.2f} ms" for k, v in sorted(parts.items(), key=lambda kv: -kv[1]))
    )
    result["in_process"] = {**_figures(ms), "parts_ms": {k: round(v, 3) for k, v in parts.items()}}
    return result


def _load() -> str:
    return "load average " + " ".join(f"{x:.2f}" for x in os.getloadavg())


def dynamic_ratio(participants: int, rounds: int = 2) -> dict[str, Any]:
    """In process, static and dynamic studies alternating (static, dynamic, ``rounds`` times, on
    the same machine in the same minutes): each one's selections and parts, then the ratio of
    the dynamic step's p50 to the static one's, per round and over all selections (#44's goal:
    at most 2). The load average is printed before and after (the machine is shared)."""
    print(f"static vs dynamic step CPU, in process: {os.cpu_count()} cores, {_load()}")
    runs: dict[str, list[np.ndarray]] = {"static": [], "dynamic": []}
    ratios = []
    for _ in range(rounds):
        for label, study in (("static", BENCH_STUDY), ("dynamic", DYNAMIC_STUDY)):
            ms, parts = in_process(participants, study)
            runs[label].append(ms)
            print(_line(label, ms) + "  " + ", ".join(f"{k} {v:.1f} ms" for k, v in parts.items()))
        ratios.append(float(np.median(runs["dynamic"][-1]) / np.median(runs["static"][-1])))
    static, dynamic = (np.concatenate(runs[k]) for k in ("static", "dynamic"))
    overall = float(np.median(dynamic) / np.median(static))
    print(
        f"dynamic/static p50 ratio {overall:.2f} (per round: "
        + ", ".join(f"{r:.2f}" for r in ratios)
        + f"; goal ≤ 2), {_load()}"
    )
    return {
        "static": _figures(static),
        "dynamic": _figures(dynamic),
        "ratio_p50": round(overall, 2),
        "ratio_p50_rounds": [round(r, 2) for r in ratios],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--participants", type=int, default=8)
    parser.add_argument("--no-http", action="store_true", help="in process only")
    parser.add_argument(
        "--dynamic",
        action="store_true",
        help="in process: static and dynamic faces, alternating (static, dynamic, twice), "
        "and the ratio of their p50s",
    )
    parser.add_argument(
        "--against",
        type=Path,
        metavar="SRC",
        help="another checkout's src folder: its server runs side by side, participants "
        "alternate between the two (a fair comparison on a machine whose speed drifts)",
    )
    args = parser.parse_args()
    if args.participants < 1:
        parser.error(f"--participants must be at least 1; got {args.participants}")
    if args.against is not None and not (args.against / "emogen" / "__init__.py").is_file():
        parser.error(
            f"--against must be a checkout's src folder (with emogen/); got {args.against}"
        )
    if args.against is not None and args.no_http:
        parser.error("--against compares servers over HTTP; leave out --no-http")
    if args.dynamic:
        dynamic_ratio(args.participants)
        return
    run(args.participants, http=not args.no_http, against=args.against)


if __name__ == "__main__":
    main()
