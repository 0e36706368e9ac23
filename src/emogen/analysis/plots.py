"""Figures with matplotlib (object API, Agg canvas: no display, no global pyplot state)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from emogen.analysis.separability import Separability

DPI = 110
COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf")


def _figure(width: float, height: float) -> Figure:
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), dpi=DPI, layout="constrained")


def _save(fig: Figure, path: Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI)
    return path


def _panels(n: int, most: int = 4) -> tuple[int, int]:
    cols = min(n, most)
    return -(-n // cols), cols


def generation_distributions(
    panels: dict[str, np.ndarray], path: Path, *, ylabel: str = "CD error", title: str = ""
) -> Path:
    """Per-generation error distributions (violins, mean ± sd marked), one panel per entry of
    ``panels`` (label → errors (n_samples, G + 1)), like the paper's Figs. 11–18."""
    rows, cols = _panels(len(panels))
    fig = _figure(3.3 * cols, 2.6 * rows)
    axes = fig.subplots(rows, cols, squeeze=False, sharey=True)
    for ax, (label, errors) in zip(axes.ravel(), panels.items(), strict=False):
        e = np.asarray(errors, dtype=np.float64)
        data = [c[np.isfinite(c)] for c in e.T]
        gens = [g for g, d in enumerate(data) if len(d) > 1]
        if gens:
            parts = ax.violinplot(
                [data[g] for g in gens], positions=gens, widths=0.8, showextrema=False
            )
            for body in parts["bodies"]:
                body.set_alpha(0.45)
        means = [np.mean(d) if len(d) else np.nan for d in data]
        sds = [np.std(d, ddof=1) if len(d) > 1 else 0.0 for d in data]
        ax.errorbar(
            range(len(data)),
            means,
            yerr=sds,
            fmt="o-",
            ms=3,
            lw=1,
            color="k",
            capsize=2,
            label="mean ± sd",
        )
        ax.set_title(label, fontsize=9)
        ax.set_xlabel("generation")
        ax.grid(alpha=0.3)
    for ax in axes[:, 0]:
        ax.set_ylabel(ylabel)
    for ax in axes.ravel()[len(panels) :]:
        ax.set_visible(False)
    if title:
        fig.suptitle(title, fontsize=10)
    return _save(fig, path)


def kl_curves(series: dict[str, np.ndarray], path: Path, *, title: str = "") -> Path:
    """KL(P_g ‖ P_{g−1}) against g, one line per entry (Figs. 15 and 17)."""
    fig = _figure(5.2, 3.2)
    ax = fig.subplots()
    for i, (label, kl) in enumerate(series.items()):
        g = np.arange(1, len(kl) + 1)
        ax.plot(g, kl, "o-", ms=4, color=COLOURS[i % len(COLOURS)], label=label)
    ax.set_yscale("log")
    ax.set_xlabel("generation g")
    ax.set_ylabel("KL(P_g ‖ P_g−1) [nats]")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    if title:
        ax.set_title(title, fontsize=10)
    return _save(fig, path)


def _ellipse(ax: Axes, mean: np.ndarray, cov: np.ndarray, colour: str, label: str) -> None:
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
                color=colour,
            )
        )
    ax.annotate(
        label,
        (float(mean[0]), float(mean[1])),
        fontsize=7,
        ha="center",
        bbox={"boxstyle": "round", "fc": "white", "alpha": 0.7, "lw": 0},
    )


def separability(sep: Separability, path: Path, *, title: str = "") -> Path:
    """Samples in the first two PCA components, coloured by group, with the GMM's components
    (1σ and 2σ ellipses, named by correspondence), group means (×) and targets (★) — Fig. 8."""
    fig = _figure(5.2, 4.2)
    ax = fig.subplots()
    z = sep.coords
    y2 = z[:, 1] if z.shape[1] > 1 else np.zeros(len(z))
    for i, g in enumerate(sep.groups):
        m = sep.labels == i
        ax.scatter(z[m, 0], y2[m], s=5, alpha=0.35, color=COLOURS[i % len(COLOURS)], label=g)
        gm = sep.group_means[i]
        ax.scatter([gm[0]], [gm[1] if len(gm) > 1 else 0], marker="x", s=60, color="k")
        if sep.target_coords is not None:
            t = sep.target_coords[i]
            ax.scatter(
                [t[0]],
                [t[1] if len(t) > 1 else 0],
                marker="*",
                s=140,
                color=COLOURS[i % len(COLOURS)],
                edgecolor="k",
                zorder=5,
            )
    if z.shape[1] > 1:
        for c, name in enumerate(sep.cluster_names):
            _ellipse(ax, sep.means[c], sep.covariances[c], "0.2", name)
    ax.set_xlabel("PCA component 1")
    ax.set_ylabel("PCA component 2")
    ax.legend(fontsize=7, markerscale=2, loc="best")
    ax.grid(alpha=0.3)
    ax.set_title(
        title or f"GMM in {sep.n_pca} PCA components (accuracy {sep.accuracy:.0%})", fontsize=9
    )
    return _save(fig, path)


