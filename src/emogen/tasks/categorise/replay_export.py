"""Replay of categorise trials from exported files alone (``emogen study replay --from-export``).

What the export lets us rebuild, from the trials' recorded seeds (``trials``) and the faces
shown (``categorise_responses``), is rebuilt and compared:

* the labels offered, in their order: drawn again from each trial's seed (exact);
* a face with genes (random faces; own and others' faces): its weights are its genes expanded
  by the rig and corrected again (within floating-point rounding, :mod:`emogen.tasks.rounding`);
* which faces a block drew, and in which trial each went: the block's draw is replayed from its
  trials' seeds in the order it was made (own, others', file, random faces): the random faces'
  genes, kinds and identities, and the face table's rows (when the table is readable here);
* a face table's face: its weights are the table's row.

What the export cannot rebuild is said, with why, and never passes as checked: which of the
participant's own faces, and which other participants' faces, a block drew (those faces are
the records of the task that made them, and the pool of others' faces depends on the sessions
completed when the block started, which no table records); and so the file and random faces a
block drew after others' faces (the draw's generator passed through that pool first).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from emogen.errors import EmoGenError
from emogen.tasks.categorise.block import CategoriseBlock
from emogen.tasks.categorise.faces import FileFaces, read_file_faces
from emogen.tasks.categorise.sources import label_order, pick_rows, random_faces
from emogen.tasks.protocol import ExportedStudy, Replayed, TaskEnv
from emogen.tasks.rounding import WEIGHT_TOLERANCE, weight_deviation, within_rounding

#: the export table a categorise replay reads
TABLES = ("categorise_responses",)
#: the order a block draws its faces in (:class:`emogen.tasks.categorise.draw.BlockDraw`)
DRAW_ORDER = ("own", "other", "file", "random")


@dataclass
class Shown:
    """One trial's exported face and its replay."""

    row: dict[str, Any]
    where: str
    done: Replayed


def replay_exported(env: TaskEnv, study: ExportedStudy) -> dict[int, list[Replayed]]:
    """Every exported categorise trial of ``study.sessions``: by session id, in trial order."""
    trials = study.trials_of("categorise")
    if trials.empty:
        return {}
    lacking = study.missing("categorise", TABLES)
    if lacking is not None:
        return lacking
    shown = study.tables["categorise_responses"].set_index(["session_id", "trial"], drop=False)
    out: dict[int, list[Replayed]] = {}
    for (sid, k), block_trials in trials.groupby(["session_id", "block"], sort=True):
        block = study.config.study_blocks()[int(k)]
        faces = []
        for t in block_trials.sort_values("condition").to_dict("records"):
            key = (int(t["session_id"]), int(t["trial"]))
            where = f"session {key[0]} trial {key[1] + 1}"
            if key not in shown.index:
                if str(t["status"]) in ("active", "done"):
                    out.setdefault(key[0], []).append(
                        Replayed(problems=[f"{where}: shown, but its face is not exported"])
                    )
                continue  # the block not reached yet: nothing shown
            row = shown.loc[key].to_dict()
            faces.append(Shown(row, f"{where} ({row['source']} face)", Replayed()))
            _check_face(env, study, block, int(t["seed"]), faces[-1])
        if faces and isinstance(block, CategoriseBlock):
            _check_draw(env, study, int(k), block, block_trials, faces)
        for f in sorted(faces, key=lambda f: int(f.row["trial"])):
            out.setdefault(int(sid), []).append(f.done)
    return {sid: out[sid] for sid in sorted(out)}


def _compare(face: Shown, what: str, recorded: Any, rebuilt: Any, names: list[str]) -> None:
    a = np.asarray(recorded, dtype=np.float64)
    b = np.asarray(rebuilt, dtype=np.float64)
    if a.shape != b.shape:
        face.done.problems.append(f"{face.where}: {what}: {a.size} recorded, {b.size} rebuilt")
        return
    worst = weight_deviation(a, b)
    face.done.deviation = max(face.done.deviation, worst)
    if not within_rounding(worst):
        i = int(np.argmax(np.where(a == b, 0.0, np.abs(a - b))))
        face.done.problems.append(
            f"{face.where}: {what}: recorded and rebuilt differ by up to {worst:.3g} "
            f"(tolerance {WEIGHT_TOLERANCE:g}); at {names[i]}: recorded {a[i]:.12g}, "
            f"rebuilt {b[i]:.12g}"
        )


def _check_face(env: TaskEnv, study: ExportedStudy, block: Any, seed: int, face: Shown) -> None:
    """The trial's labels offered and its face's weights against its genes."""
    done, row = face.done, face.row
    if not isinstance(block, CategoriseBlock):
        done.problems.append(f"{face.where}: its block in the config is not a categorise block")
        return
    offered = label_order(block.labels or (), np.random.default_rng(seed))
    recorded = str(row["labels"]).split("|")
    done.checked["label orders"] = 1
    if recorded != offered:
        done.problems.append(
            f"{face.where}: labels recorded {recorded}, the trial's seed gives {offered}"
        )
    genes = np.asarray([row[f"g_{g}"] for g in study.genes], dtype=np.float64)
    weights = np.asarray([row[f"w_{w}"] for w in study.weights], dtype=np.float64)
    if np.isnan(genes).all():
        return  # a face table's face: checked against its row with the block's draw
    done.stimuli += 1
    done.checked["categorised faces"] = 1
    shapes = study.rig.expand(genes[None, :], study.config.ga.eye_motion)
    corrector = env.correctors(str(row["identity"]))
    full = shapes[0]
    if corrector is not None:
        _, extra = corrector(shapes)
        full = np.concatenate([full, np.asarray(extra, dtype=np.float64).reshape(-1)])
    _compare(face, "w_ columns (its weights from its genes)", weights, full, study.weights)


