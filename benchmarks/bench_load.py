"""Study server under load: N simulated participants over HTTP, as the page drives the API.

``python benchmarks/bench_load.py`` starts the real server (``python -m emogen serve``) for every
combination of ``--database`` (sqlite, postgresql: a throwaway cluster, fsync on) and
``--workers`` (1, 2), and for each ``--participants`` N (50 100 200 400) a fresh database; the
N participants arrive over ``--ramp`` seconds and each goes through the whole study as the
page does: landing page, consent (create session), session page, state, begin, then a
selection per generation and a rating per trial, pausing ``--pause`` seconds (uniform, e.g.
``1-3`` or ``8-20``) before each step, with the page's step keys, ``response_ms`` and
``load_ms``. It prints one line per run: p50/p95/max of the *step* (the selection that asks
for the next generation, as the participant waits for it: request sent → answer received),
errors, steps/s, server CPU per request and the driver's own CPU (one asyncio process; over
~70% of a core it may itself be the bottleneck and says so). ``--breaking-point`` then raises N
(×1.5) until the step p95 passes 1 s and reports that N. ``--export-during`` fills the
database with that many completed sessions first and downloads the dashboard's faces.csv
over and over during the run, reporting the step p95 while an export runs and while none does.

All traffic goes to 127.0.0.1; every loop is bounded in count and time.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import random
import resource
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx
import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO), str(REPO / "src")]

from benchmarks.bench_study import (  # noqa: E402
    BENCH_STUDY,
    BENCH_TOKEN,
    DYNAMIC_STUDY,
    MIXED_STUDY,
    ServerProcess,
    model_path,
    write_study_toml,
)

STUDIES = {"evolve": BENCH_STUDY, "mixed": MIXED_STUDY, "dynamic": DYNAMIC_STUDY}


@dataclass
class Run:
    steps: list[tuple[float, float]] = field(default_factory=list)  # (sent at, seconds)
    #: ratings and categorisations (a rating that ends an evolve block also draws the next
    #: categorise block's faces): (sent at, seconds)
    answers: list[tuple[float, float]] = field(default_factory=list)
    requests: int = 0
    errors: list[str] = field(default_factory=list)
    completed: int = 0
    unfinished: int = 0
    exports: list[tuple[float, float]] = field(default_factory=list)  # (start, end)


async def participant(
    client: httpx.AsyncClient,
    i: int,
    run: Run,
    cfg: argparse.Namespace,
    deadline: float,
    nonce: str,
) -> None:
    rng = random.Random(i)
    lo, hi = cfg.pause
    keys = (f"{nonce}-{i:05d}-{k:04d}" for k in range(10_000))
    await asyncio.sleep(cfg.ramp * rng.random())

    async def call(method: str, path: str, body: dict[str, Any] | None = None) -> Any:
        run.requests += 1
        what = path.split("/")[-1] + (f" {body['command']}" if body and "command" in body else "")
        try:
            r = await client.request(method, path, json=body)
        except httpx.HTTPError as exc:
            run.errors.append(f"{what}: {type(exc).__name__}")
            return None
        if r.status_code >= 400:
            run.errors.append(f"{what}: {r.status_code} {r.text[:100]}")
            return None
        return r.json() if "json" in r.headers.get("content-type", "") else r.text

    pid = f"load-{nonce}-{i:05d}"
    if await call("GET", f"/?PROLIFIC_PID={pid}") is None:
        return
    created = await call("POST", "/api/sessions", {"participant_id": pid, "resume_token": None})
    if created is None:
        return
    token = created["token"]
    await call("GET", f"/s/{token}")
    state = await call("GET", f"/api/s/{token}/state")
    shown = time.monotonic()
    await asyncio.sleep(rng.uniform(lo, hi))  # reads the instructions
    step = f"/api/s/{token}/step"
    state = await call("POST", step, {"command": "begin", "key": next(keys)})
    for _ in range(500):  # bounded, whatever the study
        if state is None or state["stage"] == "done":
            break
        if time.monotonic() > deadline:
            run.unfinished += 1
            return
        shown = time.monotonic()
        pause = rng.uniform(lo, hi)
        await asyncio.sleep(pause)
        trial, view = state["progress"]["trial"], state["view"]
        if view["task"] == "categorise":
            body = {
                "command": "answer",
                "key": next(keys),
                "trial": trial,
                "label": rng.choice(view["labels"]),
                "intensity": rng.randint(1, view["intensity"]["points"])
                if view["intensity"]
                else None,
                "confidence": rng.randint(1, view["confidence"]["points"])
                if view["confidence"]
                else None,
                "response_ms": round(1000 * pause),
                "load_ms": 5.0,
            }
            t0 = time.monotonic()
            state = await call("POST", step, body)
            if state is not None:
                run.answers.append((t0, time.monotonic() - t0))
        elif state["trial"]["status"] == "active":
            ids = [f["id"] for f in view["population"]["faces"]]
            limits = view["limits"]
            chosen = rng.sample(
                ids, rng.randint(limits["min_selections"], min(3, limits["max_selections"]))
            )
            body = {
                "command": "select",
                "key": next(keys),
                "trial": trial,
                "attempt": state["trial"]["attempt"],
                "generation": view["generation"],
                "elite": chosen[0],
                "others": chosen[1:],
                "response_ms": round(1000 * (time.monotonic() - shown)),
                "load_ms": 5.0,
            }
            t0 = time.monotonic()
            state = await call("POST", step, body)
            if state is not None:
                run.steps.append((t0, time.monotonic() - t0))
        else:
            body = {
                "command": "rate",
                "key": next(keys),
                "trial": trial,
                "value": rng.randint(1, 7),
                "response_ms": round(1000 * pause),
            }
            t0 = time.monotonic()
            state = await call("POST", step, body)
            if state is not None:
                run.answers.append((t0, time.monotonic() - t0))
    if state is not None and state["stage"] == "done":
        run.completed += 1


async def exporter(client: httpx.AsyncClient, run: Run, stop: asyncio.Event, wait: float) -> None:
    """Downloads faces.csv, then waits as long as it took, and again (steps both with and
    without an export running), from ``wait`` seconds in (once everyone has arrived)."""
    with contextlib.suppress(TimeoutError):
        await asyncio.wait_for(stop.wait(), wait)
    while not stop.is_set():
        t0 = time.monotonic()
        try:
            r = await client.get(
                "/api/researcher/export/faces.csv",
                timeout=600,
                headers={"Authorization": f"Bearer {BENCH_TOKEN}"},
            )
            if r.status_code != 200:
                run.errors.append(f"faces.csv: {r.status_code}")
        except httpx.HTTPError as exc:
            run.errors.append(f"faces.csv: {type(exc).__name__}")
        run.exports.append((t0, time.monotonic()))
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(stop.wait(), time.monotonic() - t0)


async def drive(url: str, n: int, cfg: argparse.Namespace) -> Run:
    run = Run()
    nonce = f"{time.time_ns():x}"[-8:]
    limits = httpx.Limits(max_connections=n + 2, max_keepalive_connections=n + 2)
    deadline = time.monotonic() + cfg.max_seconds
    async with httpx.AsyncClient(base_url=url, timeout=60.0, limits=limits) as client:
        stop = asyncio.Event()
        export = (
            asyncio.create_task(exporter(client, run, stop, cfg.ramp + 5))
            if cfg.export_during
            else None
        )
        await asyncio.wait_for(
            asyncio.gather(*(participant(client, i, run, cfg, deadline, nonce) for i in range(n))),
            timeout=cfg.max_seconds + 120,
        )
        stop.set()
        if export is not None:
            await export
    return run


def _cpu_s(pid: int) -> float:
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _pct(values: list[float], q: float) -> float:
    return float(np.percentile(values, q)) * 1000 if values else float("nan")


def one_run(
    database_url: str, workers: int, n: int, cfg: argparse.Namespace, folder: Path
) -> dict[str, Any]:
    config = write_study_toml(STUDIES[cfg.study], folder / "bench.toml")
    if cfg.export_during:
        from benchmarks.bench_export import fill

        fill(database_url, config, cfg.export_during)
    server = ServerProcess(
        config,
        database_url,
        model_path(),
        folder / f"server-{n}.log",
        workers,
        extra=("--session-limit", "off"),
    ).start()
    try:
        pids = server.pids()
        cpu0 = sum(_cpu_s(p) for p in pids)
        me0 = resource.getrusage(resource.RUSAGE_SELF)
        t0 = time.monotonic()
        run = asyncio.run(drive(server.url, n, cfg))
        wall = time.monotonic() - t0
        me1 = resource.getrusage(resource.RUSAGE_SELF)
        cpu = sum(_cpu_s(p) for p in pids) - cpu0
    finally:
        server.stop()
    steps = [s for _, s in run.steps]
    first = min((t for t, _ in run.steps), default=t0)
    last = max((t + s for t, s in run.steps), default=t0 + 1)
    result = {
        "database": database_url.split(":")[0].split("+")[0],
        "workers": workers,
        "participants": n,
        "pause": f"{cfg.pause[0]:g}-{cfg.pause[1]:g}",
        "steps": len(steps),
        "step_p50_ms": _pct(steps, 50),
        "step_p95_ms": _pct(steps, 95),
        "step_max_ms": _pct(steps, 100),
        "errors": len(run.errors),
        "answer_p95_ms": _pct([s for _, s in run.answers], 95),
        "answers": len(run.answers),
        "steps_per_s": len(steps) / max(last - first, 1e-9),
        "completed": run.completed,
        "unfinished": run.unfinished,
        "server_cpu_ms_per_request": 1000 * cpu / max(run.requests, 1),
        "driver_cpu_pct": 100
        * ((me1.ru_utime + me1.ru_stime) - (me0.ru_utime + me0.ru_stime))
        / wall,
        "error_examples": sorted(set(run.errors))[:5],
    }
    if cfg.export_during:
        during = [s for t, s in run.steps if any(a <= t <= b for a, b in run.exports)]
        apart = [s for t, s in run.steps if not any(a <= t <= b for a, b in run.exports)]
        result |= {
            "exports": len(run.exports),
            "step_p95_during_export_ms": _pct(during, 95),
            "step_p95_without_export_ms": _pct(apart, 95),
            "export_s": float(np.mean([b - a for a, b in run.exports]))
            if run.exports
            else float("nan"),
        }
    return result


HEADER = (
    f"{'database':<10} {'workers':>7} {'N':>5} {'pause':>6} {'steps':>6} {'p50 ms':>8} "
    f"{'p95 ms':>8} {'max ms':>8} {'errors':>6} {'steps/s':>8} {'cpu/req':>8} "
    f"{'driver%':>7}"
)


def line(r: dict[str, Any]) -> str:
    text = (
        f"{r['database']:<10} {r['workers']:>7} {r['participants']:>5} {r['pause']:>6} "
        f"{r['steps']:>6} {r['step_p50_ms']:>8.0f} {r['step_p95_ms']:>8.0f} "
        f"{r['step_max_ms']:>8.0f} {r['errors']:>6} {r['steps_per_s']:>8.1f} "
        f"{r['server_cpu_ms_per_request']:>8.1f} {r['driver_cpu_pct']:>7.0f}"
    )
    if r["answers"]:
        text += f"  ratings+categorisations p95 {r['answer_p95_ms']:.0f} ms ({r['answers']})"
    if r["driver_cpu_pct"] > 70:
        text += "  (driver busy: figures may be the driver's)"
    if r["unfinished"]:
        text += f"  ({r['unfinished']} unfinished at --max-seconds)"
    if "exports" in r:
        text += (
            f"\n{'':>10} export of faces.csv ({r['exports']}×, {r['export_s']:.1f} s each): "
            f"step p95 {r['step_p95_during_export_ms']:.0f} ms while exporting, "
            f"{r['step_p95_without_export_ms']:.0f} ms otherwise"
        )
    for e in r["error_examples"]:
        text += f"\n{'':>10} error: {e}"
    return text


@contextmanager
def databases(kind: str, folder: Path, stack: ExitStack) -> Iterator[Any]:
    """A factory of fresh, empty database URLs of this kind."""
    if kind == "sqlite":
        counter = iter(range(10_000))
        yield lambda: f"sqlite:///{folder / f'load-{next(counter)}.sqlite'}"
        return
    from benchmarks.pgcluster import cluster

    pg = stack.enter_context(cluster())
    yield pg.new_database


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--database", nargs="+", default=["sqlite", "postgresql"], choices=["sqlite", "postgresql"]
    )
    parser.add_argument("--workers", nargs="+", type=int, default=[1, 2])
    parser.add_argument("--participants", nargs="+", type=int, default=[50, 100, 200, 400])
    parser.add_argument("--pause", default="1-3", help="seconds before each step: LO-HI")
    parser.add_argument(
        "--study",
        choices=sorted(STUDIES),
        default="evolve",
        help="evolve: two GA trials; mixed: GA trials, then a categorise block "
        "(own + others' + random faces); dynamic: the GA trials with faces that move",
    )
    parser.add_argument("--ramp", type=float, default=10.0, help="arrivals spread over (s)")
    parser.add_argument("--max-seconds", type=float, default=900.0, help="cap per run")
    parser.add_argument(
        "--breaking-point", action="store_true", help="then raise N until the step p95 passes 1 s"
    )
    parser.add_argument(
        "--export-during",
        type=int,
        default=0,
        metavar="SESSIONS",
        help="prefill SESSIONS completed sessions; download faces.csv during",
    )
    parser.add_argument("--json", type=Path, help="also write the figures as JSON")
    cfg = parser.parse_args()
    lo, _, hi = cfg.pause.partition("-")
    cfg.pause = (float(lo), float(hi or lo))
    os.environ.setdefault("EMOGEN_MODEL", str(model_path()))
    print(
        f"study server load: {os.cpu_count()} cores, study {BENCH_STUDY['emotions']} × "
        f"G={BENCH_STUDY['ga']['generations']} (12 selections + 2 ratings per participant"
        f"{', then 8 faces to categorise' if cfg.study == 'mixed' else ''}"
        f"{', faces that move' if cfg.study == 'dynamic' else ''}), "
        f"pause {cfg.pause[0]:g}–{cfg.pause[1]:g} s, arrivals over {cfg.ramp:g} s"
    )
    print(HEADER, flush=True)
    results: list[dict[str, Any]] = []
    breaking: dict[str, int | None] = {}
    with ExitStack() as stack, tempfile.TemporaryDirectory(prefix="emogen-load-") as tmp:
        folder = Path(tmp)
        for kind in cfg.database:
            with databases(kind, folder, stack) as fresh:
                for workers in cfg.workers:
                    counts = list(cfg.participants)
                    k = 0
                    while k < len(counts) and k < 12:
                        r = one_run(fresh(), workers, counts[k], cfg, folder)
                        results.append(r)
                        print(line(r), flush=True)
                        k += 1
                        if r["step_p95_ms"] > 1000 or r["errors"]:
                            breaking.setdefault(f"{kind}/{workers}", counts[k - 1])
                        if (
                            cfg.breaking_point
                            and k == len(counts)
                            and f"{kind}/{workers}" not in breaking
                        ):
                            counts.append(int(counts[-1] * 1.5))
    if cfg.breaking_point:
        for key, n in breaking.items():
            print(f"breaking point {key} worker(s): step p95 > 1 s (or errors) at N = {n}")
    if cfg.json:
        cfg.json.write_text(json.dumps({"runs": results, "breaking_point": breaking}, indent=2))


if __name__ == "__main__":
    main()
