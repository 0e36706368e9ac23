"""`emogen render clip`: a face that moves, from its curves, to an animation, frames and a sheet.

emogen render clip curves.csv --out clip.webp --out clip.mp4 --sheet keys.png
emogen render clip face_curves.csv --select session_id=3 --select face_id=12 --out frames/

The curves are one face's rows of a study export's ``face_curves`` table (docs/data.md): a
``gene`` column and its ``amplitude``, ``onset``, ``acceleration``, ``peak``,
``deceleration``, ``offset`` (each in [0, 1]); genes without a row stay at rest. The weight of a
gene at time t is docs/ga.md's curve ("Dynamic faces"); the frames are the clip at ``--fps``
(0, 1/fps, …, clip_s), then the hold at rest, as the study page loops it.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from emogen.cli.options import JsonOpt, ModelOpt, RigOpt, at_least, show_result
from emogen.cli.outputs import ForceOpt, output_folder
from emogen.cli.render_setup import (
    BackgroundOpt,
    CorrectOpt,
    FovOpt,
    Framing,
    FramingOpt,
    IdentityOpt,
    PlainOpt,
    SizeOpt,
    SupersampleOpt,
    image_metadata,
    load_render_model,
    look_record,
    make_renderer,
    png_file,
    render_appearance,
)

if TYPE_CHECKING:
    import numpy as np
    import pandas as pd

    from emogen.model.rig import Rig

#: Columns that tell faces apart in an export's ``face_curves`` table.
FACE_KEY = ("study", "session_id", "trial", "attempt", "generation", "face_id")
_COLUMNS = ("gene", "amplitude", "onset", "acceleration", "peak", "deceleration", "offset")


def read_curves(path: Path, rig: Rig, select: list[str] | None) -> tuple[np.ndarray, pd.DataFrame]:
    """One face's genes (K, 6) in the rig's gene order (``amplitude`` then the timing; genes
    without a row: 0) from a ``face_curves`` CSV, after ``--select COLUMN=VALUE`` filters;
    and the face's rows (for their ``clip_s`` and latencies)."""
    import difflib

    import numpy as np
    import pandas as pd

    from emogen.errors import ConfigError

    if not path.is_file():
        raise ConfigError(f"curves file {path} does not exist (a face_curves CSV of an export)")
    table = pd.read_csv(path, dtype={"gene": "string"})
    missing = [c for c in _COLUMNS if c not in table.columns]
    if missing:
        raise ConfigError(
            f"{path} has no column {', '.join(missing)} (a face's curves need {', '.join(_COLUMNS)})"
        )
    for item in select or []:
        column, sep, value = item.partition("=")
        if not sep or column not in table.columns:
            raise ConfigError(
                f"--select {item!r}: give COLUMN=VALUE with a column of {path.name} "
                f"({', '.join(map(str, table.columns))})"
            )
        table = table[table[column].astype(str) == value.strip()]
        if table.empty:
            raise ConfigError(f"--select {item!r}: no row of {path.name} has {column} = {value}")
    keys = [c for c in FACE_KEY if c in table.columns]
    faces = table.groupby(keys).ngroups if keys else 1
    if faces > 1:
        raise ConfigError(
            f"{path.name} holds {faces} faces (told apart by {', '.join(keys)}); pick one with "
            "--select COLUMN=VALUE, e.g. --select session_id=1 --select generation=3 "
            "--select face_id=2"
        )
    names = rig.gene_names(True)
    genes = np.zeros((len(names), len(_COLUMNS) - 1))
    seen: list[int] = []
    for row in table.itertuples(index=False):
        gene = str(row.gene)
        if gene not in names:
            close = difflib.get_close_matches(gene, names, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ConfigError(f"{path.name}: gene {gene!r} is not a gene of rig {rig.name!r}{hint}")
        if names.index(gene) in seen:
            raise ConfigError(
                f"{path.name}: gene {gene!r} has two rows; one face has one row a gene"
            )
        seen.append(names.index(gene))
        for j, column in enumerate(_COLUMNS[1:]):
            value = getattr(row, column)
            if not (isinstance(value, int | float) and 0.0 <= float(value) <= 1.0):
                raise ConfigError(
                    f"{path.name}: gene {gene!r}: {column} must be a number in [0, 1]; got {value!r}"
                )
            genes[names.index(gene), j] = float(value)
    return genes, table.assign(gene_index=seen)


def clip(
    curves: Annotated[Path, typer.Argument(help="One face's curves: a face_curves CSV.")],
    out: Annotated[
        list[Path] | None,
        typer.Option(
            "--out",
            "-o",
            help="An animation (.webp lossless, .gif, .mp4) or a folder for the frames as PNGs; "
            "repeatable.",
        ),
    ] = None,
    sheet: Annotated[
        Path | None, typer.Option("--sheet", help="A contact sheet of key frames (.png).")
    ] = None,
    sheet_frames: Annotated[
        int, typer.Option("--sheet-frames", callback=at_least(2), help="Key frames on the sheet.")
    ] = 11,
    select: Annotated[
        list[str] | None,
        typer.Option("--select", help="COLUMN=VALUE: the rows of one face; repeatable."),
    ] = None,
    fps: Annotated[float, typer.Option("--fps", help="Frames a second.")] = 30.0,
    hold: Annotated[
        bool, typer.Option("--hold/--no-hold", help="End with the hold at rest (as the page).")
    ] = True,
    clip_s: Annotated[
        float | None,
        typer.Option("--clip-s", help="The clip's length (s) when the file has no clip_s."),
    ] = None,
    hold_s: Annotated[float, typer.Option("--hold-s", help="The hold at rest (s).")] = 0.75,
    min_segment_s: Annotated[
        float, typer.Option("--min-segment-s", help="The study's min_segment_s (docs/ga.md).")
    ] = 0.08,
    identity: IdentityOpt = None,
    size: SizeOpt = None,
    background: BackgroundOpt = None,
    fov: FovOpt = None,
    supersample: SupersampleOpt = None,
    correct: CorrectOpt = False,
    framing: FramingOpt = Framing.face,
    plain: PlainOpt = False,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
    force: ForceOpt = False,
    as_json: JsonOpt = False,
) -> None:
    """A face that moves: its clip as an animation, its frames as PNGs, a sheet of key frames
    (each frame rendered as a still face; ``--correct``: each corrected on its own)."""
    import numpy as np

    from emogen.render.images import save_png
    from emogen.tasks.evolve import dynamic_clip as dc

    _check_outputs(out, sheet)  # before any work
    model, name, ident = load_render_model(model_path, rig, identity)
    genes, rows = read_curves(curves, model.rig, select)
    genome = dc.clip_genome(rows, genes, clip_s, hold_s, min_segment_s)
    weights = dc.clip_weights(model.rig, genes, genome, times := dc.clip_times(genome, fps, hold))
    appearance = render_appearance(model, ident, plain)
    look = look_record(name, ident, appearance, framing)
    record = {**look, "clip": genome.to_dict(), "fps": fps, "corrected": correct}
    key_t = np.linspace(0.0, genome.clip_s, sheet_frames)
    with make_renderer(
        model, size, background, fov, supersample, appearance=appearance, framing=framing
    ) as r:
        images = dc.render_frames(r, weights, correct)
        keys = None
        if sheet is not None:
            key_w = dc.clip_weights(model.rig, genes, genome, key_t)
            keys = r.sheet(key_w, [f"{t:.3f} s" for t in key_t], columns=min(sheet_frames, 6),
                           correct=correct)  # fmt: skip
    wrote = [_write(path, images, times, weights, model, record, force) for path in out or []]
    if keys is not None and sheet is not None:
        save_png(sheet, keys, image_metadata(model, None, key_times_s=key_t.tolist(), **record))
        wrote.append(str(sheet))
    show_result(
        as_json,
        {"wrote": wrote, "frames": len(images), "fps": fps, "clip_s": genome.clip_s},
        [f"wrote {w}" for w in wrote] + [f"{len(images)} frames at {fps:g}/s"],
    )


def _check_outputs(out: list[Path] | None, sheet: Path | None) -> None:
    """An animation's suffix, the sheet's .png, and something to write."""
    from emogen.errors import ConfigError
    from emogen.render.animation import animation_format

    if not out and sheet is None:
        raise ConfigError("give --out (an animation or a folder) and/or --sheet")
    for path in out or []:
        if path.suffix:
            animation_format(path)
    if sheet is not None:
        png_file(sheet, "--sheet")


def _write(
    path: Path,
    images: np.ndarray,
    times: np.ndarray,
    weights: np.ndarray,
    model: Any,
    record: dict[str, Any],
    force: bool,
) -> str:
    """One ``--out``: an animation file, or a folder of PNG frames with their times."""
    from emogen.render.animation import write_animation
    from emogen.render.images import save_png

    if path.suffix:
        write_animation(path, images, float(record["fps"]), comment=f"EmoGen clip {record['clip']}")
        return str(path)
    with output_folder(path, force=force) as tmp:
        for i, (t, image) in enumerate(zip(times, images, strict=True)):
            meta = image_metadata(model, weights[i], time_s=float(t), **record)
            save_png(tmp / f"frame_{i:04d}.png", image, meta)
    return str(path)