def _check_draw(
    env: TaskEnv,
    study: ExportedStudy,
    k: int,
    block: CategoriseBlock,
    trials: pd.DataFrame,
    faces: list[Shown],
) -> None:
    """The block's draw replayed from its trials' seeds, source by source in the order it was
    made, as far as the export allows."""
    seeds = [int(s) for s in trials.sort_values("condition")["seed"]]
    rng = np.random.default_rng(seeds)
    by_source: dict[str, list[Shown]] = {}
    for f in faces:  # in condition order
        by_source.setdefault(str(f.row["source"]), []).append(f)
    drawable = True  # the generator is where the draw had it
    for source in DRAW_ORDER:
        mine = by_source.get(source, [])
        if not mine:
            continue
        if source == "own":
            _unchecked(
                mine,
                "which of the participant's own faces each shows is not re-drawn: "
                "the faces a session made are the records of the task that made them",
            )
        elif source == "other":
            _unchecked(
                mine,
                "which other participants' faces they show is not re-drawn: the "
                "draw depends on the sessions completed when the block started, which "
                "the export does not record",
            )
            drawable = False
        elif not drawable:
            _unchecked(
                mine,
                f"which {source} faces they show is not re-drawn: the block drew them "
                "after others' faces, whose draw cannot be replayed",
            )
        elif source == "file":
            _check_file(env, study, k, block, rng, mine)
        else:
            _check_random(env, study, block, rng, mine)


def _unchecked(faces: list[Shown], why: str) -> None:
    """One line for a block's faces of one source that could not be checked (on the first
    of them; every trial named)."""
    trials = sorted(int(f.row["trial"]) + 1 for f in faces)
    source = str(faces[0].row["source"])
    what = f"trial {trials[0]}" if len(trials) == 1 else f"trials {_spans(trials)}"
    count = f"{len(faces)} {source} face{'s' if len(faces) > 1 else ''}"
    session = int(faces[0].row["session_id"])
    faces[0].done.unchecked.append(f"session {session} {what} ({count}): {why}")


def _spans(numbers: list[int]) -> str:
    """1, 2, 3, 5 → "1–3, 5"."""
    spans: list[list[int]] = []
    for n in numbers:
        if spans and n == spans[-1][1] + 1:
            spans[-1][1] = n
        else:
            spans.append([n, n])
    return ", ".join(str(a) if a == b else f"{a}–{b}" for a, b in spans)


def _identities(env: TaskEnv, block: CategoriseBlock) -> tuple[str, ...]:
    return tuple(block.identities or env.config.identities)


def _check_random(
    env: TaskEnv,
    study: ExportedStudy,
    block: CategoriseBlock,
    rng: np.random.Generator,
    faces: list[Shown],
) -> None:
    genes, made = random_faces(
        study.rig,
        study.config.ga,
        kind=block.random_kind,
        n=len(faces),
        genes_range=block.random_genes,
        rng=rng,
    )
    idents = _identities(env, block)
    for j, f in enumerate(faces):
        f.done.checked["faces re-drawn"] = 1
        recorded = [f.row[f"g_{g}"] for g in study.genes]
        _compare(f, "g_ columns (the face drawn)", recorded, genes[j], study.genes)
        for what, got, rebuilt in (
            ("source_label", f.row["source_label"], made[j]),
            ("identity", f.row["identity"], idents[j % len(idents)]),
        ):
            if str(got) != rebuilt:
                f.done.problems.append(f"{f.where}: {what} recorded {got}, rebuilt {rebuilt}")


def _check_file(
    env: TaskEnv,
    study: ExportedStudy,
    k: int,
    block: CategoriseBlock,
    rng: np.random.Generator,
    faces: list[Shown],
) -> None:
    """The face table's rows the block drew (when the table is here), and their weights."""
    path = block.file
    table: FileFaces | None = None
    why = f"its face table {path} is not here"
    if path is not None and Path(path).exists():
        try:
            table = read_file_faces(Path(path), env.ctx, f"blocks[{k + 1}].file")
        except EmoGenError as exc:
            why = f"its face table cannot be read: {exc}"
    if table is None:
        _unchecked(faces, f"which rows of the face table they show is not re-drawn: {why}")
        return
    rows = pick_rows(len(table.weights), len(faces), rng)
    idents = _identities(env, block)
    n = table.weights.shape[1]  # its shape weights (then the correctives computed for them)
    for j, f in enumerate(faces):
        f.done.checked["faces re-drawn"] = 1
        f.done.stimuli += 1
        got = None if pd.isna(f.row["source_row"]) else int(f.row["source_row"])
        if got != rows[j]:
            f.done.problems.append(f"{f.where}: source_row recorded {got}, rebuilt {rows[j]}")
            continue
        identity = table.identities[rows[j]] or idents[j % len(idents)]
        if str(f.row["identity"]) != identity:
            f.done.problems.append(
                f"{f.where}: identity recorded {f.row['identity']}, rebuilt {identity}"
            )
        names = study.weights[:n]
        recorded = [f.row[f"w_{w}"] for w in names]
        _compare(f, "w_ columns (the table's row)", recorded, table.weights[rows[j]], names)
