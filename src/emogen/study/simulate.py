"""``emogen study simulate``: simulated participants run a whole study through the real study
service and database — every block of every task — so a lab can pilot the design,
the export and the analysis before going live.

Participant ``i`` (id ``sim-0001`` …) draws their prototypes and every choice from child ``i``
of the seed (:func:`numpy.random.SeedSequence.spawn`); they answer what the page would show
(the service's state), through the same steps a browser sends. Their sessions are recorded
with ``participant_source = "simulated"`` (a column of every exported table).

With one worker the participants run one after another, so participant ``i`` draws others'
faces from participants ``< i``: the same seed gives the same data. ``concurrent = N``
(``--arrivals concurrent N``) runs them in waves of N that arrive at once, as a launch on a
panel does: each takes one step in turn, so nobody in a wave finishes before the others reach
a labelling block — the first wave finds no other participant's faces (fallback faces, or the
block's ``others_pool``). Still one seed, the same data. With several workers each
runs a share of the participants in its own process on the same database; everything but
which other participants' faces a labelling block finds complete is the same.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from sqlalchemy import func, select

from emogen.errors import ConfigError
from emogen.study.config import StudyConfig
from emogen.study.storage import Store
from emogen.study.tables import SessionRow
from emogen.tasks.registry import task_named
from emogen.tasks.simulated import (
    SimulatedDesign,
    SimulatedParticipant,
    SimulatedPeople,
    own_courses,
    own_prototypes,
    population_prototypes,
)

if TYPE_CHECKING:
    from emogen.model.face import FaceModel
    from emogen.study.sessions import StudyService

SOURCE = "simulated"


@dataclass(frozen=True)
class SimulationPlan:
    """Everything a worker needs (picklable): the study, where to record it, who to run."""

    config: StudyConfig
    database_url: str
    seed: int
    participants: int
    design: SimulatedDesign
    shuffle_prototypes: bool
    model_path: Path | None = None
    #: Participants who arrive at once (``--arrivals concurrent N``): waves of N, each taking
    #: its steps in turn; 1: one after another.
    concurrent: int = 1


@dataclass
class SimulationSummary:
    participants: int
    database: str
    seed: int
    seconds: float
    shuffled: bool
    steps: int = 0
    by_task: dict[str, int] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


def participant_id(i: int) -> str:
    return f"sim-{i + 1:04d}"


def participant_stream(
    plan: SimulationPlan, rig: Any, i: int
) -> tuple[dict[str, np.ndarray], np.random.Generator]:
    """Participant ``i``'s prototypes, drawn first from their own child of the seed, and that
    generator (their choices come next from it)."""
    cfg = plan.config
    population = population_prototypes(rig, cfg.emotions, plan.design, cfg.ga.eye_motion)
    child = np.random.SeedSequence(plan.seed).spawn(plan.participants)[i]
    rng = np.random.default_rng(child)
    return own_prototypes(population, plan.design, rng), rng


def timing_stream(plan: SimulationPlan, i: int) -> np.random.Generator:
    """Participant ``i``'s own stream of their time courses (a child of their stream's seed, so
    their prototypes and choices are drawn as without it)."""
    child = np.random.SeedSequence(plan.seed).spawn(plan.participants)[i]
    return np.random.default_rng(child.spawn(1)[0])


def all_prototypes(plan: SimulationPlan, rig: Any) -> list[dict[str, np.ndarray]]:
    """Every participant's prototypes."""
    return [participant_stream(plan, rig, i)[0] for i in range(plan.participants)]


class Walker:
    """Participant ``i`` in the study: their session made on creation, one step at a time."""

    def __init__(
        self,
        service: StudyService,
        plan: SimulationPlan,
        i: int,
        prototypes: list[dict[str, np.ndarray]],
    ) -> None:
        rig, eyes = service.ctx.rig, plan.config.ga.eye_motion
        _, rng = participant_stream(plan, rig, i)
        n = plan.participants
        labeller = prototypes[(i + 1) % n] if plan.shuffle_prototypes else prototypes[i]
        courses = own_courses(plan.config.emotions, plan.design, timing_stream(plan, i))
        maker = SimulatedParticipant(prototypes[i], plan.design, rig, eyes, rng, courses)
        judge = SimulatedParticipant(labeller, plan.design, rig, eyes, rng, courses)
        self.who = SimulatedPeople(maker=maker, judge=judge)
        self.service, self.i = service, i
        self.token, self.state = service.create_session(participant_id(i), source=SOURCE)
        self.counts: dict[str, int] = {}
        self.k = 0

    @property
    def done(self) -> bool:
        return bool(self.state["stage"] == "done")

    def step(self) -> None:
        self.k += 1
        body = _command(self.who, self.state)
        key = f"sim{self.i + 1:05d}s{self.k:05d}"
        self.state = self.service.step(self.token, {**body, "key": key})
        self.counts[body["command"]] = self.counts.get(body["command"], 0) + 1


