"""A/B render time of one 512² face, interleaved: two worker processes (one per source tree,
e.g. main's and a branch's), asked in turn to render the same face, so that both see the same
load on a shared machine. Prints medians, IQR and the ratio per configuration.

    python benchmarks/bench_render_ab.py OLD_CHECKOUT/src src [--repeat 21]   # OLD_CHECKOUT: a git worktree of main

Each worker builds a ``Renderer`` per configuration (flat: no appearance, the bench_render
figure; textured: the generic preset, the default face framing) and times ``render`` of one
face (bench_render's first face, uncorrected as its figure) after a warm-up.

Measured (2026-11-26, 2 shared cores, llvmpipe, load average 6.3, 21 repeats; main vs the
issue-29 branch): flat 181.6 ms (IQR 145-212) vs 157.9 ms (135-172), 0.87×; textured 203.0 ms
(181-230) vs 189.4 ms (170-224), 0.93×. Before the per-group programs: 1.26× and 1.31×.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import IO, cast

import numpy as np

REPO = Path(__file__).resolve().parents[1]

_WORKER = """
import json, sys, time
import numpy as np
from emogen.model import load_model
from emogen.appearance.identities import PRESETS
from emogen.render.renderer import Renderer
sys.path.insert(0, sys.argv[2])
from benchmarks.bench_render import _faces
m = load_model(sys.argv[1])
w = _faces(m, 10)[:1]
configs = {"flat": {}, "textured": {"appearance": PRESETS["generic"].appearance}}
rs = {k: Renderer(m, size=512, **o) for k, o in configs.items()}
for r in rs.values():
    r.render(w)
    r.render(w)
print("ready", flush=True)
for line in sys.stdin:
    name = line.strip()
    t = time.perf_counter()
    rs[name].render(w)
    print(json.dumps(time.perf_counter() - t), flush=True)
"""


def _worker(src: str, model: str) -> subprocess.Popen[str]:
    env = {**os.environ, "PYTHONPATH": src}
    p = subprocess.Popen(
        [sys.executable, "-c", _WORKER, model, str(REPO)],
        env=env,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    if cast(IO[str], p.stdout).readline().strip() != "ready":
        raise RuntimeError(f"worker for {src} failed to start")
    return p


def _ask(p: subprocess.Popen[str], name: str) -> float:
    stdin, stdout = cast(IO[str], p.stdin), cast(IO[str], p.stdout)
    stdin.write(name + "\n")
    stdin.flush()
    return float(json.loads(stdout.readline()))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("a", help="source tree A (PYTHONPATH), e.g. a worktree of main: ../main/src")
    ap.add_argument("b", help="source tree B")
    ap.add_argument("--repeat", type=int, default=21)
    ap.add_argument("--model", default=os.environ.get("EMOGEN_MODEL", ""))
    args = ap.parse_args()
    workers = [_worker(args.a, args.model), _worker(args.b, args.model)]
    times: dict[tuple[str, int], list[float]] = {}
    for i in range(args.repeat):
        for name in ("flat", "textured"):
            order = (0, 1) if i % 2 == 0 else (1, 0)  # alternate who goes first
            for j in order:
                times.setdefault((name, j), []).append(_ask(workers[j], name))
    for p in workers:
        cast(IO[str], p.stdin).close()
        p.wait()
    load = os.getloadavg()
    print(f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}; {args.repeat} repeats each")
    print(f"{'':10s} {'A median':>9s} {'A IQR':>13s} {'B median':>9s} {'B IQR':>13s} {'B/A':>6s}")
    for name in ("flat", "textured"):
        a, b = (np.asarray(times[(name, j)]) * 1000 for j in (0, 1))
        qa, qb = np.percentile(a, [25, 75]), np.percentile(b, [25, 75])
        print(
            f"{name:10s} {np.median(a):7.1f}ms {qa[0]:5.0f}–{qa[1]:5.0f} ms "
            f"{np.median(b):7.1f}ms {qb[0]:5.0f}–{qb[1]:5.0f} ms {np.median(b) / np.median(a):6.2f}"
        )


if __name__ == "__main__":
    main()
