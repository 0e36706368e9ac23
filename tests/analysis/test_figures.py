"""Figures as a journal wants them: vector + 300-dpi PNG, colour-blind-safe colours, labelled
axes, legends outside the data, and layouts that hold for 2 to 12 groups (checked on the
drawn text's bounding boxes, not by eye)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure
from PIL import Image

from emogen.analysis import plots
from emogen.analysis.repeatability import BIN_LABELS
from emogen.analysis.separability import gmm_separability
from emogen.analysis.separability_figure import separability_figure
from emogen.errors import ConfigError


def _groups(n: int) -> list[str]:
    return [f"emotion {i} / identity-{i % 3}" for i in range(n)]


def _separable(n: int, per: int = 12, dim: int = 16, seed: int = 0):  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(seed)
    centres = rng.uniform(0, 1, (n, dim))
    weights = np.concatenate([c + 0.03 * rng.standard_normal((per, dim)) for c in centres])
    labels = np.repeat(np.arange(n), per)
    return gmm_separability(weights, labels, _groups(n), targets=centres, n_init=1, seed=0)


def _texts(fig: Figure) -> list:  # type: ignore[type-arg]
    """Every visible, non-empty text of the figure with its drawn box (display units)."""
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    out = []
    for ax in fig.axes:
        # the tick labels drawn: those of ticks within the view limits
        ticks = [t for axis in (ax.xaxis, ax.yaxis) for t in axis._update_ticks()]
        candidates = [
            *(t.label1 for t in ticks),
            *(t.label2 for t in ticks),
            ax.title,
            ax.xaxis.label,
            ax.yaxis.label,
            *ax.texts,
        ]
        if not ax.get_visible():
            continue
        legend = ax.get_legend()
        if legend is not None:
            candidates += legend.get_texts()
        for t in candidates:
            if t.get_visible() and t.get_text().strip():
                out.append((t.get_text(), t.get_window_extent(renderer)))
    for legend in fig.legends:
        out += [(t.get_text(), t.get_window_extent(renderer)) for t in legend.get_texts()]
    return out


def _draw(fig: Figure) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig).draw()


def overlapping_texts(fig: Figure) -> list[tuple[str, str]]:
    _draw(fig)
    boxes = _texts(fig)
    return [
        (a, b)
        for i, (a, ba) in enumerate(boxes)
        for b, bb in boxes[i + 1 :]
        if ba.overlaps(bb) and ba.intersection(ba, bb).width * ba.intersection(ba, bb).height > 1
    ]


def legends_over_data(fig: Figure) -> list[str]:
    """Axes whose legend lies (partly) inside the axes' own area."""
    _draw(fig)
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    bad = []
    for ax in fig.axes:
        legend = ax.get_legend()
        if legend is not None and legend.get_window_extent(renderer).overlaps(
            ax.get_window_extent(renderer)
        ):
            bad.append(ax.get_title())
        for legend in fig.legends:  # a figure legend must keep off every axes too
            if legend.get_window_extent(renderer).overlaps(ax.get_window_extent(renderer)):
                bad.append(f"figure legend over {ax.get_title()!r}")
    return bad


@pytest.mark.parametrize("n", [2, 8, 12])
def test_separability_layout_holds_for_2_to_12_groups(n: int, tmp_path: Path) -> None:
    sep = _separable(n)
    with plots.keep_figures() as figs:
        separability_figure(sep, tmp_path / "sep.png")
    (fig,) = figs
    assert overlapping_texts(fig) == []
    assert legends_over_data(fig) == []
    ax = fig.axes[0]
    assert "[" in ax.get_xlabel() and "[" in ax.get_ylabel()  # units
    # every group has its own look: (colour, marker) pairs are distinct
    looks = {
        (tuple(np.round(c.get_facecolor()[0], 3)), c.get_paths()[0].vertices.tobytes())
        for c in ax.collections
        if c.get_label() in sep.groups
    }
    assert len(looks) == n
    # no group label is written over the data (names are in the legend, outside)
    assert not ax.texts


