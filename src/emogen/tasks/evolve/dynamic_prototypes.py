"""Participants' dynamic prototypes drawn for the report: per block and emotion an animated WebP
in which every participant's prototype plays in sync beside the emotion's mean and median, and
key-frame sheets for print (PNG).

A participant's dynamic prototype of an emotion is the mean, at each frame time, of the shape
weights of their final faces of it (one final face: that face's clip exactly); the emotion's
mean and median are the mean and the median over participants of their prototypes' weights at
each time (participants weigh equally). Each is drawn on the identity most of its faces showed,
through the study's framing, corrected frame by frame when the study corrected its faces — the
frames of ``emogen render clip`` (:mod:`emogen.tasks.evolve.dynamic_clip`): :data:`FPS` frames a
second, :data:`TILE_PX` pixels a face, the clip then its hold at rest, looped as the page loops
it. Key frames are the :data:`KEY_FRAMES` frames nearest evenly spaced times over the clip.
"""

from __future__ import annotations

import json
import re
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from emogen.errors import ConfigError
from emogen.render.animation import write_animation
from emogen.render.images import contact_sheet, save_png
from emogen.tasks.evolve.block import Dynamic
from emogen.tasks.evolve.dynamic_clip import (
    clip_genome,
    clip_times,
    clip_weights,
    render_frames,
)

if TYPE_CHECKING:
    from emogen.ga.genome import DynamicGenome
    from emogen.model.rig import Rig

#: Frames a second and pixels a face of the report's clips; key frames a clip on the sheets;
#: participants a key-frame sheet (one row each; more: further sheets); faces a row of the
#: animation.
FPS = 12.0
TILE_PX = 128
KEY_FRAMES = 6
SHEET_ROWS = 12
GRID_COLUMNS = 6
#: A face's genes in a ``face_curves`` row, in the genome's order (docs/ga.md).
GENE_COLUMNS = ("amplitude", "onset", "acceleration", "peak", "deceleration", "offset")


@dataclass(frozen=True)
class StudyLook:
    """How a study showed its dynamic faces: its config (``config_json``) and framing."""

    config: dict[str, Any]
    framing: str

    @classmethod
    def of(cls, study: pd.DataFrame | None) -> StudyLook:
        if study is None or study.empty or "config_json" not in study.columns:
            raise ConfigError("the export has no study table with its config_json")
        config = json.loads(str(study["config_json"].iloc[0]))
        framing = str(study["framing"].iloc[0]) if "framing" in study.columns else "face"
        return cls(config, framing)

    @property
    def correct(self) -> bool:
        return bool(self.config.get("correct", True))

    @property
    def eye_motion(self) -> bool:
        return bool(self.config.get("ga", {}).get("eye_motion", True))

    def genome(self, block: int) -> DynamicGenome:
        """The genome of the study's block ``block`` (its position in ``blocks``)."""
        blocks = self.config.get("blocks", [])
        spec = blocks[block].get("dynamic") if 0 <= block < len(blocks) else None
        if spec is None:
            raise ConfigError(f"block {block} of the study's config has no dynamic faces")
        return Dynamic(**spec).genome()


@dataclass(frozen=True)
class Tile:
    """One face of a drawing: its label, whose prototype (None: the emotion's mean or median),
    the identity it is drawn on, how many final faces it averages, and its shape weights at the
    frame times (T, S)."""

    label: str
    participant_id: str | None
    identity: str
    n_faces: int
    weights: np.ndarray


def face_genes(rows: pd.DataFrame, names: Sequence[str], genome: DynamicGenome) -> np.ndarray:
    """One face's genes (K, 6) in the rig's gene order from its ``face_curves`` rows (genes
    without a row: at rest); its recorded clip length and latencies must be ``genome``'s."""
    genes = np.zeros((len(names), len(GENE_COLUMNS)))
    index = {n: i for i, n in enumerate(names)}
    unknown = sorted(set(rows["gene"].astype(str)) - set(index))
    if unknown:
        raise ConfigError(f"genes {unknown} of the export are not genes of the face model's rig")
    at = rows["gene"].astype(str).map(index).to_numpy()
    genes[at] = rows[list(GENE_COLUMNS)].to_numpy(dtype=np.float64)
    clip_genome(rows.assign(gene_index=at), genes, genome.clip_s, 0.0, genome.min_segment_s)
    return genes


