"""The task protocol: what the study layer asks of every task.

A study is a sequence of blocks; a block runs one **task** over its trials. A task is one
module (``emogen/tasks/<task>/``) implementing :class:`Task`: its block config (a
:class:`~emogen.tasks.blocks.TaskBlock`), its record tables (rows on
:class:`~emogen.tasks.records.Base`), the commands a participant sends (pydantic models keyed by
``command``), how a trial starts (what it shows is stored before it is shown), the
participant's view of a trial (only what the participant may know), how a command is accepted
(the records it makes and whether the trial is done), the trial's record for an embedding page,
its replay and its simulated participant. The study service, the web layer, the export and the
page drive tasks only through this protocol and :mod:`emogen.tasks.registry` — after pymoo's
ask/tell and jsPsych's plugins (typed ``info``, ``trial()``, ``simulate()``).

Each method gets a :class:`TaskEnv` (the study's config, rig, correctors and what the task
prepared when the service started) and, where it reads or stores records, the step's open
database session: the study holds the lock and the transaction; a task adds its rows to it.

Optional: ``ahead(env, db, row, cmd)``, a command's pure work done in a read before the write
transaction where the block's ``works_ahead`` says so; it stores nothing (docs/tasks.md).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Annotated, Any, ClassVar, Literal, NotRequired, Protocol

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field
from sqlalchemy.orm import Session
from typing_extensions import TypedDict

from emogen.tasks.blocks import Condition, TaskBlock
from emogen.tasks.records import TrialRow


class Motion(TypedDict):
    """How a face that moves moves (docs/ga.md, "Dynamic faces"), as the page plays it: a clip
    of ``clip_s`` seconds, then ``hold_s`` at rest, looped. At time t of the clip a shape's
    weight is its peak weight (the face's ``weights``) times the curve of its row of
    ``curves`` — ``[t_on, t_peak, t_off, rise_slope, fall_slope]`` (seconds; the Hermite
    slopes), every shape in GLB target order — and the corrective weights are ``keyframes``
    (rows evenly over the clip, empty for faces shown uncorrected) interpolated linearly."""

    clip_s: float
    hold_s: float
    curves: list[list[float]]
    keyframes: list[list[float]]


class FaceView(TypedDict):
    """A face: its id in the trial and its full weights (shapes, then correctives) in GLB
    target order; a face that moves also its ``motion`` (its weights are then its peak)."""

    id: int
    weights: list[float]
    motion: NotRequired[Motion]


# ---- commands ----------------------------------------------------------------------------
def _whole_number(value: Any) -> Any:
    """JSON Schema counts 3.0 as an integer: take it as 3 (3.5 stays a float and is refused)."""
    return int(value) if isinstance(value, float) and value.is_integer() else value


#: A client-made key per step (e.g. a UUID); the same key again is the same step.
StepKey = Annotated[str, Field(pattern=r"^[A-Za-z0-9_-]{8,64}$")]
Index = Annotated[int, Field(ge=0, le=100_000), BeforeValidator(_whole_number)]
FaceId = Annotated[int, Field(ge=0, le=2**31 - 1), BeforeValidator(_whole_number)]
Millis = Annotated[float, Field(ge=0, le=86_400_000, allow_inf_nan=False)]
Points = Annotated[int, Field(ge=1, le=11), BeforeValidator(_whole_number)]


class Command(BaseModel):
    """A participant's step: ``command`` names it (each subclass narrows it to a Literal),
    ``key`` makes it idempotent. Strict: a wrong type or an unknown key is refused."""

    model_config = ConfigDict(extra="forbid", strict=True, frozen=True)

    command: str
    key: StepKey

    def payload(self) -> dict[str, Any]:
        """What the request held besides its key and name (hashed to tell a replayed key from a
        reused one); the page's facts added later (``load_ms``, ``fallback``) only when given,
        as keys recorded before they were sent."""
        data = self.model_dump(exclude={"key", "command"})
        for later in ("load_ms", "fallback"):
            if data.get(later, 0) is None:
                del data[later]
        return data


class Begin(Command):
    """Instructions read: the first trial starts (the study's own command, not a task's)."""

    command: Literal["begin"]


class TrialCommand(Command):
    """A command of a task: for the session's trial at ``trial`` (0-based), with the page's
    times (``response_ms``: the screen visible → the answer; ``load_ms``: what was shown
    received → drawn, for a first screen page, model and textures)."""

    trial: Index
    response_ms: Millis | None = None

    @property
    def load(self) -> float | None:
        return getattr(self, "load_ms", None)


class MadeFace(TypedDict):
    """A face a participant made in a finished trial (a later block may show it)."""

    session_id: int
    trial: int
    condition: int
    emotion: str
    identity: str
    face_id: int
    genes: list[float]
    weights: list[float]


# ---- what a task gets and gives ---------------------------------------------------------------
@dataclass(frozen=True)
class TaskEnv:
    """What a task knows of the study it runs in.

    ctx : the study's context (config, rig, conditions, the accepted study rows)
    correctors : ``correctors(identity, collision_solver=None)`` — the corrector of a
        corrected study's faces of that identity (None when faces are not corrected)
    prepared : what each block's task prepared when the service started, by block index
    made_faces : ``made_faces(db, where)`` — the faces participants made in the finished
        trials matching ``where`` (SQL conditions on :class:`TrialRow`), by every task that
        makes faces
    sessions_done : ``sessions_done(session_id)`` — a SELECT of the ids of this study's
        completed sessions other than ``session_id`` (other participants' faces come from them)
    """

    ctx: Any
    correctors: Callable[..., Any]
    prepared: dict[int, Any] = field(default_factory=dict)
    made_faces: Callable[[Session, Sequence[Any]], list[MadeFace]] = lambda db, where: []
    sessions_done: Callable[[int], Any] = lambda session_id: ()

    @property
    def config(self) -> Any:
        return self.ctx.config

    def block(self, row: TrialRow) -> Any:
        """The (resolved) block config of a trial."""
        return self.ctx.config.study_blocks()[row.block]


@dataclass
class Outcome:
    """What a task's start or accepted command did: ``done`` when the trial is finished (the
    study then starts the next one); ``shown``: what it has just stored to show, handed to
    :meth:`Task.view` so the view need not read it back."""

    done: bool = False
    shown: Any = None


@dataclass(frozen=True)
class ExportedStudy:
    """One study of an export folder (``emogen study export``), for a replay from the files.

    config : the study's resolved config (:class:`emogen.study.config.StudyConfig`)
    genes, weights : the gene and weight column names (``g_<gene>``, ``w_<weight>``)
    tables : the export's tables, by name, holding this study's rows only
    sessions : the session ids to replay
    rig : the face model's rig
    """

    config: Any
    genes: list[str]
    weights: list[str]
    tables: dict[str, Any]
    sessions: frozenset[int]
    rig: Any

    def trials_of(self, task: str) -> Any:
        """The exported trials of ``task`` in the sessions to replay, in session and trial
        order (a DataFrame of the ``trials`` table)."""
        t = self.tables["trials"]
        mine = t[(t["task"].astype(str) == task) & t["session_id"].isin(list(self.sessions))]
        return mine.sort_values(["session_id", "trial"])

    def missing(self, task: str, names: Sequence[str]) -> dict[int, list[Replayed]] | None:
        """Where the export lacks one of ``names`` (a task's tables): for each session with
        trials of ``task``, a replay saying they could not be checked and why; else None."""
        lacking = [n for n in names if n not in self.tables]
        if not lacking:
            return None
        out: dict[int, list[Replayed]] = {}
        for sid, trials in self.trials_of(task).groupby("session_id", sort=True):
            why = (
                f"session {sid}: its {len(trials)} {task} trials not checked: the export has "
                f"no {' or '.join(lacking)} table"
            )
            out[int(sid)] = [Replayed(unchecked=[why])]
        return out


@dataclass
class Replayed:
    """A trial's replay: what was checked and what differed (``deviation``: the largest
    weight deviation, :mod:`emogen.tasks.rounding`); ``checked``: what the task rebuilt and
    compared, counted by what it is ("label orders": 16); ``unchecked``: what it could not check,
    each saying what and why (a replay with any is not "ok": nothing unchecked passes)."""

    populations: int = 0
    faces: int = 0
    stimuli: int = 0
    problems: list[str] = field(default_factory=list)
    deviation: float = 0.0
    checked: dict[str, int] = field(default_factory=dict)
    unchecked: list[str] = field(default_factory=list)


class Task(Protocol):
    """One task: registered in :mod:`emogen.tasks.registry` under :attr:`name`."""

    #: as in ``[[blocks]] task = …`` and ``trials.task``
    name: ClassVar[str]
    #: its block config
    block: ClassVar[type[TaskBlock]]
    #: the commands it accepts (each a :class:`TrialCommand` with its own ``command`` Literal)
    commands: ClassVar[tuple[type[TrialCommand], ...]]
    #: what :meth:`view` answers (a TypedDict whose ``task`` is ``Literal[name]``)
    view_type: ClassVar[type]
    #: what :meth:`result` answers (a TypedDict whose ``task`` is ``Literal[name]``)
    result_type: ClassVar[type]
    #: its record tables (rows on :class:`emogen.tasks.records.Base`)
    tables: ClassVar[tuple[type, ...]]
    #: its export tables (:class:`emogen.tasks.export.ExportTable`: name, typed columns, rows
    #: from a read's records; :func:`emogen.tasks.export.record_table` makes one from a record)
    export_tables: ClassVar[tuple[Any, ...]]
    #: the export tables :meth:`replay_exported` reads (``emogen study replay --from-export``)
    replay_tables: ClassVar[tuple[str, ...]]
    #: what the study's default instructions say of its blocks
    instructions: ClassVar[str]
    #: screens a trial shows a participant, and the seconds each takes (low, high): an
    #: estimate of the session's length (:mod:`emogen.study.length`)
    screens: ClassVar[dict[str, tuple[float, float]]]

    def screens_of(self, condition: Condition, generations: int) -> dict[str, int]:
        """The screens of each kind (:attr:`screens`) a trial of ``condition`` shows."""

    def prepare(self, ctx: Any, k: int, block: Any) -> Any:
        """What block ``k`` needs read once when the service starts (a face table), checked
        before anyone starts; None when nothing."""

    def rows(self, prepared: Any) -> int | None:
        """The rows of the block's face table (its trials where it shows them all)."""

    def start(self, env: TaskEnv, db: Session, row: TrialRow, session_id: int) -> Outcome:
        """Start the session's trial ``row``: store what it shows first, then mark it active."""

    def accept(self, env: TaskEnv, db: Session, row: TrialRow, cmd: TrialCommand) -> Outcome:
        """Take the participant's command (raise StepConflict / SelectionError where it does
        not fit); store what it makes."""

    def view(self, env: TaskEnv, db: Session, row: TrialRow, shown: Any) -> dict[str, Any]:
        """What the participant is shown of the trial now (``task`` key first): only what they
        may know."""

    def prompt(self, env: TaskEnv, row: TrialRow) -> str:
        """The trial's instruction line."""

    def face(
        self, env: TaskEnv, db: Session, row: TrialRow, face_id: int
    ) -> tuple[str, str] | None:
        """(weights JSON, identity) of a face the trial shows now, else None. The weights are
        one face's, or for a face that moves a list of frames' (the server's image is then the
        strip of those frames, left to right)."""

    def result(self, env: TaskEnv, db: Session, row: TrialRow) -> dict[str, Any] | None:
        """The trial's outcome as the participant's page may record it (None before there is
        one): never what the participant may not know."""

    def made_faces(self, db: Session, where: Sequence[Any]) -> list[MadeFace]:
        """The faces this task's finished trials made (trials matching ``where``)."""

    def replay(self, env: TaskEnv, db: Session, row: TrialRow, rig: Any) -> Replayed:
        """Re-run the trial from its seed and recorded commands; compare with its records."""

    def replay_exported(self, env: TaskEnv, study: ExportedStudy) -> dict[int, list[Replayed]]:
        """Replay this task's trials of ``study``'s sessions from the exported files alone, in
        trial order: the replays of each session, by session id."""

    def export_size(self, db: Session, sessions: Any) -> dict[int, int]:
        """The rows this task's export tables hold for each session in ``sessions`` (a SELECT
        of session ids): the export is written a few sessions at a time, sized by them."""

    def simulate(self, who: Any, view: dict[str, Any], trial: int) -> dict[str, Any]:
        """The command (a JSON body, without its key) a simulated participant sends to
        ``view`` (``who``: :class:`emogen.tasks.simulated.SimulatedPeople`)."""

    def state_facts(self, state: str | None) -> dict[str, Any]:
        """Facts of a trial's stored state the trials export table shows (the GA's stream and
        collision solver), by column."""

    def shows(self, block: Any, config: Any) -> dict[str, Any]:
        """What every trial of ``block`` (resolved) shows its participant, told before the
        session (GET /api/study: a page that simulates the study's data without a server reads
        it): only what a participant sees anyway, never what they may not know."""

    def progress_step(
        self, status: str, generation: int, generations: int
    ) -> tuple[str, int | None]:
        """Where in a trial of this status a participant is, for the researcher's dashboard
        ("generation 3 of 11", "rating", the task's name), and the generation shown (from 1),
        if any."""

    def notes(self, db: Session, sessions: Any, k: int, block: Any) -> list[str]:
        """What the researcher's dashboard should say of block ``k`` over ``sessions`` (a
        SELECT of the study's session ids): what went otherwise than the design meant."""

    # Optional: ``analysis_section(tools)`` — ``emogen analyse``'s section on the task's
    # export tables (``tools``: :class:`emogen.analysis.task_sections.TaskTools`, the export's
    # tables, the task's own section ``tools.report``, figures, faces drawn; tasks sit below the
    # analysis and call back through it): returns ``tools.report`` filled — content, its
    # entries of analysis.json in ``report.data``, each test a typed result through
    # ``report.add_test`` — or None when the export has nothing of the task's. A task without
    # one is analysed by emogen.analysis itself (categorise; evolve's faces, its section adds
    # dynamic blocks' timing) or not at all.


def conditions_of(blocks: Sequence[TaskBlock], study: Any, rows: dict[int, int]) -> list[Condition]:
    """Every trial in config order, block by block (``rows``: each block's face-table rows)."""
    out: list[Condition] = []
    for k, b in enumerate(blocks):
        out += b.trials(k, study, list(out), rows.get(k))
    return out


class TaskDefaults:
    """What a task that has no more to say answers (subclass it and write the rest): nothing
    to prepare, no face table, no face served as PNG, no result for an embedding page, no
    faces made, a replay that says its trials are not checked (from the database or from an
    export: never "ok"), rows too
    few to size an export by, nothing told of its blocks before the session, and its name on
    the dashboard."""

    name: ClassVar[str]
    replay_tables: ClassVar[tuple[str, ...]] = ()

    def prepare(self, ctx: Any, k: int, block: Any) -> Any:
        return None

    def rows(self, prepared: Any) -> int | None:
        return None

    def ahead(self, env: TaskEnv, db: Session, row: TrialRow, cmd: TrialCommand) -> None:
        return None

    def face(
        self, env: TaskEnv, db: Session, row: TrialRow, face_id: int
    ) -> tuple[str, str] | None:
        return None

    def result(self, env: TaskEnv, db: Session, row: TrialRow) -> dict[str, Any] | None:
        return None

    def made_faces(self, db: Session, where: Sequence[Any]) -> list[MadeFace]:
        return []

    def replay(self, env: TaskEnv, db: Session, row: TrialRow, rig: Any) -> Replayed:
        why = f"trial {row.position + 1}: not checked: the {self.name} task has no replay"
        return Replayed(unchecked=[why])

    def replay_exported(self, env: TaskEnv, study: ExportedStudy) -> dict[int, list[Replayed]]:
        out: dict[int, list[Replayed]] = {}
        for sid, trials in study.trials_of(self.name).groupby("session_id", sort=True):
            why = (
                f"session {sid}: its {len(trials)} {self.name} trials not checked: the task "
                "does not replay from an export"
            )
            out[int(sid)] = [Replayed(unchecked=[why])]
        return out

    def export_size(self, db: Session, sessions: Any) -> dict[int, int]:
        return {}

    def state_facts(self, state: str | None) -> dict[str, Any]:
        return {}

    def shows(self, block: Any, config: Any) -> dict[str, Any]:
        return {}

    def progress_step(
        self, status: str, generation: int, generations: int
    ) -> tuple[str, int | None]:
        return self.name, None

    def notes(self, db: Session, sessions: Any, k: int, block: Any) -> list[str]:
        return []
