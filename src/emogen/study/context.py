"""What a study service knows of its study: the config, the rig and the study row it records to."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from sqlalchemy import select
from sqlalchemy.exc import IntegrityError

from emogen import __version__
from emogen.errors import ConfigError
from emogen.model.rig import Rig
from emogen.study.config import StudyConfig
from emogen.study.storage import Store
from emogen.study.tables import StudyRow, dumps, utcnow
from emogen.tasks.blocks import Condition

if TYPE_CHECKING:
    from emogen.model.face import FaceModel


@dataclass(frozen=True)
class StudyContext:
    """The config, the rig, the model's name and hash, the study row's id and its columns,
    and the study's trials (conditions)."""

    config: StudyConfig
    rig: Rig
    model_name: str
    model_hash: str
    study_id: int
    gene_names: tuple[str, ...]
    weight_names: tuple[str, ...]
    #: every trial of a session in config order (``StudyConfig.conditions``, its blocks' face
    #: tables counted)
    conditions: tuple[Condition, ...] = ()
    #: study rows of this name and design (texts may differ) whose sessions this one continues,
    #: and every row of this name (a participant id takes part once): :mod:`~emogen.study.versions`
    same_design: tuple[int, ...] = ()
    all_versions: tuple[int, ...] = ()

    @property
    def accepted(self) -> tuple[int, ...]:
        """The study rows whose sessions this server runs (its own, and its design's)."""
        return self.same_design or (self.study_id,)


def accepted_hashes(model_hash: str, model: FaceModel | None) -> frozenset[str]:
    """The recorded model hashes that mean this model: its hash and, for the loaded model, the
    version-1 hash of studies recorded before version 2 (:mod:`emogen.model.model_hash`;
    needed by tests/study/test_recorded_before.py::test_recorded_study_replays_exactly)."""
    if model is not None and model.model_hash == model_hash and model.legacy_model_hash:
        from emogen.model.load import records_of

        if records_of(model, model.legacy_model_hash):  # not for a rig with reach shapes
            return frozenset({model_hash, model.legacy_model_hash})
    return frozenset({model_hash})


def recorded_model_hash(store: Store, config: StudyConfig) -> str | None:
    """The model hash the study row of this config recorded (None: not registered yet)."""
    with store.read() as db:
        return db.scalar(
            select(StudyRow.model_hash).where(
                StudyRow.name == config.name, StudyRow.config_hash == config.config_hash()
            )
        )


def register_study(
    store: Store,
    config: StudyConfig,
    *,
    model_name: str,
    model_hash: str,
    gene_names: tuple[str, ...],
    weight_names: tuple[str, ...],
    aliases: frozenset[str] = frozenset(),
) -> int:
    """The id of the study row of this config (made if new); a different model is an error.

    aliases : other hashes of the same model (the version-1 hash older studies recorded)."""
    chash = config.config_hash()
    for _ in range(2):
        try:
            with store.write() as db:
                row = db.scalar(
                    select(StudyRow).where(
                        StudyRow.name == config.name, StudyRow.config_hash == chash
                    )
                )
                if row is None:
                    row = StudyRow(
                        name=config.name,
                        config_hash=chash,
                        config_json=config.canonical_json(),
                        model_name=model_name[:128],
                        model_hash=model_hash,
                        gene_names=dumps(list(gene_names)),
                        weight_names=dumps(list(weight_names)),
                        package_version=__version__,
                        created_at=utcnow(),
                    )
                    db.add(row)
                    db.flush()
                elif row.model_hash != model_hash and row.model_hash not in aliases:
                    raise ConfigError(
                        f"study '{config.name}' (config {chash[:12]}) was recorded with model "
                        f"{row.model_hash[:16]}…; this server loaded {model_hash[:16]}…: "
                        "serve it with the same model, or rename the study"
                    )
                return row.id
        except IntegrityError:  # another process registered it at the same moment
            continue
    raise ConfigError(f"could not register study '{config.name}'")  # pragma: no cover
