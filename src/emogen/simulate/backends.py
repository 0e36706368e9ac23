"""Where simulated runs are computed: in this process, a local process pool, or Dask.

A backend takes tasks — (problem, run numbers, run seeds) — and yields each task's
:class:`~emogen.simulate.problem.RunArrays` as it finishes. Every run draws from its own seeds,
so the numbers do not depend on the backend, the chunking or the order tasks finish in.

* :class:`LocalBackend` — ``workers=1``: in this process, one vectorised batch per task,
  reporting progress every generation; ``workers>1``: a process pool (forkserver).
* :class:`DaskBackend` — a ``distributed`` cluster: ``DaskBackend("tcp://host:8786")`` joins a
  running scheduler; ``DaskBackend()`` starts a ``LocalCluster`` (``n_workers``,
  ``processes``). Each task's problem is scattered to the workers once.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from typing import Any

import numpy as np

from emogen.errors import ConfigError
from emogen.simulate.problem import Problem, RunArrays
from emogen.simulate.vectorised import simulate_runs

Progress = Callable[[int], None]


@dataclass(frozen=True, eq=False)
class Task:
    """Runs of one problem: run numbers and their seeds, (R,) int each."""

    problem: Problem
    runs: np.ndarray
    seeds: np.ndarray


def _run_task(problem: Problem, runs: np.ndarray, seeds: np.ndarray) -> RunArrays:
    return simulate_runs(problem, runs, seeds)


def _one_blas_thread() -> None:
    """Pool worker initialiser: BLAS on one thread in this worker process for its lifetime (the
    parallelism is the workers'; BLAS threads of their own would only compete for the same
    cores). Dask's nanny does the same for its worker processes (OMP/MKL/OPENBLAS_NUM_THREADS=1)."""
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1)  # not restored: nothing else runs in the worker


class LocalBackend:
    """In this process (``workers=1``), or a pool of ``workers`` local processes."""

    def __init__(self, workers: int = 1) -> None:
        if workers < 1:
            raise ConfigError(f"workers must be >= 1; got {workers}")
        self.workers = workers

    @property
    def name(self) -> str:
        return "local" if self.workers == 1 else f"local processes ({self.workers})"

    def chunk_size(self, runs: int) -> int:
        """Runs per task: all at once in-process (capped for memory), else ~2 tasks a worker."""
        if self.workers == 1:
            return min(runs, 2000)
        return max(1, -(-runs // (2 * self.workers)))

    def run(
        self, tasks: Sequence[Task], progress: Progress | None = None
    ) -> Iterator[tuple[int, RunArrays]]:
        if self.workers == 1:
            for i, t in enumerate(tasks):
                yield i, simulate_runs(t.problem, t.runs, t.seeds, on_generation=progress)
            return
        import multiprocessing

        ctx = multiprocessing.get_context("forkserver")
        with ProcessPoolExecutor(
            max_workers=self.workers, mp_context=ctx, initializer=_one_blas_thread
        ) as pool:
            futures = {
                pool.submit(_run_task, t.problem, t.runs, t.seeds): i for i, t in enumerate(tasks)
            }
            for fut in as_completed(futures):
                i = futures[fut]
                if progress is not None:
                    progress(len(tasks[i].runs) * tasks[i].problem.n_generations)
                yield i, fut.result()

    def close(self) -> None:
        """Nothing to release."""


class DaskBackend:
    """A Dask ``distributed`` cluster: a scheduler address, or a new LocalCluster."""

    def __init__(
        self,
        address: str | None = None,
        *,
        n_workers: int = 2,
        processes: bool = True,
        threads_per_worker: int = 1,
        chunk_runs: int = 100,
    ) -> None:
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise ConfigError(
                "the Dask backend needs dask[distributed]: pip install 'emogen[dask]'"
            ) from None
        self.address = address
        self.chunk_runs = chunk_runs
        self._cluster: Any = None
        if address:
            self.client = Client(address)
        else:
            self._cluster = LocalCluster(
                n_workers=n_workers,
                processes=processes,
                threads_per_worker=threads_per_worker,
                dashboard_address=None,
            )
            self.client = Client(self._cluster)

    @property
    def name(self) -> str:
        return f"dask {self.address or 'LocalCluster'}"

    def chunk_size(self, runs: int) -> int:
        return max(1, min(runs, self.chunk_runs))

    def run(
        self, tasks: Sequence[Task], progress: Progress | None = None
    ) -> Iterator[tuple[int, RunArrays]]:
        from distributed import as_completed as dask_completed

        scattered: dict[int, Any] = {}
        futures = {}
        for i, t in enumerate(tasks):
            key = id(t.problem)
            if key not in scattered:
                scattered[key] = self.client.scatter(t.problem, broadcast=True, hash=False)
            fut = self.client.submit(_run_task, scattered[key], t.runs, t.seeds, pure=False)
            futures[fut] = i
        for fut in dask_completed(list(futures)):
            i = futures[fut]
            result = fut.result()
            if progress is not None:
                progress(len(tasks[i].runs) * tasks[i].problem.n_generations)
            yield i, result

    def close(self) -> None:
        self.client.close()
        if self._cluster is not None:
            self._cluster.close()

    def __enter__(self) -> DaskBackend:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


Backend = LocalBackend | DaskBackend


def make_backend(dask: str | None = None, workers: int = 1) -> Backend:
    """``dask``: None (local), ``"local"`` (a LocalCluster of ``workers`` processes) or a
    scheduler address such as ``tcp://10.0.0.5:8786``."""
    if dask is None:
        return LocalBackend(workers)
    if dask == "local":
        return DaskBackend(n_workers=max(1, workers))
    if "://" not in dask:
        raise ConfigError(
            f"--dask must be 'local' or a scheduler address (tcp://host:port); got {dask!r}"
        )
    return DaskBackend(dask)
