"""A participant study's configuration (TOML), validated; errors name the bad key.

::

    name = "demo"
    emotions = ["happy", "sad"]          # trials = emotions × repetitions × identities
    repetitions = 1
    identities = ["female-light", "male-dark", "my_face"]   # presets and the lab's own
    order = "random"                     # or "latin_square", "fixed"
    participant_param = "PROLIFIC_PID"   # URL parameter with the participant id
    [ga]                                 # emogen.config.GAConfig: generations, selections, init …
    generations = 10
    [completion]
    code = "C1A2B3"
    [identity.my_face]                   # a lab's own identity: shape + appearance keys
    shape = "female"
    skin_tone = 6.5

See ``docs/study.md`` for every key.
"""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import (
    AfterValidator,
    Field,
    ModelWrapValidatorHandler,
    SerializeAsAny,
    field_serializer,
    field_validator,
    model_validator,
)

from emogen.appearance.identities import PRESETS, Identity, identity_from_dict, identity_table
from emogen.config import GAConfig, _Strict, read_toml, validate_config
from emogen.errors import ConfigError
from emogen.study.block_order import block_names_of, check_block_order
from emogen.study.framing import check_framing
from emogen.study.length import session_length
from emogen.study.origins import check_origin
from emogen.study.texts import (
    DEFAULT_CONSENT,
    DEFAULT_CONSENT_USER_AGENT,
    DEFAULT_INSTRUCTIONS,
    USER_AGENT_WORDS,
    default_consent,
    default_instructions,
)
from emogen.tasks.blocks import Condition, TaskBlock, fill_emotion
from emogen.tasks.protocol import conditions_of
from emogen.tasks.registry import DEFAULT_TASK, blocks_from, task_named

STUDY_SCHEMA = "emogen.study/1"
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")
_PARAM = re.compile(r"^[A-Za-z_][A-Za-z0-9_]{0,63}$")
#: A lab's identity name: it is a URL path segment of the viewer's GLB and a trial column.
_IDENTITY = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]{0,63}$")


class RatingConfig(_Strict):
    """The satisfaction rating of each trial's final face (``question`` fills in ``{EMOTION}``
    and ``{emotion}`` as the prompt does; the prompt stays above it)."""

    question: str = "How well does this face show the emotion you were asked for?"
    low_label: str = "not at all"
    high_label: str = "perfectly"
    points: Annotated[int, Field(ge=2, le=11)] = 7


class CompletionConfig(_Strict):
    """What the participant sees at the end: a code to paste, and/or a redirect."""

    message: str = "Thank you! You have completed the study."
    #: Completion code shown to the participant (e.g. Prolific's).
    code: str | None = None
    #: Redirect URL; ``{code}`` (or ``{completion_code}``) and ``{participant}`` (or
    #: ``{participant_id}``, or the study's ``participant_param`` in braces) are filled in.
    redirect_url: str | None = None

    @field_validator("redirect_url")
    @classmethod
    def _http(cls, v: str | None) -> str | None:
        if v is not None and not re.match(r"^https?://", v):
            raise ValueError(f"redirect_url must start with http:// or https://; got {v!r}")
        return v


