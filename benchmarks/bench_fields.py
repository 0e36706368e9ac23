"""Cost of the perceptive fields' quadratic parts at a study's size, with BLAS on its default
threads and on one: the Bhattacharyya matrix of one emotion, and one study of the clustering
null (four emotions' overlap matrices, the spectral embedding and the silhouettes).

    python benchmarks/bench_fields.py                  # 336 participants
    python benchmarks/bench_fields.py --sizes 100 336

Fields are random: two faces each in a 10-dimensional face space (the published design's
fields at 336 participants: two faces per emotion, 10 components). Prints wall and CPU seconds
(user + system, every thread of this process) and the load average beside them: on a busy
2-core machine BLAS's second thread mostly waits for a core, and these matrices are small.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable

import numpy as np
from threadpoolctl import threadpool_limits

from emogen.analysis.field_clusters import best_clusters, field_distances
from emogen.analysis.fields import bhattacharyya

EMOTIONS = ("angry", "fearful", "happy", "sad")


def fields(n: int, rng: np.random.Generator) -> list[np.ndarray]:
    return [rng.normal(rng.normal(0.0, 1.0, 10), 0.3, (2, 10)) for _ in range(n)]


def timed(task: Callable[[], object], repeats: int) -> tuple[float, float]:
    """Mean wall and CPU seconds of ``task`` over ``repeats`` calls."""
    wall, cpu = time.perf_counter(), time.process_time()
    for _ in range(repeats):
        task()
    return (time.perf_counter() - wall) / repeats, (time.process_time() - cpu) / repeats


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[336])
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    for n in args.sizes:
        pts = {e: fields(n, rng) for e in EMOTIONS}
        bw = dict.fromkeys(EMOTIONS, 0.3)

        def bc(pts: dict[str, list[np.ndarray]] = pts) -> object:
            return bhattacharyya(pts["angry"], 0.3, rng=np.random.default_rng(1))

        def null(pts: dict[str, list[np.ndarray]] = pts, bw: dict[str, float] = bw) -> object:
            return best_clusters(field_distances(pts, bw), 6)

        for threads in (None, 1):
            with threadpool_limits(limits=threads, user_api="blas"):
                for name, task in (("Bhattacharyya, one emotion", bc), ("one null study", null)):
                    wall, cpu = timed(task, args.repeats)
                    print(
                        f"{n} participants, BLAS threads {threads or 'default'}: {name}: "
                        f"{wall:.3f} s wall, {cpu:.3f} s CPU (load {os.getloadavg()[0]:.1f})",
                        flush=True,
                    )


if __name__ == "__main__":
    main()
