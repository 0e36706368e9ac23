"""Study server load: 50 simulated participants at once over HTTP on loopback.

``python benchmarks/bench_study.py [--participants 50] [--seconds 60]`` starts the study
server (uvicorn, SQLite in a temporary folder, or ``--database-url``) in a subprocess, runs
every participant through a two-trial study (G = 5: 12 selections and 2 ratings each),
arriving over the first 5 s and pausing 1–3 s between steps (faster than people, who look at
ten faces each time), and prints the p50/p95/max *server-side* step latency (the
server's own ``Server-Timing`` header: request in → response out, database commit included),
the client-side latency and the error count. Every loop is bounded in count and time; all
traffic goes to 127.0.0.1.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import random
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import httpx
import numpy as np

REPO = Path(__file__).resolve().parents[1]
#: The researcher token of the servers the benchmarks and tests start (32+ characters, as required).
BENCH_TOKEN = "bench-researcher-token-0123456789-abcdefgh"

BENCH_STUDY: dict[str, Any] = {
    "name": "bench",
    "emotions": ["happy", "sad"],
    "seed": 7,
    "ga": {"generations": 5, "min_selections": 1, "max_selections": 4},
}
#: The same GA trials, then a categorise block: the participant's own two faces, four of other
#: participants' (random stand-ins until others are complete) and two random faces.
MIXED_STUDY: dict[str, Any] = {
    **BENCH_STUDY,
    "name": "bench-mixed",
    "blocks": [
        {"task": "evolve"},
        {"task": "categorise", "own": True, "others": 4, "random": 2, "intensity": True},
    ],
}
#: The bench study with faces that move (docs/ga.md, "Dynamic faces"; its default clip): the same
#: GA trials, each face corrected at its keyframes as well as at its peak.
DYNAMIC_STUDY: dict[str, Any] = {**BENCH_STUDY, "blocks": [{"task": "evolve", "dynamic": {}}]}


def model_path() -> Path:
    return Path(
        os.environ.get("EMOGEN_MODEL") or REPO.parent / "shared" / "ict-facekit" / "FaceXModel"
    )


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def write_study_toml(data: dict[str, Any], path: Path) -> Path:
    """A study config dict (nested tables allowed, e.g. [ga], [ga.init]; a list of dicts is an
    array of tables, e.g. [[blocks]]) as TOML."""
    lines: list[str] = []
    tables: list[tuple[str, dict[str, Any]]] = []
    arrays: list[tuple[str, dict[str, Any]]] = []
    for k, v in data.items():
        if isinstance(v, dict):
            tables.append((k, v))
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            arrays.extend((k, x) for x in v)
        else:
            lines.append(f"{k} = {json.dumps(v)}")  # strings, numbers, lists: valid TOML
    while tables:
        name, table = tables.pop(0)
        lines.append(f"[{name}]")
        for k, v in table.items():
            if isinstance(v, dict):
                tables.append((f"{name}.{k}", v))
            else:
                lines.append(f"{k} = {json.dumps(v)}")
    for name, table in arrays:
        lines.append(f"[[{name}]]")
        lines.extend(f"{k} = {json.dumps(v)}" for k, v in table.items())
    path.write_text("\n".join(lines) + "\n")
    return path


class ServerProcess:
    """``emogen serve`` (``python -m emogen serve``) on 127.0.0.1 with ``workers`` worker
    processes; ``kill()`` sends SIGKILL to the server and its workers (its process group)."""

    def __init__(
        self,
        config: Path,
        database_url: str,
        model: Path,
        log: Path,
        workers: int = 1,
        extra: tuple[str, ...] = (),
        env: dict[str, str] | None = None,
    ) -> None:
        self.config, self.database_url, self.model, self.log = config, database_url, model, log
        self.workers, self.extra, self.env = workers, extra, env or {}
        self.port = free_port()
        self.proc: subprocess.Popen[bytes] | None = None

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    def start(self, timeout: float = 300.0) -> ServerProcess:
        env = {**os.environ, "EMOGEN_RESEARCHER_TOKEN": BENCH_TOKEN, **self.env}
        with open(self.log, "ab") as log:
            self.proc = subprocess.Popen(
                [
                    sys.executable,
                    "-m",
                    "emogen",
                    "serve",
                    str(self.config),
                    "--port",
                    str(self.port),
                    "--database-url",
                    self.database_url,
                    "--model",
                    str(self.model),
                    "--workers",
                    str(self.workers),
                    *self.extra,
                ],
                stdout=log,
                stderr=subprocess.STDOUT,
                env=env,
                start_new_session=True,  # its own process group: kill() reaches the workers
            )
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise RuntimeError(
                    f"server exited with {self.proc.returncode}: {self.log.read_text()}"
                )
            try:
                if (
                    httpx.get(f"{self.url}/healthz", timeout=1.0).status_code == 200
                    and self.ready_workers() >= self.workers
                ):
                    return self
            except httpx.HTTPError:
                pass
            time.sleep(0.1)
        self.stop()
        raise RuntimeError(f"server did not start in {timeout} s: {self.log.read_text()}")

    def pids(self) -> list[int]:
        """The server's process and its worker processes."""
        if self.proc is None:
            return []
        out = [self.proc.pid]
        for stat in Path("/proc").glob("[0-9]*/stat"):
            try:
                fields = stat.read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == self.proc.pid:  # its parent is the server
                out.append(int(stat.parent.name))
        return out

    def ready_workers(self) -> int:
        """Worker processes waiting for requests in their event loop (1 without workers)."""
        if self.workers == 1:
            return 1
        ready = 0
        for pid in self.pids()[1:]:
            try:
                ready += "epoll" in Path(f"/proc/{pid}/wchan").read_text()
            except OSError:
                continue
        return ready

    def kill(self) -> None:
        """SIGKILL to the server and every worker at once (as a crash or the OOM killer would)."""
        if self.proc is not None and self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait(10)

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.kill()