def _most_shown(identities: pd.Series) -> str:
    counts = Counter(identities.astype(str))
    return min(counts, key=lambda name: (-counts[name], name))


def emotion_tiles(
    curves: pd.DataFrame,
    rig: Rig,
    genome: DynamicGenome,
    times: np.ndarray,
    eye_motion: bool,
) -> list[Tile]:
    """The tiles of one block and emotion (its rows of ``final_curves`` with ``identity``):
    the mean, the median, then each participant's prototype (by participant id)."""
    names = rig.gene_names(eye_motion)
    people = []
    for who, rows in curves.groupby("participant_id", sort=True):
        faces = [face_genes(f, names, genome) for _, f in rows.groupby(["session_id", "trial"])]
        w = clip_weights(rig, np.stack(faces), genome, times, eye_motion).mean(axis=0)
        faces_shown = rows.drop_duplicates(["session_id", "trial"])["identity"]
        people.append(Tile(str(who), str(who), _most_shown(faces_shown), len(faces), w))
    stack = np.stack([p.weights for p in people])
    identity = _most_shown(curves.drop_duplicates(["session_id", "trial"])["identity"])
    n = sum(p.n_faces for p in people)
    return [
        Tile(f"mean of {len(people)}", None, identity, n, stack.mean(axis=0)),
        Tile(f"median of {len(people)}", None, identity, n, np.median(stack, axis=0)),
        *people,
    ]


def key_frames(times: np.ndarray, clip_s: float, n: int = KEY_FRAMES) -> np.ndarray:
    """Indices of the frames nearest ``n`` times evenly over the clip."""
    want = np.linspace(0.0, clip_s, n)
    return np.abs(times[None, :] - want[:, None]).argmin(axis=1)


def frame_times(genome: DynamicGenome) -> np.ndarray:
    """The report's frame times: the clip at :data:`FPS`, then its hold at rest."""
    return clip_times(genome, FPS, hold=True)


def render_tiles(tiles: list[Tile], renderer_for: Any, correct: bool) -> np.ndarray:
    """Every tile's frames (n_tiles, T, H, W, 3), each tile on its identity's renderer
    (``renderer_for(identity)``)."""
    drawn: dict[int, np.ndarray] = {}
    for identity in dict.fromkeys(t.identity for t in tiles):
        which = [i for i, t in enumerate(tiles) if t.identity == identity]
        weights = np.stack([tiles[i].weights for i in which])
        drawn |= zip(which, render_frames(renderer_for(identity), weights, correct), strict=True)
    return np.stack([drawn[i] for i in range(len(tiles))])


def animation(images: np.ndarray, labels: list[str], background: Any) -> np.ndarray:
    """The frames (T, H, W, 3) of tiles' clips (n, T, h, w, 3) playing side by side, labelled,
    :data:`GRID_COLUMNS` a row, with the ICT-FaceKit notice."""
    return np.stack(
        [
            contact_sheet(images[:, k], labels, columns=GRID_COLUMNS, background=background)
            for k in range(images.shape[1])
        ]
    )


def key_sheet(
    images: np.ndarray, labels: list[str], keys: np.ndarray, times: np.ndarray, background: Any
) -> np.ndarray:
    """A sheet of key frames: one row per tile (``images`` (n, T, h, w, 3)), its ``keys``
    frames left to right, the first labelled with the tile's label, the others with their
    times."""
    cells = images[:, keys].reshape(-1, *images.shape[2:])
    text = [
        label if j == 0 else f"{times[k]:.2f} s" for label in labels for j, k in enumerate(keys)
    ]
    return contact_sheet(cells, text, columns=len(keys), background=background)