class StudyConfig(_Strict):
    """One study: its trials, their order, the GA, and the participant's pages."""

    name: Annotated[str, Field(min_length=1)] = "study"
    title: str = "Making facial expressions"
    #: Study seed: a session's seed is a keyed hash of it and the participant id (the same
    #: participant, the same seed, whoever else came; None: a fresh seed per session, recorded).
    seed: Annotated[int, Field(ge=0, lt=2**63)] | None = None
    emotions: tuple[str, ...] = Field(default=("happy",), min_length=1)
    repetitions: Annotated[int, Field(ge=1, le=100)] = 1
    #: Identities, each crossed with every emotion: presets (female-light, …, female-dark-v3,
    #: male-…; older: female-dark, …-v2, generic; docs/study.md) or the lab's own.
    identities: tuple[str, ...] = Field(default=("generic",), min_length=1)
    #: The lab's own identities, ``[identity.NAME]`` tables: ``shape`` (generic, a rig preset or
    #: identity coefficients) plus any :class:`~emogen.appearance.Appearance` key.
    identity: dict[str, Identity] = Field(default_factory=dict)
    #: random (seeded per session), latin_square (balanced Williams rows), fixed.
    order: Literal["random", "latin_square", "fixed"] = "random"
    #: How a participant's Latin-square row is chosen: ``hash`` (a keyed hash of the participant
    #: id: balanced in expectation, the same row whoever came first) or ``arrival`` (exact: the
    #: k-th session of the study gets row k modulo the rows, under the database's lock).
    counterbalance: Literal["hash", "arrival"] = "hash"
    #: The order of the blocks: ``fixed`` (config order), ``latin_square`` (rows of a balanced
    #: Latin square over ``reordered_blocks``, assigned as ``counterbalance`` says) or ``random``
    #: (seeded per session): :mod:`emogen.study.block_order`.
    block_order: Literal["fixed", "latin_square", "random"] = "fixed"
    #: The blocks that trade places (their names; one run in the config): default every block.
    reordered_blocks: tuple[str, ...] = ()
    #: This study is the retest of the study of this name (same database): only participants
    #: who completed it take part, matched by id (:mod:`emogen.study.retest`).
    retest_of: str | None = None
    #: URL parameter carrying the participant id (e.g. Prolific's PROLIFIC_PID); also accepted:
    #: ``participant``. Without one, an id is generated (unless ``participant_required``).
    participant_param: str = "PROLIFIC_PID"
    #: Refuse sessions without a participant id in the link (a page says the link lacks it).
    participant_required: bool = False
    #: Who may continue a participant's session: ``link`` (the browser holding it: its session
    #: link or the consent page's key; another browser is refused) or ``participant_id`` (anyone
    #: opening the study with that id: for embedded studies, a reopened Prolific link in a new
    #: tab or after a crash continues the session — docs/jspsych.md says what it trusts).
    resume: Literal["link", "participant_id"] = "link"
    #: Emotion words the study means although ``emogen study check`` does not know them.
    custom_emotions: tuple[str, ...] = ()
    prompt: str = "Make the face look {EMOTION}"
    #: Default: :func:`default_consent`, its length estimated from the design (and, when
    #: ``collect_user_agent``, saying so).
    consent: str = DEFAULT_CONSENT
    #: Record the browser's user agent with each session (personal data: off by default; the
    #: default consent text then says it is recorded). Off: ``user_agent`` is NULL.
    collect_user_agent: bool = False
    instructions: str = DEFAULT_INSTRUCTIONS
    #: Show "Start again" (what it does is ga.init.on_reset: reinitialise or keep).
    allow_restart: bool = True
    #: Show corrected faces (paper Section III-A): the engines correct every population
    #: (combinational + lip/teeth collision correctives), the correctives' weights are stored
    #: after the shape weights, and the viewer / fallback PNGs draw the corrected face.
    correct: bool = True
    #: What participants see around each face: ``face`` or ``oval`` (the face through an oval
    #: on the background, hair, ears and neck hidden: :mod:`emogen.study.framing`).
    framing: Annotated[str, AfterValidator(check_framing)] = "face"
    #: Face model folder or GLB, and rig TOML (default: $EMOGEN_MODEL / the packaged rig).
    model: Path | None = None
    rig: Path | None = None
    #: SQLAlchemy URL; $EMOGEN_DATABASE_URL and --database-url win.
    database_url: str | None = None
    ga: GAConfig = GAConfig()
    rating: RatingConfig = RatingConfig()
    completion: CompletionConfig = CompletionConfig()
    #: ``[[blocks]]``: the study's blocks in order, each running one task (``task`` names it:
    #: :mod:`emogen.tasks.registry`); none: one block of the default task (the GA) made of the
    #: keys above.
    blocks: tuple[SerializeAsAny[TaskBlock], ...] = ()
    #: Web origins whose pages may call the participant API (jsPsych plugin, docs/jspsych.md):
    #: exact ``scheme://host[:port]``; none by default. Not part of the config hash.
    embed_origins: tuple[Annotated[str, AfterValidator(check_origin)], ...] = ()

    @field_validator("blocks", mode="before")
    @classmethod
    def _blocks(cls, v: Any) -> tuple[TaskBlock, ...]:
        return blocks_from(v)

    @field_validator("name")
    @classmethod
    def _name(cls, v: str) -> str:
        if not _NAME.fullmatch(v):
            raise ValueError(
                f"name must be 1-64 letters, digits, '_', '.', '-' (starting with a letter or "
                f"digit); got {v!r}"
            )
        return v

    @field_validator("retest_of")
    @classmethod
    def _retest(cls, v: str | None) -> str | None:
        if v is not None and not _NAME.fullmatch(v):
            raise ValueError(f"retest_of must be a study name; got {v!r}")
        return v

    @field_validator("participant_param")
    @classmethod
    def _param(cls, v: str) -> str:
        if not _PARAM.fullmatch(v):
            raise ValueError(f"participant_param must be a plain identifier; got {v!r}")
        return v

    @field_validator("emotions", "identities", "custom_emotions")
    @classmethod
    def _unique(cls, v: tuple[str, ...]) -> tuple[str, ...]:
        dup = sorted({x for x in v if v.count(x) > 1})
        if dup:
            raise ValueError(f"must not repeat entries; got {dup} more than once")
        if any(not x.strip() for x in v):
            raise ValueError("entries must not be empty")
        return v

    @field_validator("identity", mode="before")
    @classmethod
    def _own_identities(cls, v: Any) -> Any:
        if not isinstance(v, dict):
            return v
        out: dict[str, Any] = {}
        for name, table in v.items():
            if not _IDENTITY.fullmatch(str(name)):
                raise ValueError(
                    f"identity name must be 1-64 letters, digits, '_', '-' (starting with a "
                    f"letter or digit); got {name!r}"
                )
            if name in PRESETS:
                raise ValueError(
                    f"identity '{name}' is a preset; give the lab's own identity another name"
                )
            if isinstance(table, Identity):
                out[name] = table
                continue
            try:
                out[name] = identity_from_dict(name, table)
            except ConfigError as exc:
                raise ValueError(str(exc)) from None
        return out

    @field_serializer("identity")
    def _flat_identities(self, v: dict[str, Identity]) -> dict[str, Any]:
        """As written in the TOML: ``shape`` and the appearance keys side by side."""
        return {name: identity_table(ident) for name, ident in v.items()}

    @model_validator(mode="wrap")
    @classmethod
    def _default_consent(cls, data: Any, handler: ModelWrapValidatorHandler[StudyConfig]) -> Any:
        """No consent given: the default text with the length estimated from the design."""
        if not isinstance(data, dict):
            return handler(data)
        collects = data.get("collect_user_agent") is True
        given = "consent" in data
        if collects and data.get("consent", DEFAULT_CONSENT) == DEFAULT_CONSENT:
            data = {**data, "consent": DEFAULT_CONSENT_USER_AGENT}  # says so; checked below
        config = handler(data)
        if given:
            return config
        minutes = session_length(config.conditions(), config.ga.generations).words()
        consent = default_consent(minutes, user_agent=config.collect_user_agent)
        # validated again, not copied: StudyConfig(...) must get back the instance it fills
        return handler({**data, "consent": consent})

    @model_validator(mode="before")
    @classmethod
    def _instructions_say_the_tasks(cls, data: Any) -> Any:
        if isinstance(data, dict) and "instructions" not in data:
            text = default_instructions(data.get("blocks"))
            if text is not None:
                return {**data, "instructions": text}
        return data

    @model_validator(mode="after")
    def _consistent(self) -> StudyConfig:
        if self.collect_user_agent and not any(
            word in self.consent.lower() for word in USER_AGENT_WORDS
        ):
            raise ValueError(
                "collect_user_agent = true, but the study's own consent text does not tell "
                "participants: name the browser's 'user agent' in it (or leave consent out for "
                f"the default text that does); got consent = {self.consent[:80]!r}"
            )
        for k, block in enumerate(self.blocks):
            block.check(k + 1, self.emotions, self.blocks[:k])
        names = block_names_of(self.blocks)
        doubled = sorted({n for n in names if names.count(n) > 1})
        if doubled:
            raise ValueError(
                f"blocks: two blocks are named {', '.join(map(repr, doubled))}: the exports "
                "tell blocks apart by name (give each its own name)"
            )
        check_block_order(self)
        if self.retest_of == self.name:
            raise ValueError(
                f"retest_of = {self.name!r} names this study itself: a retest is a study of its "
                "own name (e.g. name = 'mystudy-retest', retest_of = 'mystudy')"
            )
        if self.n_trials > 500:
            raise ValueError(
                "a study must have at most 500 trials (a GA block: emotions × repetitions × "
                f"identities; a labelling block: its faces); got {self.n_trials}"
            )
        return self

    @property
    def n_trials(self) -> int:
        """How many trials a session has (a block's face table read without a count of its faces
        counts as 0 here: its rows are counted when the server reads the file)."""
        return len(self.conditions())

    def study_blocks(self) -> tuple[Any, ...]:
        """The blocks with the study's defaults filled in (each task's block says which:
        :meth:`emogen.tasks.blocks.TaskBlock.resolved`)."""
        blocks = self.blocks or (task_named(DEFAULT_TASK).block.model_validate({}),)
        return tuple(b.resolved(self) for b in blocks)

    def conditions(self, file_rows: dict[int, int] | None = None) -> list[Condition]:
        """Every trial in config order, block by block (``file_rows``: the number of rows of
        each block's face table, by block index, where its trials are its rows)."""
        return conditions_of(self.study_blocks(), self, file_rows or {})

    def identity_of(self, name: str) -> Identity:
        """The identity called ``name``: the lab's own, a preset, or else a rig shape preset of
        that name with the default appearance (``check_identities`` vets the names)."""
        if name in self.identity:
            return self.identity[name]
        return PRESETS.get(name) or Identity(shape=name)

    def study_identities(self) -> dict[str, Identity]:
        """Every identity the study shows, by name, in config order (blocks' included)."""
        return {name: self.identity_of(name) for name in self.all_identities()}

    def all_identities(self) -> tuple[str, ...]:
        """The names of every identity the study's blocks show, in config order."""
        names = dict.fromkeys(self.identities)
        for b in self.study_blocks():
            names.update(dict.fromkeys(b.identities or ()))
        return tuple(names)

    def ga_for(self, identity: str) -> GAConfig:
        """The GA config of a trial of ``identity``; the engine sees the identity's shape
        preset (coefficient shapes share the generic rig: gene space does not change)."""
        shape = self.identity_of(identity).shape
        return self.ga.model_copy(
            update={"identity": shape if isinstance(shape, str) else "generic"}
        )

    def prompt_for(self, emotion: str) -> str:
        return fill_emotion(self.prompt, emotion)

    def config_hash(self) -> str:
        """SHA-256 of the resolved config (canonical JSON): stamped on every exported row."""
        return hashlib.sha256(self.canonical_json().encode()).hexdigest()

    def canonical_json(self) -> str:
        data = self.model_dump(mode="json")
        if not data["identity"]:  # studies without their own identities keep their hash
            del data["identity"]
        if not data["collect_user_agent"]:  # nor do studies that do not collect user agents
            del data["collect_user_agent"]
        if not data["blocks"]:  # nor studies of one default-task block (written before blocks)
            del data["blocks"]
        for key, default in (
            ("custom_emotions", []),
            ("participant_required", False),
            ("counterbalance", "hash"),
            ("framing", "face"),
            ("block_order", "fixed"),
            ("reordered_blocks", []),
            ("retest_of", None),
            ("resume", "link"),
        ):
            if data[key] == default:  # studies without them keep their hash
                del data[key]
        del data["embed_origins"]  # where it may be embedded is no part of what people do
        return json.dumps(data, sort_keys=True, separators=(",", ":"))