# ---- one simulated participant -------------------------------------------------------------
def selection_body(state: dict[str, Any], chosen: list[int]) -> dict[str, Any]:
    """The page's selection command for the shown generation (no key): ``chosen[0]`` the
    elite."""
    return {
        "command": "select",
        "trial": state["progress"]["trial"],
        "attempt": state["trial"]["attempt"],
        "generation": state["view"]["generation"],
        "elite": chosen[0],
        "others": chosen[1:],
        "response_ms": 1000.0,
    }


class Stats:
    def __init__(self) -> None:
        self.server_ms: list[float] = []
        self.client_ms: list[float] = []
        self.errors: list[str] = []
        self.completed = 0


def _server_ms(response: httpx.Response) -> float | None:
    timing = response.headers.get("server-timing", "")
    if "dur=" in timing:
        return float(timing.split("dur=")[1].split(";")[0])
    return None


async def participant(
    client: httpx.AsyncClient,
    index: int,
    stats: Stats,
    deadline: float,
    think_s: float,
    ramp_s: float,
    nonce: str,
) -> None:
    rng = random.Random(index)
    n = 0
    await asyncio.sleep(ramp_s * rng.random())  # participants arrive over the first seconds

    async def post(path: str, body: dict[str, Any]) -> dict[str, Any] | None:
        nonlocal n
        n += 1
        body = {**body, "key": f"bench-{index:04d}-{n:05d}"} if path != "/api/sessions" else body
        t0 = time.perf_counter()
        try:
            r = await client.post(path, json=body)
        except httpx.HTTPError as exc:
            stats.errors.append(f"{path}: {type(exc).__name__}")
            return None
        stats.client_ms.append((time.perf_counter() - t0) * 1000)
        ms = _server_ms(r)
        if ms is not None:
            stats.server_ms.append(ms)
        if r.status_code >= 400:
            stats.errors.append(f"{path}: {r.status_code} {r.text[:120]}")
            return None
        return r.json()  # type: ignore[no-any-return]

    created = await post("/api/sessions", {"participant_id": f"bench-{nonce}-{index:04d}"})
    if created is None:
        return
    token = created["token"]
    step = f"/api/s/{token}/step"
    state = await post(step, {"command": "begin"})
    steps = 0
    while state is not None and state["stage"] != "done" and time.monotonic() < deadline:
        steps += 1
        if steps > 200:  # bounded, whatever happens
            stats.errors.append(f"participant {index}: too many steps")
            return
        await asyncio.sleep(think_s * (0.5 + rng.random()))
        if state["trial"]["status"] == "active":
            ids = [f["id"] for f in state["view"]["population"]["faces"]]
            chosen = rng.sample(ids, rng.randint(1, 4))
            state = await post(step, selection_body(state, chosen))
        else:
            state = await post(
                step,
                {
                    "command": "rate",
                    "trial": state["progress"]["trial"],
                    "value": rng.randint(1, 7),
                },
            )
    if state is not None and state["stage"] == "done":
        stats.completed += 1
    elif state is not None:
        stats.errors.append(f"participant {index}: not finished before the time limit")


