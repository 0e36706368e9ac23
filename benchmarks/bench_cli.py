"""Command-line start-up: wall time of ``emogen --help`` and of a few commands' ``--help``.

``python benchmarks/bench_cli.py [--repeat 5]`` runs each in a fresh process (``python -m
emogen``) and prints the best and median wall time, and which heavy libraries each imported
(from ``-X importtime``). The goal is under 0.5 s for ``emogen --help``; the test
``tests/test_cli_startup.py`` checks the imports behind it, not the time.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time

COMMANDS = (["--help"], ["simulate", "--help"], ["analyse", "--help"], ["render", "--help"])
HEAVY = (
    "numpy",
    "numba",
    "scipy",
    "sklearn",
    "matplotlib",
    "pandas",
    "sqlalchemy",
    "moderngl",
    "fastapi",
)


def heavy_imports(args: list[str]) -> list[str]:
    proc = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "emogen", *args],
        capture_output=True,
        text=True,
        check=True,
    )
    names = {line.rsplit("|", 1)[-1].strip() for line in proc.stderr.splitlines() if "|" in line}
    return sorted(h for h in HEAVY if h in names)


def run(repeat: int = 5) -> dict[str, dict[str, object]]:
    print("\n== command line start-up (fresh process each; machine load adds noise) ==")
    print(f"{'command':<28} {'best s':>8} {'median s':>9}  heavy imports")
    results: dict[str, dict[str, object]] = {}
    for args in COMMANDS:
        times = []
        for _ in range(repeat):
            t = time.perf_counter()
            subprocess.run([sys.executable, "-m", "emogen", *args], capture_output=True, check=True)
            times.append(time.perf_counter() - t)
        heavy = heavy_imports(args)
        name = "emogen " + " ".join(args)
        results[name] = {"best_s": min(times), "median_s": statistics.median(times), "heavy": heavy}
        print(f"{name:<28} {min(times):>8.3f} {statistics.median(times):>9.3f}  {heavy or 'none'}")
    return results


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=5)
    run(parser.parse_args().repeat)