def study_from_dict(data: dict[str, object], source: str = "(study config)") -> StudyConfig:
    return validate_config(StudyConfig, dict(data), source)


def load_study_config(path: Path) -> StudyConfig:
    """A study config from TOML; relative ``model``/``rig`` paths are relative to the file."""
    path = Path(path)
    data = read_toml(path)
    for key in ("model", "rig"):
        value = data.get(key)
        if isinstance(value, str) and value and not Path(value).expanduser().is_absolute():
            data[key] = str((path.parent / value).resolve())
    for block in data.get("blocks") or ():
        for key in ("file", "others_fallback"):
            value = block.get(key) if isinstance(block, dict) else None
            if isinstance(value, str) and value and not Path(value).expanduser().is_absolute():
                block[key] = str((path.parent / value).resolve())
    if "ga" in data and isinstance(data["ga"], dict):
        init = data["ga"].get("init")
        if isinstance(init, dict) and isinstance(init.get("fixed_file"), str):
            ff = Path(init["fixed_file"]).expanduser()
            if not ff.is_absolute():
                init["fixed_file"] = str((path.parent / ff).resolve())
    return study_from_dict(data, str(path))


def demo_study_path() -> Path:
    """The packaged demo study (``emogen/data/demo_study.toml``)."""
    return Path(__file__).resolve().parents[1] / "data" / "demo_study.toml"