def file_part(name: object) -> str:
    """A block's or emotion's name as part of a file name."""
    return re.sub(r"[^A-Za-z0-9_-]+", "-", str(name)).strip("-") or "x"


@dataclass
class Drawing:
    """What :func:`draw_block` drew: the files (path, caption), in the report's order, and
    one row per tile and emotion (where the tile is)."""

    figures: list[tuple[Path, str]]
    tiles: list[dict[str, Any]]


def draw_block(
    curves: pd.DataFrame,
    look: StudyLook,
    rig: Rig,
    renderer_for: Any,
    folder: Path,
) -> Drawing:
    """One block's drawings (``curves``: its rows of ``final_curves``) in ``folder``: the
    emotions' mean and median key frames on one sheet, then per emotion the animation of every
    tile and the participants' key-frame sheets (:data:`SHEET_ROWS` a sheet)."""
    block, name = int(curves["block"].iloc[0]), str(curves["block_name"].iloc[0])
    genome = look.genome(block)
    times = frame_times(genome)
    keys = key_frames(times, genome.clip_s)
    stem = f"dynamic_{file_part(name)}"
    figures: list[tuple[Path, str]] = []
    rows: list[dict[str, Any]] = []
    summaries, summary_labels = [], []
    for emotion, part in curves.groupby("emotion", sort=True):
        tiles = emotion_tiles(part, rig, genome, times, look.eye_motion)
        images = render_tiles(tiles, renderer_for, look.correct)
        background = renderer_for(tiles[0].identity).look.background_srgb
        labels = [t.label for t in tiles]
        clip = folder / f"{stem}_{file_part(emotion)}.webp"
        frames = animation(images, labels, background)
        write_animation(clip, frames, FPS, comment=f"EmoGen dynamic prototypes: {name}, {emotion}")
        figures.append((clip, _clip_caption(str(emotion), tiles, look)))
        for page, start in enumerate(range(2, len(tiles), SHEET_ROWS)):
            sheet = folder / f"{stem}_{file_part(emotion)}_keys_{page + 1}.png"
            chunk = slice(start, start + SHEET_ROWS)
            save_png(sheet, key_sheet(images[chunk], labels[chunk], keys, times, background))
            figures.append((sheet, f"The participants' {emotion} prototypes, one row each "
                            f"(participants {start - 1}–{min(start + SHEET_ROWS, len(tiles)) - 2} "
                            f"of {len(tiles) - 2}, by id); {_key_text(keys, times)}."))  # fmt: skip
        summaries.append(images[:2])
        summary_labels += [f"{emotion}, {t.label}" for t in tiles[:2]]
        rows += [_tile_row(name, str(emotion), i, t, clip) for i, t in enumerate(tiles)]
    means = folder / f"{stem}_keys.png"
    save_png(means, key_sheet(np.concatenate(summaries), summary_labels, keys, times, background))
    figures.insert(0, (means, f"Block {name}: each emotion's mean and median dynamic prototype "
                   f"across participants, one row each; {_key_text(keys, times)}."))  # fmt: skip
    return Drawing(figures, rows)


def _key_text(keys: np.ndarray, times: np.ndarray) -> str:
    shown = ", ".join(f"{times[k]:.2f}" for k in keys)
    return f"key frames at {shown} s left to right (the first column labelled with the row)"


def _clip_caption(emotion: str, tiles: list[Tile], look: StudyLook) -> str:
    corrected = (
        "corrected frame by frame" if look.correct else "uncorrected, as the study showed them"
    )
    return (
        f"{emotion}: every participant's dynamic prototype playing in sync ({len(tiles) - 2} "
        f"participants, by id), after the mean and the median across them; {FPS:g} frames/s, "
        f"the clip then its hold at rest, looped; {corrected}."
    )


def _tile_row(block: str, emotion: str, i: int, tile: Tile, clip: Path) -> dict[str, Any]:
    return {
        "block_name": block,
        "emotion": emotion,
        "position": i,
        "label": tile.label,
        "participant_id": tile.participant_id,
        "identity": tile.identity,
        "n_faces": tile.n_faces,
        "animation": clip.name,
    }
