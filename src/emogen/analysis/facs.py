"""Which FACS action unit each blendshape of the face model approximates — an approximation, not
an AU coding.

The ICT FaceKit model names its expression shapes after Apple ARKit's face blendshapes
(``ARFaceAnchor.BlendShapeLocation``: ``browInnerUp``, ``mouthSmileLeft`` …; ICT writes
``mouthSmile_L``) and adds a few of its own (``cheekRaiser``, ``PupilDilate``). ARKit describes
each shape by the facial movement it makes; the Facial Action Coding System (Ekman, Friesen &
Hager 2002, *Facial Action Coding System: The Manual*) describes the same movements as action
units (AUs: the visible effect of one muscle or muscle group). :data:`FACS_APPROXIMATIONS` pairs
each gene (one per left/right pair, as the GA searches them) with the AU whose appearance change
it resembles most, from the two descriptions side by side.

They are approximations, not AUs: a blendshape is one artist-sculpted displacement of the mesh,
at one fixed pattern, whereas an AU is defined by appearance changes a trained coder scores on a
real face (wrinkles, bulges, furrows the mesh may not show), at intensities A–E and in
combinations whose appearance is not the sum of their parts. A face made of ``mouthSmile`` and
``cheekSquint`` looks like AU6+12, but no one has FACS-coded it. Eye-gaze shapes map to the
FACS eye-position codes (61–64), jaw and cheek shapes without a muscle basis to action
descriptors (AD, e.g. AD34 puff), and shapes with no FACS counterpart to ``""``.
"""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd


@dataclass(frozen=True)
class FacsApproximation:
    """The FACS code a gene's shape resembles (``""``: none), the code's name in the manual,
    and how close the resemblance is."""

    code: str
    name: str
    note: str = ""


FACS_APPROXIMATIONS: dict[str, FacsApproximation] = {
    "browInnerUp": FacsApproximation("AU1", "inner brow raiser"),
    "browOuterUp": FacsApproximation("AU2", "outer brow raiser"),
    "browDown": FacsApproximation("AU4", "brow lowerer"),
    "eyeWide": FacsApproximation("AU5", "upper lid raiser"),
    "cheekSquint": FacsApproximation(
        "AU6", "cheek raiser", "ARKit's cheek-under-the-eye raise; ICT also has cheekRaiser"
    ),
    "cheekRaiser": FacsApproximation("AU6", "cheek raiser", "ICT's own shape, beside cheekSquint"),
    "eyeSquint": FacsApproximation("AU7", "lid tightener"),
    "noseSneer": FacsApproximation("AU9", "nose wrinkler"),
    "mouthUpperUp": FacsApproximation("AU10", "upper lip raiser"),
    "mouthSmile": FacsApproximation("AU12", "lip corner puller"),
    "mouthDimple": FacsApproximation("AU14", "dimpler"),
    "mouthFrown": FacsApproximation("AU15", "lip corner depressor"),
    "mouthLowerDown": FacsApproximation("AU16", "lower lip depressor"),
    "mouthShrugLower": FacsApproximation("AU17", "chin raiser"),
    "mouthShrugUpper": FacsApproximation(
        "AU17", "chin raiser", "weak: the upper lip pushed up and out, no AU of its own"
    ),
    "mouthPucker": FacsApproximation("AU18", "lip pucker"),
    "mouthStretch": FacsApproximation("AU20", "lip stretcher"),
    "mouthFunnel": FacsApproximation("AU22", "lip funneler"),
    "mouthPress": FacsApproximation("AU24", "lip presser"),
    "jawOpen": FacsApproximation(
        "AU26/27", "jaw drop / mouth stretch", "AU26 when moderate, AU27 when wide"
    ),
    "mouthRollLower": FacsApproximation("AU28", "lip suck", "lower lip only"),
    "mouthRollUpper": FacsApproximation("AU28", "lip suck", "upper lip only"),
    "jawForward": FacsApproximation("AD29", "jaw thrust", "an action descriptor"),
    "cheekPuff": FacsApproximation("AD34", "puff", "an action descriptor"),
    "eyeBlink": FacsApproximation("AU43/45", "eyes closed / blink", "static: AU43"),
    "eyeLookLeft": FacsApproximation("AU61/62", "eyes turn left / right", "gaze, not a face AU"),
    "eyeLookRight": FacsApproximation("AU61/62", "eyes turn left / right", "gaze, not a face AU"),
    "eyeLookUp": FacsApproximation("AU63", "eyes up", "gaze, not a face AU"),
    "eyeLookDown": FacsApproximation("AU64", "eyes down", "gaze, not a face AU"),
    "PupilDilate": FacsApproximation("", "", "no FACS counterpart (pupil size)"),
}

#: The caveat every report that shows the mapping states.
CAVEAT = (
    "Blendshape → action unit pairs are approximations read from Apple ARKit's blendshape "
    "descriptions (the names the ICT model uses) beside the FACS manual (Ekman, Friesen & Hager "
    "2002): a blendshape is one sculpted mesh displacement, not an AU a trained coder would "
    "score; no face here was FACS-coded."
)


def gene_base(name: str) -> str:
    """A gene column's shape name: ``g_mouthSmile`` → ``mouthSmile``."""
    return name[2:] if name.startswith("g_") else name


def facs_code(gene: str) -> str:
    """The approximate FACS code of a gene (``g_`` prefix allowed); ``""`` when none."""
    hit = FACS_APPROXIMATIONS.get(gene_base(gene))
    return "" if hit is None else hit.code


def gene_label(gene: str) -> str:
    """A gene for a figure axis: ``mouthSmile (≈AU12)``, or the bare name without a code."""
    code = facs_code(gene)
    return f"{gene_base(gene)} (≈{code})" if code else gene_base(gene)


def facs_table(genes: tuple[str, ...] | list[str]) -> pd.DataFrame:
    """One row per gene: ``gene``, ``facs_code`` (``""``: none), ``facs_name``, ``note``."""
    rows = []
    for g in genes:
        hit = FACS_APPROXIMATIONS.get(gene_base(g), FacsApproximation("", "", "not in the map"))
        rows.append(
            {"gene": gene_base(g), "facs_code": hit.code, "facs_name": hit.name, "note": hit.note}
        )
    return pd.DataFrame(rows, columns=["gene", "facs_code", "facs_name", "note"])