def run_participant(
    service: StudyService, plan: SimulationPlan, i: int, prototypes: list[dict[str, np.ndarray]]
) -> dict[str, int]:
    """Participant ``i`` through the whole study; the steps taken per kind."""
    walker = Walker(service, plan, i, prototypes)
    while not walker.done:
        walker.step()
    return walker.counts


def run_wave(
    service: StudyService,
    plan: SimulationPlan,
    wave: Sequence[int],
    prototypes: list[dict[str, np.ndarray]],
) -> dict[str, int]:
    """Participants ``wave`` at once, as a launch sees them: all consent, then each takes one
    step in turn until every one is done (no one finishes before the others have started)."""
    walkers = [Walker(service, plan, i, prototypes) for i in wave]
    while not all(w.done for w in walkers):
        for w in walkers:
            if not w.done:
                w.step()
    total: dict[str, int] = {}
    for w in walkers:
        for kind, n in w.counts.items():
            total[kind] = total.get(kind, 0) + n
    return total


def _command(who: SimulatedPeople, state: Any) -> dict[str, Any]:
    """What the simulated participant sends to the state shown (its task answers)."""
    if state["stage"] == "instructions":
        return {"command": "begin"}
    trial = state["trial"]
    return task_named(trial["task"]).simulate(who, state["view"], state["progress"]["trial"])


def _service(plan: SimulationPlan, model: FaceModel | None) -> tuple[StudyService, Store]:
    from emogen.model import load_model
    from emogen.study.sessions import StudyService

    if model is None:
        model = load_model(plan.model_path or plan.config.model, rig=plan.config.rig)
    store = Store(plan.database_url)
    service = StudyService(
        plan.config,
        store,
        model.rig,
        model_name=model.name,
        model_hash=model.model_hash,
        model=model,
    )
    return service, store


def _run_share(plan: SimulationPlan, share: Sequence[int]) -> dict[str, int]:
    """A worker process: its share of the participants."""
    service, store = _service(plan, None)
    try:
        prototypes = all_prototypes(plan, service.ctx.rig)
        total: dict[str, int] = {}
        for i in share:
            for kind, n in run_participant(service, plan, i, prototypes).items():
                total[kind] = total.get(kind, 0) + n
        return total
    finally:
        store.dispose()


def _check_fresh(store: Store, study_id: int) -> None:
    """Simulated participants go into a database of their own: never beside real ones, never
    twice (the same ids would collide and the data would not be the seed's)."""
    with store.read() as db:
        n = db.scalar(
            select(func.count()).select_from(SessionRow).where(SessionRow.study_id == study_id)
        )
    if n:
        raise ConfigError(
            f"{store.describe()} already holds {n} session(s) of this study: simulated "
            "participants go into a database of their own (choose a new --database-url)"
        )


def simulate_study(
    plan: SimulationPlan,
    *,
    workers: int = 1,
    model: FaceModel | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> SimulationSummary:
    """Run ``plan.participants`` simulated participants through the study."""
    if plan.participants < 1:
        raise ConfigError(f"--participants must be >= 1; got {plan.participants}")
    if workers < 1:
        raise ConfigError(f"--workers must be >= 1; got {workers}")
    if plan.concurrent < 1:
        raise ConfigError(f"--arrivals concurrent N needs N >= 1; got {plan.concurrent}")
    if plan.concurrent > 1 and workers > 1:
        raise ConfigError(
            "--arrivals concurrent runs its waves in one process (their steps interleaved, the "
            f"same data for the same seed): use --workers 1; got --workers {workers}"
        )
    started = time.perf_counter()
    service, store = _service(plan, model)
    try:
        _check_fresh(store, service.ctx.study_id)
        total: dict[str, int] = {}
        if workers == 1:
            prototypes = all_prototypes(plan, service.ctx.rig)
            size = plan.concurrent
            for start in range(0, plan.participants, size):
                wave = range(start, min(start + size, plan.participants))
                for kind, n in run_wave(service, plan, wave, prototypes).items():
                    total[kind] = total.get(kind, 0) + n
                if progress is not None:
                    progress(wave[-1] + 1, plan.participants)
        else:
            if plan.model_path is None and model is not None and model.source:
                plan = replace(plan, model_path=Path(model.source))  # workers load the same
            shares = [list(range(w, plan.participants, workers)) for w in range(workers)]
            with ProcessPoolExecutor(max_workers=workers) as pool:
                for done, part in enumerate(pool.map(_run_share, [plan] * workers, shares)):
                    for kind, n in part.items():
                        total[kind] = total.get(kind, 0) + n
                    if progress is not None:
                        progress(sum(len(s) for s in shares[: done + 1]), plan.participants)
    finally:
        store.dispose()
    return SimulationSummary(
        participants=plan.participants,
        database=store.describe(),
        seed=plan.seed,
        seconds=round(time.perf_counter() - started, 2),
        shuffled=plan.shuffle_prototypes,
        steps=sum(total.values()),
        by_task=total,
    )
