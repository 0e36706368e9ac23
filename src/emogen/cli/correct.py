"""``emogen correct IN.csv --out OUT.csv [--mesh OUT.npz]``: correct faces given as weights.

A plain command function, registered on the top-level app by :mod:`emogen.cli.app`.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from emogen.cli.options import IdentityOpt, JsonOpt, ModelOpt, RigOpt, friendly_errors, show_result

if TYPE_CHECKING:
    import numpy as np
    import pandas as pd

    from emogen.model.face import FaceModel

STATUS_COLUMNS = ("collision_detected", "collision_remaining", "collision_iterations")


def read_weights_csv(path: Path, model: FaceModel) -> tuple[np.ndarray, pd.DataFrame]:
    """A CSV of faces (one per row; columns = shape or gene names) → weights (B, S).

    Shapes without a column are 0. An unknown column, an empty cell, a non-number or a value
    outside [0, 1] is an error naming it (:func:`emogen.model.face_table.read_face_table`).
    """
    from emogen.model.face_table import read_face_table
    from emogen.render.weights import LABEL_COLUMNS

    table = read_face_table(
        path,
        model.rig,
        what="input CSV",
        others="error",
        unit_range=True,
        label_columns=LABEL_COLUMNS,
    )
    return table.weights, table.frame


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
    import numpy as np
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
    as_json: JsonOpt = False,
) -> None:
    """Correct faces: companion caps, combinational and collision correctives (paper III-A).

    The output adds every corrective weight to the shape weights, and says for each face
    whether a lip or teeth collision was found and whether any remains.
    """
    from emogen.model import load_model

    model = load_model(model_path, identity, rig=rig)
    report = correct_csv(source, out, model, mesh)
    line = (
        f"{report['faces']} faces: {report['collided']} with a collision, "
        f"{report['remaining']} remaining after correction; wrote {out}"
        + (f" and {mesh}" if mesh else "")
    )
    wrote = [str(out), *([str(mesh)] if mesh else [])]
    show_result(as_json, {**report, "wrote": wrote}, [line])
