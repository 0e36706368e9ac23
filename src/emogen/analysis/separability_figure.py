"""The separability figure (Fig. 8): samples in the first two PCA components with the GMM's
components, group means and targets, in the house style of :mod:`emogen.analysis.plots`."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from emogen.analysis.plots import colour, marker, new_figure, save_figure

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from emogen.analysis.separability import Separability


def _ellipse(ax: Axes, mean: np.ndarray, cov: np.ndarray, edge: str) -> None:
    from matplotlib.patches import Ellipse

    vals, vecs = np.linalg.eigh(cov[:2, :2])
    vals = np.maximum(vals, 1e-12)
    angle = float(np.degrees(np.arctan2(vecs[1, 1], vecs[0, 1])))
    for k in (1, 2):
        ax.add_patch(
            Ellipse(
                (float(mean[0]), float(mean[1])),
                2 * k * np.sqrt(vals[1]),
                2 * k * np.sqrt(vals[0]),
                angle=angle,
                fill=False,
                ls="-" if k == 1 else "--",
                lw=1.2,
                color=edge,
            )
        )


def separability_figure(sep: Separability, path: Path, *, title: str = "") -> Path:
    """Samples in the first two PCA components, coloured (and shaped) by group, with the GMM's
    components (1σ solid and 2σ dashed ellipses, in the colour of the group each one matches;
    grey when it matches none), group means (×) and targets (★) — Fig. 8. Names are in the
    legend, outside the axes (no labels over the data, whatever the number of groups)."""
    from matplotlib.lines import Line2D

    n = len(sep.groups)
    fig = new_figure(5.2 + 1.2 * max(1, -(-n // 10)), 4.2)
    ax = fig.subplots()
    z = sep.coords
    y2 = z[:, 1] if z.shape[1] > 1 else np.zeros(len(z))
    for i, g in enumerate(sep.groups):
        m = sep.labels == i
        ax.scatter(z[m, 0], y2[m], s=6, alpha=0.4, color=colour(i), marker=marker(i), label=g)
        gm = sep.group_means[i]
        ax.scatter([gm[0]], [gm[1] if len(gm) > 1 else 0], marker="x", s=60, color=colour(i))
        if sep.target_coords is not None:
            t = sep.target_coords[i]
            ax.scatter(
                [t[0]],
                [t[1] if len(t) > 1 else 0],
                marker="*",
                s=140,
                color=colour(i),
                edgecolor="k",
                zorder=5,
            )
    if z.shape[1] > 1:
        index = {g: i for i, g in enumerate(sep.groups)}
        for c, name in enumerate(sep.cluster_names):
            edge = colour(index[name]) if name in index else "0.5"
            _ellipse(ax, sep.means[c], sep.covariances[c], edge)
    ax.set_xlabel("PCA component 1 [weight units]")
    ax.set_ylabel("PCA component 2 [weight units]")
    extra = [
        Line2D([], [], color="k", marker="x", ls="", label="group mean"),
        Line2D([], [], color="0.3", ls="-", label="GMM component, 1σ"),
        Line2D([], [], color="0.3", ls="--", label="GMM component, 2σ"),
    ]
    if sep.target_coords is not None:
        extra.append(Line2D([], [], color="w", marker="*", mec="k", ms=9, ls="", label="target"))
    handles = ax.get_legend_handles_labels()[0] + extra
    ax.legend(
        handles=handles,
        loc="upper left",
        bbox_to_anchor=(1.02, 1.0),
        borderaxespad=0.0,
        fontsize=7,
        markerscale=1.5,
        frameon=False,
        ncol=max(1, -(-len(handles) // 14)),
    )
    ax.grid(alpha=0.3)
    ax.set_title(
        title or f"GMM in {sep.n_pca} PCA components (accuracy {sep.accuracy:.0%})", fontsize=9
    )
    return save_figure(fig, path)