async def _load(
    url: str, participants: int, seconds: float, think_s: float, ramp_s: float
) -> Stats:
    stats = Stats()
    nonce = f"{time.time_ns():x}"[-8:]  # fresh participant ids on a reused database
    deadline = time.monotonic() + seconds
    limits = httpx.Limits(max_connections=participants, max_keepalive_connections=participants)
    async with httpx.AsyncClient(base_url=url, timeout=30.0, limits=limits) as client:
        await asyncio.wait_for(
            asyncio.gather(
                *(
                    participant(client, i, stats, deadline, think_s, ramp_s, nonce)
                    for i in range(participants)
                )
            ),
            timeout=seconds + 60,
        )
    return stats


def _cpu_s(pid: int) -> float:
    """User + system CPU seconds of a process (Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def run(
    participants: int = 50,
    seconds: float = 120.0,
    think_s: float = 2.0,
    database_url: str | None = None,
    ramp_s: float = 5.0,
) -> dict[str, Any]:
    """Start a server, run the participants, stop it; returns (and prints) the figures."""
    with tempfile.TemporaryDirectory(prefix="emogen-bench-") as tmp:
        folder = Path(tmp)
        config = write_study_toml(BENCH_STUDY, folder / "bench.toml")
        url = database_url or f"sqlite:///{folder / 'bench.sqlite'}"
        server = ServerProcess(config, url, model_path(), folder / "server.log").start()
        try:
            pid = server.proc.pid if server.proc is not None else 0
            cpu0 = _cpu_s(pid)
            t0 = time.perf_counter()
            stats = asyncio.run(_load(server.url, participants, seconds, think_s, ramp_s))
            wall = time.perf_counter() - t0
            cpu = _cpu_s(pid) - cpu0
        finally:
            server.stop()
    server_ms = np.array(stats.server_ms or [np.nan])
    client_ms = np.array(stats.client_ms or [np.nan])
    result = {
        "participants": participants,
        "completed": stats.completed,
        "requests": len(stats.client_ms),
        "wall_s": round(wall, 1),
        "server_p50_ms": round(float(np.percentile(server_ms, 50)), 1),
        "server_p95_ms": round(float(np.percentile(server_ms, 95)), 1),
        "server_max_ms": round(float(np.max(server_ms)), 1),
        "client_p95_ms": round(float(np.percentile(client_ms, 95)), 1),
        "server_cpu_ms_per_step": round(1000 * cpu / max(1, len(stats.client_ms)), 2),
        "errors": len(stats.errors),
        "database": "sqlite" if database_url is None else url.split(":")[0],
    }
    print(
        f"study server, {participants} concurrent participants ({result['database']}): "
        f"{result['requests']} steps in {result['wall_s']} s, {stats.completed} finished\n"
        f"  server-side step latency  p50 {result['server_p50_ms']} ms  "
        f"p95 {result['server_p95_ms']} ms  max {result['server_max_ms']} ms\n"
        f"  server CPU per step {result['server_cpu_ms_per_step']} ms; "
        f"client-side p95 {result['client_p95_ms']} ms; errors {result['errors']}"
    )
    for e in stats.errors[:10]:
        print(f"  error: {e}")
    return result


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--participants", type=int, default=50)
    parser.add_argument("--seconds", type=float, default=120.0)
    parser.add_argument("--think", type=float, default=2.0, help="mean pause between steps (s)")
    parser.add_argument("--ramp", type=float, default=5.0, help="arrivals spread over (s)")
    parser.add_argument("--database-url", default=None)
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    result = run(args.participants, args.seconds, args.think, args.database_url, args.ramp)
    if args.json:
        args.json.write_text(json.dumps(result, indent=2) + "\n")


if __name__ == "__main__":
    sys.path.insert(0, str(REPO / "src"))
    main()
