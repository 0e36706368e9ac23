"""Figures with matplotlib (object API, Agg canvas: no display, no global pyplot state).

The house style lives here, for every figure of ``analyse``, ``replicate`` and ``power``:

* every figure in each format of :func:`formats` (``png`` at 300 dpi, ``svg``, ``pdf``; default
  ``png`` and ``svg``), beside one another (``kl.png``, ``kl.svg``);
* groups in the Okabe–Ito colour-blind-safe palette, with marker shapes cycling beside it so 12
  groups stay apart; ordered magnitudes on a perceptual map (``cividis``; heat maps ``viridis``
  — never ``jet``/``turbo``: :data:`MAGNITUDE_MAPS`);
* axes labelled with their units; legends outside the axes, so they never cover data;
  layouts that grow with the number of groups (2–12).
"""

from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


DPI = 300
#: Okabe & Ito (2008): distinguishable with every common colour-vision deficiency.
COLOURS = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#D55E00", "#F0E442", "#000000")
MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")
#: Perceptually uniform, colour-blind-safe maps for magnitudes (distances, shares).
MAGNITUDE_MAPS = ("viridis", "cividis", "magma", "inferno", "plasma")
FORMATS = ("png", "svg", "pdf")
_FORMATS: contextvars.ContextVar[tuple[str, ...]] = contextvars.ContextVar(
    "figure_formats", default=("png", "svg")
)


def check_formats(names: Sequence[str]) -> tuple[str, ...]:
    """Figure formats from a ``--format`` value (``png,svg``, ``pdf``…), checked; ``png`` is
    always written too (the HTML report shows it)."""
    from emogen.errors import ConfigError

    chosen = [n.strip().lower() for name in names for n in str(name).split(",") if n.strip()]
    bad = [n for n in chosen if n not in FORMATS]
    if bad or not chosen:
        raise ConfigError(
            f"--format must be one or more of {', '.join(FORMATS)}; got {bad or names}"
        )
    return tuple(dict.fromkeys(["png", *chosen]))


@contextlib.contextmanager
def formats(names: Sequence[str]) -> Iterator[tuple[str, ...]]:
    """Within the block, every figure is written in these formats (:func:`check_formats`)."""
    token = _FORMATS.set(check_formats(names))
    try:
        yield _FORMATS.get()
    finally:
        _FORMATS.reset(token)


_KEPT: contextvars.ContextVar[list[Figure] | None] = contextvars.ContextVar(
    "kept_figures", default=None
)


@contextlib.contextmanager
def keep_figures() -> Iterator[list[Figure]]:
    """Collects every figure saved within the block (to check its layout)."""
    kept: list[Figure] = []
    token = _KEPT.set(kept)
    try:
        yield kept
    finally:
        _KEPT.reset(token)


def colour(i: int) -> str:
    return COLOURS[i % len(COLOURS)]


def marker(i: int) -> str:
    """Group i's marker: the shape changes when the colours come round again."""
    return MARKERS[(i // len(COLOURS) + i) % len(MARKERS)] if i >= len(COLOURS) else MARKERS[0]


def new_figure(width: float, height: float) -> Figure:
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), dpi=DPI, layout="constrained")


