"""Cost of ``emogen analyse`` on simulated studies of the published design (4 emotions × 2
identities, a categorise block of 24: ``examples/published-design.toml``) at several sizes.

    python benchmarks/bench_analyse.py                               # 50 100 200 336
    python benchmarks/bench_analyse.py --sizes 50 100 --cores 0,1    # analyse pinned to 2 cores
    PYTHONPATH=. python benchmarks/bench_analyse.py --planted        # exports in seconds

For each size: ``emogen study simulate`` (``--workers`` processes) and ``emogen study export``
into a temporary folder (not timed; ``--planted``: ``benchmarks/planted_study.py`` writes the
export directly — the same design and table sizes, 11 generations of 10 faces, 8 own, 8
others' and 8 random faces to label, but weights without correctives, so the reliability
section says it cannot run and CD omits the correctives; analysed with ``--no-exclusions``, as
its carried elite sits on tile 0 and the quality rule would exclude everyone), then
``emogen analyse --progress`` in a fresh process
(optionally pinned by ``taskset -c CORES``), timed. Prints the wall and CPU time per size
with the 1-minute load average at the start and end of its analysis, each
section's share (from the progress lines), and the growth exponent of every section between
the smallest and largest size (1: linear in participants; 2: quadratic).
"""

from __future__ import annotations

import argparse
import math
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
CONFIG = REPO / "examples" / "published-design.toml"
LINE = re.compile(r"^\[\s*([\d.]+) s\] (.+)$")


def emogen(*args: str, cores: str | None = None) -> subprocess.CompletedProcess[str]:
    pin = ["taskset", "-c", cores] if cores else []
    cmd = [*pin, sys.executable, "-m", "emogen", *args]
    run = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if run.returncode:
        raise SystemExit(f"{' '.join(cmd)} failed ({run.returncode}):\n{run.stderr[-3000:]}")
    return run


def sections(progress: str, total: float) -> dict[str, float]:
    """Seconds per section from ``--progress`` lines ([  t s] name), the last to the end."""
    marks = [(float(m[1]), m[2]) for m in map(LINE.match, progress.splitlines()) if m]
    ends = [t for t, _ in marks[1:]] + [total]
    out: dict[str, float] = {}
    for (start, name), end in zip(marks, ends, strict=True):
        key = re.sub(r"\s*\(.*\)$", "", name)
        out[key] = out.get(key, 0.0) + end - start
    return out


def one_size(n: int, args: argparse.Namespace, tmp: Path) -> tuple[float, dict[str, float]]:
    tmp = args.keep or tmp
    db = tmp / f"s{n}.sqlite"
    export, report = tmp / f"e{n}", tmp / f"r{n}"
    start = time.perf_counter()
    if args.keep and (export / "trials.parquet").is_file():
        pass  # made by an earlier run with --keep
    elif args.planted:
        planted_export(n, export, args.seed)
    else:
        emogen(
            "study",
            "simulate",
            str(CONFIG),
            "-n",
            str(n),
            "--seed",
            str(args.seed),
            "--workers",
            str(args.workers),
            "--database-url",
            f"sqlite:///{db}",
        )
        emogen("study", "export", "--database-url", f"sqlite:///{db}", "--out", str(export))
    made = time.perf_counter() - start
    start, cpu, load = time.perf_counter(), _child_cpu(), os.getloadavg()[0]
    # the planted generator carries the elite on tile 0 in > 90% of generations, which the
    # quality rule excludes (every participant): its exports are analysed without exclusions
    unruled = ["--no-exclusions"] if args.planted else []
    run = emogen(
        "analyse", str(export), "-o", str(report), "--progress", *unruled, cores=args.cores
    )
    total, cpu = time.perf_counter() - start, _child_cpu() - cpu
    print(
        f"{n} participants: simulated and exported in {made:.0f} s; analyse {total:.1f} s "
        f"wall, {cpu:.1f} s CPU (user + system; the wall time on a busy machine is longer); "
        f"load average {load:.1f} at the start, {os.getloadavg()[0]:.1f} at the end",
        flush=True,
    )
    return total, sections(run.stdout + run.stderr, total)


def _child_cpu() -> float:
    """CPU seconds (user + system) of this process's finished children."""
    import resource

    use = resource.getrusage(resource.RUSAGE_CHILDREN)
    return use.ru_utime + use.ru_stime


def planted_export(n: int, folder: Path, seed: int) -> None:
    """The published design's export for ``n`` participants by the planted generator."""
    import emogen
    from benchmarks.planted_study import PlantedDesign, write_planted_study

    design = PlantedDesign(
        participants=n,
        emotions=("angry", "fearful", "happy", "sad"),
        identities=("female-medium", "male-medium"),
        generations=11,
        population=10,
        own_weight=0.5,
        n_other=8,
        n_random=8,
        n_own=8,
    )
    write_planted_study(design, folder, seed=seed, rig=emogen.load_model().rig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[50, 100, 200, 336])
    ap.add_argument("--workers", type=int, default=max(1, (os.cpu_count() or 2) - 1))
    ap.add_argument("--cores", default=None, help="taskset core list for analyse, e.g. 0,1")
    ap.add_argument("--seed", type=int, default=336)
    ap.add_argument("--planted", action="store_true", help="exports by planted_study.py")
    ap.add_argument(
        "--keep", type=Path, default=None, help="a folder to keep exports in (and reuse)"
    )
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        runs = {n: one_size(n, args, Path(tmp)) for n in args.sizes}
    names = list(dict.fromkeys(k for _t, s in runs.values() for k in s))
    print(f"\nanalyse wall time (s){' on cores ' + args.cores if args.cores else ''}:")
    print("section".ljust(40) + "".join(f"{n:>9d}" for n in runs) + "  growth")
    lo, hi = min(runs), max(runs)
    for name in [*names, "total"]:
        vals = {n: (t if name == "total" else s.get(name, 0.0)) for n, (t, s) in runs.items()}
        growth = (
            math.log(vals[hi] / vals[lo]) / math.log(hi / lo)
            if hi > lo and vals[lo] > 0.05 and vals[hi] > 0
            else float("nan")
        )
        print(
            name[:39].ljust(40) + "".join(f"{v:9.1f}" for v in vals.values()) + f"  n^{growth:.2f}"
        )


if __name__ == "__main__":
    main()