@pytest.mark.parametrize("n", [2, 8, 12])
def test_bar_and_curve_figures_hold_for_2_to_12_groups(n: int, tmp_path: Path) -> None:
    groups = _groups(n)
    rng = np.random.default_rng(n)
    shares = rng.dirichlet(np.ones(4), n) * 100
    table = pd.DataFrame(shares, index=groups, columns=list(BIN_LABELS))
    spread = pd.DataFrame(
        {
            "group": groups,
            "mean proxy error": rng.uniform(0.1, 0.3, n),
            "noise 95th pct": rng.uniform(0.2, 0.4, n),
            "noise (same n)": rng.uniform(0.1, 0.3, n),
        }
    )
    panels = {g: rng.uniform(0, 1, (10, 6)) for g in groups}
    with plots.keep_figures() as figs:
        plots.bins(table, tmp_path / "bins.png")
        plots.spread(spread, tmp_path / "spread.png")
        plots.kl_curves({g: rng.uniform(0.01, 1, 5) for g in groups}, tmp_path / "kl.png")
        plots.final_distributions({g: rng.uniform(0, 1, 30) for g in groups}, tmp_path / "f.png")
        plots.generation_distributions(panels, tmp_path / "gen.png")
    for fig in figs:
        assert overlapping_texts(fig) == [], fig.axes[0].get_xlabel()
        assert legends_over_data(fig) == []
        for ax in fig.axes:
            if ax.get_visible():
                assert ax.get_xlabel() or ax.get_ylabel()
                # units on every quantity axis (a bar chart's group axis has names, no label)
                assert "[" in ax.get_xlabel(), ax.get_xlabel()
                assert not ax.get_ylabel() or "[" in ax.get_ylabel(), ax.get_ylabel()


def test_every_figure_in_each_format_png_at_300_dpi(tmp_path: Path) -> None:
    series = {"a": np.array([0.5, 0.2, 0.1]), "b": np.array([0.4, 0.3, 0.05])}
    with plots.formats(["svg,pdf"]) as chosen:
        assert chosen == ("png", "svg", "pdf")
        png = plots.kl_curves(series, tmp_path / "kl.png")
    assert png == tmp_path / "kl.png"
    with Image.open(png) as im:
        assert im.info["dpi"] == pytest.approx((300, 300), abs=0.01)
    ET.parse(tmp_path / "kl.svg")  # well-formed SVG
    assert ET.parse(tmp_path / "kl.svg").getroot().tag.endswith("svg")
    pdf = (tmp_path / "kl.pdf").read_bytes()
    assert pdf.startswith(b"%PDF-") and pdf.rstrip().endswith(b"%%EOF")
    # the default: PNG and SVG
    plots.kl_curves(series, tmp_path / "d" / "kl.png")
    assert sorted(p.name for p in (tmp_path / "d").iterdir()) == ["kl.png", "kl.svg"]
    with pytest.raises(ConfigError, match="--format must be one or more of png, svg, pdf"):
        plots.check_formats(["jpeg"])


def test_magnitudes_use_perceptual_colour_maps(tmp_path: Path) -> None:
    table = pd.DataFrame([[10.0, 20.0, 30.0, 40.0]], index=["g"], columns=list(BIN_LABELS))
    with plots.keep_figures() as figs:
        plots.bins(table, tmp_path / "bins.png")
    bars = [p for p in figs[0].axes[0].patches]
    colours = [p.get_facecolor() for p in bars]
    # ordered bins, ordered lightness (cividis), never a rainbow
    lightness = [0.2126 * r + 0.7152 * g + 0.0722 * b for r, g, b, _ in colours]
    assert lightness == sorted(lightness) and len(set(lightness)) == 4
    for name in ("jet", "turbo"):
        assert name not in plots.MAGNITUDE_MAPS


def test_rendered_sheets_are_300_dpi_and_go_into_the_vector_formats(tmp_path: Path) -> None:
    """Face sheets and heatmaps are renders (pixels): a 300-dpi PNG, and a PDF/SVG page
    holding them at that resolution."""
    image = np.zeros((60, 90, 3), np.uint8)
    image[:, 45:] = 200
    with plots.formats(["pdf", "svg"]):
        png = plots.save_image(tmp_path / "sheet.png", image)
    with Image.open(png) as im:
        assert im.info["dpi"] == pytest.approx((300, 300), abs=0.01)
        np.testing.assert_array_equal(np.asarray(im), image)
    assert (tmp_path / "sheet.pdf").read_bytes().startswith(b"%PDF-")
    root = ET.parse(tmp_path / "sheet.svg").getroot()
    assert root.attrib["width"] == "21.6pt"  # 90 px at 300 dpi = 0.3 in