def bins(table: pd.DataFrame, path: Path, *, title: str = "") -> Path:
    """Stacked bars of repeatability bins (rows of ``table``, columns the bins in %)."""
    fig = _figure(6.0, 0.45 * len(table) + 1.4)
    ax = fig.subplots()
    left = np.zeros(len(table))
    cmap = ("#2b83ba", "#abdda4", "#fdae61", "#d7191c")
    for j, col in enumerate(table.columns):
        v = table[col].to_numpy(dtype=np.float64)
        ax.barh(range(len(table)), v, left=left, color=cmap[j % 4], label=str(col))
        left += v
    ax.set_yticks(range(len(table)), [str(i) for i in table.index], fontsize=7)
    ax.invert_yaxis()
    ax.set_xlabel("pairs of final faces [%]")
    ax.set_xlim(0, 100)
    ax.legend(fontsize=7, ncol=4, loc="upper center", bbox_to_anchor=(0.5, -0.25))
    if title:
        ax.set_title(title, fontsize=9)
    return _save(fig, path)


def final_distributions(
    samples: dict[str, np.ndarray], path: Path, *, xlabel: str = "final CD error", title: str = ""
) -> Path:
    """Overlaid histograms of final errors, one per entry (Fig. 18 / Table V)."""
    fig = _figure(5.2, 3.2)
    ax = fig.subplots()
    top = max(float(np.nanmax(s)) for s in samples.values()) if samples else 1.0
    edges = np.linspace(0, max(top, 1e-3) * 1.02, 40).tolist()
    for i, (label, s) in enumerate(samples.items()):
        s = np.asarray(s, dtype=np.float64)
        ax.hist(
            s,
            bins=edges,
            histtype="step",
            lw=1.5,
            density=True,
            color=COLOURS[i % len(COLOURS)],
            label=f"{label} ({s.mean():.3f} ± {s.std(ddof=1):.3f})",
        )
    ax.set_xlabel(xlabel)
    ax.set_ylabel("density")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    if title:
        ax.set_title(title, fontsize=9)
    return _save(fig, path)


def power_curve(
    curve: pd.DataFrame, path: Path, *, target: float, n_required: int | None, title: str = ""
) -> Path:
    fig = _figure(5.0, 3.2)
    ax = fig.subplots()
    ax.errorbar(
        curve["n"], curve["power"], yerr=curve["se"], fmt="o", ms=3, capsize=2, label="simulated"
    )
    if "fitted" in curve and curve["fitted"].notna().any():
        ax.plot(curve["n"], curve["fitted"], "-", color="C1", lw=1.2, label="fitted")
    ax.legend(fontsize=7, loc="upper left")
    ax.axhline(target, color="0.4", ls="--", lw=1)
    if n_required is not None:
        ax.axvline(n_required, color="C3", ls=":", lw=1.2)
        ax.annotate(
            f"n = {n_required}",
            (n_required, 0.05),
            color="C3",
            fontsize=8,
            xytext=(4, 0),
            textcoords="offset points",
        )
    ax.set_xscale("log")
    ax.set_xlabel("participants per group")
    ax.set_ylabel("power")
    ax.set_ylim(0, 1.02)
    ax.grid(alpha=0.3, which="both")
    if title:
        ax.set_title(title, fontsize=9)
    return _save(fig, path)


def spread(rows: pd.DataFrame, path: Path, *, title: str = "") -> Path:
    """Mean proxy error per group against the GA noise expected at the same n (95th pct)."""
    fig = _figure(5.0, 0.4 * len(rows) + 1.5)
    ax = fig.subplots()
    y = np.arange(len(rows))
    ax.barh(y, rows["mean proxy error"], color="C0", alpha=0.7, label="group: mean proxy error")
    ax.scatter(rows["noise 95th pct"], y, marker="|", s=300, color="C3", label="GA noise, 95th pct")
    ax.scatter(rows["noise (same n)"], y, marker="|", s=200, color="k", label="GA noise, mean")
    ax.set_yticks(y, [str(g) for g in rows["group"]], fontsize=7)
    ax.invert_yaxis()
    ax.set_xlabel("CD to the group's mean face")
    ax.legend(fontsize=7, loc="lower right")
    ax.grid(alpha=0.3, axis="x")
    if title:
        ax.set_title(title, fontsize=9)
    return _save(fig, path)