def legend_outside(ax: Axes, n_entries: int, **kw: object) -> None:
    """The axes' legend to their right, outside (never over the data), in columns of ≤ 12."""
    if not ax.get_legend_handles_labels()[0]:
        return
    ax.legend(
        loc="upper left",
        bbox_to_anchor=(1.02, 1.0),
        borderaxespad=0.0,
        fontsize=7,
        ncol=max(1, -(-n_entries // 12)),
        frameon=False,
        **kw,
    )


def _tidy_ticks(fig: Figure) -> None:
    """Small tick labels, and at most ~5 ticks on automatic linear axes: labels never touch."""
    from matplotlib.ticker import AutoLocator, MaxNLocator

    for ax in fig.axes:
        ax.tick_params(labelsize=7)
        for axis in (ax.xaxis, ax.yaxis):
            if isinstance(axis.get_major_locator(), AutoLocator):
                axis.set_major_locator(MaxNLocator(nbins=5, steps=[1, 2, 2.5, 5, 10]))


def _generation_axis(ax: Axes, last: int) -> None:
    """Whole generations 0 … last on the x axis."""
    from matplotlib.ticker import MaxNLocator

    ax.set_xlim(-0.6, last + 0.6)
    ax.xaxis.set_major_locator(MaxNLocator(nbins=6, integer=True))


def save_image(path: Path, image: np.ndarray) -> Path:
    """A rendered image (a face sheet, heatmaps: (H, W, 3) uint8) as a PNG marked 300 dpi,
    and in each vector format of :func:`formats` as a page holding it at 300 dpi (the faces
    are pixels: a renderer's output has no vector form). Returns the PNG's path."""
    from PIL import Image

    path = Path(path).with_suffix(".png")
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.ascontiguousarray(image)).save(path, format="PNG", dpi=(DPI, DPI))
    vector = [f for f in _FORMATS.get() if f != "png"]
    if vector:
        from matplotlib.figure import Figure

        h, w = image.shape[:2]
        fig = Figure(figsize=(w / DPI, h / DPI), dpi=DPI)
        fig.figimage(image, resize=False)
        for fmt in vector:
            fig.savefig(path.with_suffix(f".{fmt}"), dpi=DPI, format=fmt)
    return path


def save_figure(fig: Figure, path: Path) -> Path:
    """The figure at ``path`` (its suffix replaced by each format's); returns the PNG's path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    _tidy_ticks(fig)
    for fmt in _FORMATS.get():
        fig.savefig(path.with_suffix(f".{fmt}"), dpi=DPI, format=fmt)
    kept = _KEPT.get()
    if kept is not None:
        kept.append(fig)
    return path.with_suffix(".png")


def _panels(n: int, most: int = 4) -> tuple[int, int]:
    cols = min(n, most)
    return -(-n // cols), cols


def generation_distributions(
    panels: dict[str, np.ndarray], path: Path, *, ylabel: str = "elite error [CD]", title: str = ""
) -> Path:
    """Per-generation error distributions (violins, mean ± sd marked), one panel per entry of
    ``panels`` (label → errors (n_samples, G + 1)), like the paper's Figs. 11–18."""
    rows, cols = _panels(len(panels))
    fig = new_figure(3.3 * cols, 2.6 * rows)
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
        ax.set_title(label, fontsize=8)
        ax.set_xlabel("generation [g]")
        _generation_axis(ax, len(data) - 1)
        ax.grid(alpha=0.3)
    for ax in axes[:, 0]:
        ax.set_ylabel(ylabel)
    for ax in axes.ravel()[len(panels) :]:
        ax.set_visible(False)
    if title:
        fig.suptitle(title, fontsize=10)
    return save_figure(fig, path)


def kl_curves(series: dict[str, np.ndarray], path: Path, *, title: str = "") -> Path:
    """KL(P_g ‖ P_{g−1}) against g, one line per entry (Figs. 15 and 17)."""
    fig = new_figure(5.2 + 2.2 * -(-len(series) // 12), 3.2)
    ax = fig.subplots()
    for i, (label, kl) in enumerate(series.items()):
        g = np.arange(1, len(kl) + 1)
        ax.plot(g, kl, "-", marker=marker(i), ms=4, color=colour(i), label=label)
    ax.set_yscale("log")
    _generation_axis(ax, max((len(k) for k in series.values()), default=1))
    ax.set_xlabel("generation [g]")
    ax.set_ylabel("KL(P_g ‖ P_g−1) [nats]")
    ax.grid(alpha=0.3, which="both")
    legend_outside(ax, len(series))
    if title:
        ax.set_title(title, fontsize=10)
    return save_figure(fig, path)


def bins(table: pd.DataFrame, path: Path, *, title: str = "") -> Path:
    """Stacked bars of repeatability bins (rows of ``table``, columns the bins in %)."""
    import matplotlib

    fig = new_figure(6.0, 0.3 * len(table) + 1.6)
    ax = fig.subplots()
    left = np.zeros(len(table))
    shades = matplotlib.colormaps["cividis"](np.linspace(0.05, 0.95, len(table.columns)))
    for j, col in enumerate(table.columns):
        v = table[col].to_numpy(dtype=np.float64)
        ax.barh(range(len(table)), v, left=left, color=shades[j], label=f"CD {col}")
        left += v
    ax.set_yticks(range(len(table)), [str(i) for i in table.index], fontsize=7)
    ax.invert_yaxis()
    ax.set_xlabel("pairs of final faces [%]")
    ax.set_xlim(0, 100)
    fig.legend(fontsize=7, ncol=4, loc="outside lower center", frameon=False)
    if title:
        ax.set_title(title, fontsize=9)
    return save_figure(fig, path)


def final_distributions(
    samples: dict[str, np.ndarray], path: Path, *, xlabel: str = "final error [CD]", title: str = ""
) -> Path:
    """Overlaid histograms of final errors, one per entry (Fig. 18 / Table V)."""
    fig = new_figure(5.2 + 2.6 * -(-len(samples) // 12), 3.2)
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
            color=colour(i),
            ls=("-", "--", ":", "-.")[(i // len(COLOURS)) % 4],
            label=f"{label} ({s.mean():.3f} ± {s.std(ddof=1):.3f})",
        )
    ax.set_xlabel(xlabel)
    ax.set_ylabel("density [1 / CD]")
    legend_outside(ax, len(samples))
    ax.grid(alpha=0.3)
    if title:
        ax.set_title(title, fontsize=9)
    return save_figure(fig, path)


def power_curve(
    curve: pd.DataFrame, path: Path, *, target: float, n_required: int | None, title: str = ""
) -> Path:
    fig = new_figure(5.0, 3.2)
    ax = fig.subplots()
    ax.errorbar(
        curve["n"],
        curve["power"],
        yerr=curve["se"],
        fmt="o",
        ms=3,
        capsize=2,
        label="simulated",
        color=colour(0),
    )
    if "fitted" in curve and curve["fitted"].notna().any():
        ax.plot(curve["n"], curve["fitted"], "-", color=colour(1), lw=1.2, label="fitted")
    ax.axhline(target, color="0.4", ls="--", lw=1, label=f"target power {target:g}")
    if n_required is not None:
        ax.axvline(n_required, color=colour(5), ls=":", lw=1.2, label="n required")
        ax.annotate(
            f"n = {n_required}",
            (n_required, 0.05),
            color=colour(5),
            fontsize=8,
            xytext=(4, 0),
            textcoords="offset points",
        )
    ax.set_xscale("log")
    ax.set_xlabel("participants per group [n]")
    ax.set_ylabel("power [probability]")
    ax.set_ylim(0, 1.02)
    legend_outside(ax, 4)
    ax.grid(alpha=0.3, which="both")
    if title:
        ax.set_title(title, fontsize=9)
    return save_figure(fig, path)


def spread(rows: pd.DataFrame, path: Path, *, title: str = "") -> Path:
    """Mean proxy error per group against the GA noise expected at the same n (95th pct)."""
    fig = new_figure(6.2, 0.3 * len(rows) + 1.5)
    ax = fig.subplots()
    y = np.arange(len(rows))
    ax.barh(
        y, rows["mean proxy error"], color=colour(0), alpha=0.7, label="group: mean proxy error"
    )
    ax.scatter(
        rows["noise 95th pct"], y, marker="|", s=300, color=colour(5), label="GA noise, 95th pct"
    )
    ax.scatter(rows["noise (same n)"], y, marker="|", s=200, color="k", label="GA noise, mean")
    ax.set_yticks(y, [str(g) for g in rows["group"]], fontsize=7)
    ax.invert_yaxis()
    ax.set_xlabel("CD to the group's mean face [cosine distance]")
    legend_outside(ax, 3)
    ax.grid(alpha=0.3, axis="x")
    if title:
        ax.set_title(title, fontsize=9)
    return save_figure(fig, path)
