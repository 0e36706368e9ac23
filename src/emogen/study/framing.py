"""What participants see around each face: the study's ``framing``, one of the framings of
``render/look.json`` that suit a participant's tile.

* ``face`` (the default): the camera fitted to the identity's face, hairline to chin filling
  most of the tile, hair, ears and neck visible at its edges;
* ``oval``: the same camera seen through look.json's oval on the background (hair, ears and neck
  hidden), the convention of many face-perception studies. The 3D viewer lays the oval over
  each tile; the server's PNGs (browsers without WebGL) are rendered through it
  (:func:`emogen.render.images.apply_oval`).

``head`` (head and shoulders) is for figures, not tiles: at a tile's size it leaves the face too
small to judge its expression. The framing is appearance, not GA state: replay ignores it.
"""

from __future__ import annotations

import difflib

#: The framings a study may show its participants.
STUDY_FRAMINGS = ("face", "oval")


def check_framing(value: str) -> str:
    """``value`` if participants can be shown it, else a ValueError naming the choices."""
    if value in STUDY_FRAMINGS:
        return value
    choices = " or ".join(f"'{f}'" for f in STUDY_FRAMINGS)
    if value.strip().lower() == "head":
        raise ValueError(
            f"must be {choices}: 'head' (head and shoulders) leaves the face too small at a "
            "tile's size to judge its expression; it is for figures (emogen render --framing head)"
        )
    close = difflib.get_close_matches(value.strip().lower(), STUDY_FRAMINGS, n=1, cutoff=0.5)
    hint = f" (did you mean '{close[0]}'?)" if close else ""
    raise ValueError(f"must be {choices}{hint}")
