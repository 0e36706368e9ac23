"""``emogen correct IN.csv --out OUT.csv [--mesh OUT.npz]``: correct faces given as weights.

A plain command function, registered on the top-level app by :mod:`emogen.cli.app`.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import numpy as np
import typer

from emogen.cli.options import IdentityOpt, ModelOpt, RigOpt, friendly_errors
from emogen.errors import ConfigError

if TYPE_CHECKING:
    import pandas as pd

    from emogen.model.face import FaceModel

STATUS_COLUMNS = ("collision_detected", "collision_remaining", "collision_iterations")


def read_weights_csv(path: Path, model: FaceModel) -> tuple[np.ndarray, pd.DataFrame]:
    """A CSV of faces (one per row; columns = shape or gene names) → weights (B, S).

    Shapes without a column are 0. An unknown column, a non-number or a value outside [0, 1]
    is a ConfigError naming it.
    """
    import pandas as pd

    try:
        frame = pd.read_csv(path)
    except FileNotFoundError:
        raise ConfigError(f"input CSV not found: {path}") from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise ConfigError(f"cannot read {path} as CSV: {exc}") from None
    rig = model.rig
    shapes = {s: i for i, s in enumerate(model.shape_names)}
    genes = {g.name: g.shapes for g in rig.genes}
    weights = np.zeros((len(frame), model.n_shapes))
    for column in frame.columns:
        name = str(column).strip()
        if name in shapes:
            targets = [shapes[name]]
        elif name in genes:
            targets = [shapes[s] for s in genes[name]]
        else:
            raise ConfigError(
                f"{path}: unknown column '{name}'; columns must be shape (or gene) names of "
                f"model '{model.name}': {', '.join(model.shape_names)}"
            )
        values = pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=np.float64)
        bad = np.flatnonzero(~np.isfinite(values) | (values < 0) | (values > 1))
        if len(bad):
            row = int(bad[0])
            raise ConfigError(
                f"{path}: column '{name}' row {row + 1}: weight must be a number in [0, 1]; "
                f"got {frame[column].iloc[row]!r}"
            )
        weights[:, targets] = values[:, None]
    return weights, frame


def correct_csv(
    source: Path, out: Path, model: FaceModel, mesh: Path | None = None
) -> dict[str, object]:
    """Correct every face of ``source`` and write ``out`` (and ``mesh``); returns the report.

    OUT.csv has one row per input row: every shape's effective weight (companions capped,
    e.g. ``mouthClose`` at most ``jawOpen``), every corrective weight (combinational, then the
    eight collision correctives) and ``collision_detected``, ``collision_remaining`` and
    ``collision_iterations``. ``mesh`` (.npz): ``vertices`` (B, V, 3) float32 of the corrected
    faces, ``faces`` (triangles), and the names and weights above.
    """
    import pandas as pd

    weights, _ = read_weights_csv(source, model)
    from emogen.correct.faces import correct_faces, corrected_vertices

    result = correct_faces(model, weights)
    table = pd.DataFrame(result.columns())
    table["collision_detected"] = result.collided
    table["collision_remaining"] = result.remaining
    table["collision_iterations"] = result.iterations
    out.parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(out, index=False)
    if mesh is not None:
        vertices = corrected_vertices(model, result)
        mesh.parent.mkdir(parents=True, exist_ok=True)
        np.savez(
            mesh,
            vertices=vertices,
            faces=model.faces,
            shape_names=np.array(model.shape_names),
            weights=result.weights.astype(np.float32),
            corrective_names=np.array(result.corrective_names, dtype=str),
            correctives=result.correctives.astype(np.float32),
        )
    return result.report()


@friendly_errors
def correct_command(
    source: Annotated[
        Path, typer.Argument(help="CSV of faces: one per row, columns = shape (or gene) names.")
    ],
    out: Annotated[Path, typer.Option("--out", "-o", help="Output CSV.")],
    mesh: Annotated[
        Path | None, typer.Option("--mesh", help="Also save the corrected vertices (.npz).")
    ] = None,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
    identity: IdentityOpt = None,
) -> None:
    """Correct faces: companion caps, combinational and collision correctives (paper III-A).

    The output adds every corrective weight to the shape weights, and says for each face
    whether a lip or teeth collision was found and whether any remains.
    """
    from emogen.model import load_model

    model = load_model(model_path, identity, rig=rig)
    report = correct_csv(source, out, model, mesh)
    typer.echo(
        f"{report['faces']} faces: {report['collided']} with a collision, "
        f"{report['remaining']} remaining after correction; wrote {out}"
        + (f" and {mesh}" if mesh else "")
    )
