"""Maps of perceptive fields: where each emotion's fields lie in the face space's first two
components, the participants × participants overlap matrices, and contact sheets of every
participant's mean final face per emotion, rendered on the identity they made it on."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from emogen.analysis import plots
from emogen.analysis.fields import Fields
from emogen.analysis.people import People

if TYPE_CHECKING:
    from emogen.appearance.identities import Identity
    from emogen.model.face import FaceModel


def population_map(fields: Fields, emotion: str, grid: np.ndarray) -> np.ndarray:
    """The emotion's population field (every participant's field weighing the same) marginal
    on PC1–PC2 at ``grid`` points (n, 2): the 2-D Gaussian KDE of the projected faces."""
    h = fields.bandwidth[emotion]
    out = np.zeros(len(grid))
    who = fields.participants(emotion)
    for p in who:
        x = fields.points[(p, emotion)][:, :2]
        d2 = ((grid[:, None, :] - x[None, :, :]) ** 2).sum(axis=-1)
        out += np.exp(-0.5 * d2 / h**2).mean(axis=1) / (2 * np.pi * h**2)
    return out / len(who)


def field_heatmaps(fields: Fields, path: Path) -> Path:
    """One panel per emotion: the population field on PC1–PC2 (relative density, viridis) with
    each participant's field centre (white dot); shared axes."""
    allx = np.vstack(list(fields.points.values()))[:, :2]
    h = max(fields.bandwidth.values())
    lo, hi = allx.min(axis=0) - 2 * h, allx.max(axis=0) + 2 * h
    gx, gy = np.linspace(lo[0], hi[0], 120), np.linspace(lo[1], hi[1], 120)
    mesh = np.stack(np.meshgrid(gx, gy), axis=-1).reshape(-1, 2)
    emotions = fields.emotions
    cols = min(4, len(emotions))
    rows = -(-len(emotions) // cols)
    fig = plots.new_figure(3.0 * cols + 0.8, 2.9 * rows)
    axes = fig.subplots(rows, cols, squeeze=False, sharex=True, sharey=True)
    image = None
    for ax, e in zip(axes.flat, emotions, strict=False):
        dens = population_map(fields, e, mesh).reshape(len(gy), len(gx))
        image = ax.imshow(
            dens / dens.max(),
            origin="lower",
            extent=(lo[0], hi[0], lo[1], hi[1]),
            aspect="auto",
            cmap="viridis",
            vmin=0,
            vmax=1,
        )
        centres = np.stack(
            [fields.points[(p, e)][:, :2].mean(axis=0) for p in fields.participants(e)]
        )
        ax.scatter(centres[:, 0], centres[:, 1], s=6, c="white", edgecolors="black", linewidths=0.3)
        ax.set_title(f"{e} (n = {len(centres)})", fontsize=9)
    for ax in axes.flat[len(emotions) :]:
        ax.set_visible(False)
    ev = fields.space.explained
    for ax in axes[-1, :]:
        ax.set_xlabel(f"PC1 ({100 * ev[0]:.0f} % of gene variance)")
    for ax in axes[:, 0]:
        ax.set_ylabel(f"PC2 ({100 * ev[1]:.0f} %)" if len(ev) > 1 else "PC2")
    if image is not None:
        fig.colorbar(image, ax=axes.ravel().tolist(), label="density / its peak", shrink=0.8)
    return plots.save_figure(fig, path)


def overlap_heatmaps(
    matrices: dict[str, pd.DataFrame], order: list[str], path: Path, *, title: str = ""
) -> Path:
    """The participants × participants overlap of each emotion, rows and columns in ``order``
    (e.g. by cluster), on one shared 0–1 scale."""
    emotions = list(matrices)
    cols = min(4, len(emotions))
    rows = -(-len(emotions) // cols)
    fig = plots.new_figure(2.8 * cols + 0.8, 2.7 * rows)
    axes = fig.subplots(rows, cols, squeeze=False)
    image = None
    for ax, e in zip(axes.flat, emotions, strict=False):
        m = matrices[e]
        keep = [p for p in order if p in m.index]
        image = ax.imshow(m.loc[keep, keep].to_numpy(), cmap="viridis", vmin=0, vmax=1)
        ax.set_title(e, fontsize=9)
        ax.set_xlabel("participant")
        ax.set_ylabel("participant")
        ax.set_xticks([])
        ax.set_yticks([])
    for ax in axes.flat[len(emotions) :]:
        ax.set_visible(False)
    if title:
        fig.suptitle(title, fontsize=9)
    if image is not None:
        fig.colorbar(image, ax=axes.ravel().tolist(), label="overlap of fields", shrink=0.8)
    return plots.save_figure(fig, path)


def study_identities(people: People) -> dict[str, Identity]:
    """Each identity name of the faces as the participants saw it: the export's
    ``identities`` table first, then the presets; unknown names are left out."""
    from emogen.appearance.identities import resolve_identity
    from emogen.errors import ConfigError
    from emogen.study.export import identities_from_table

    known: dict[str, Identity] = {}
    if people.identities is not None and len(people.identities):
        for (_, name), ident in identities_from_table(people.identities).items():
            known.setdefault(name, ident)
    out = {}
    for name in people.identity_names:
        try:
            out[name] = resolve_identity(name, known)
        except ConfigError:
            continue
    return out


def mean_faces(people: People) -> pd.DataFrame:
    """Each participant's mean final face (corrected weights ``w_*``) per emotion × identity."""
    cols = list(people.weights)
    keys = ["emotion", "participant_id", "identity"]
    f = people.faces.assign(**{k: people.faces[k].astype(str) for k in keys})
    grouped = f.groupby(keys, sort=True)[cols]
    return pd.concat([grouped.size().rename("n_faces"), grouped.mean()], axis=1).reset_index()


def contact_sheets(
    people: People,
    model: FaceModel,
    folder: Path,
    *,
    size: int = 160,
    columns: int = 8,
    participants: set[str] | None = None,
) -> tuple[dict[str, Path], list[str]]:
    """One contact sheet per emotion of every participant's (or only ``participants``') mean
    face per identity, rendered on that identity (shape and appearance), labelled
    ``participant · identity (n faces)``. Returns the sheets by emotion and the identities
    that could not be resolved."""
    from emogen.analysis.face_sheets import model_weights, render_on_identities
    from emogen.render.images import contact_sheet

    means = mean_faces(people)
    if participants is not None:
        means = means[means["participant_id"].isin(sorted(participants))].reset_index(drop=True)
    idents = study_identities(people)
    missing = sorted(set(means["identity"]) - set(idents))
    means = means[means["identity"].isin(list(idents))].reset_index(drop=True)
    shapes = [c.removeprefix("w_") for c in people.weights]
    weights = model_weights(means[list(people.weights)].to_numpy(), shapes, model)
    per_face = [idents[str(i)] for i in means["identity"]]
    images, background = render_on_identities(model, weights, per_face, size=size)
    sheets = {}
    for e, part in means.groupby("emotion", sort=True):
        labels = [
            f"{p} · {i} ({n})"
            for p, i, n in part[["participant_id", "identity", "n_faces"]].itertuples(index=False)
        ]
        sheet = contact_sheet(
            images[part.index.to_numpy()], labels, columns=columns, background=background
        )
        sheets[str(e)] = plots.save_image(folder / f"fields_faces_{e}.png", sheet)
    return sheets, missing
