"""``emogen analyse``'s section on a study's dynamic evolve blocks
(:mod:`emogen.tasks.evolve.dynamic_analysis`): per emotion the participants' peak latencies
with intervals, each gene's temporal profile across participants, and the test of whether
timing differs between emotions (participants as the unit)."""

from __future__ import annotations

import time
from contextlib import ExitStack
from typing import Any

import numpy as np
import pandas as pd

from emogen.errors import EmoGenError
from emogen.render import Renderer
from emogen.tasks.evolve.dynamic_analysis import (
    PERMUTATIONS,
    TimingTest,
    emotion_timing,
    final_curves,
    gene_profiles,
    participant_timing,
    timing_test,
)
from emogen.tasks.evolve.dynamic_prototypes import (
    FPS,
    KEY_FRAMES,
    SHEET_ROWS,
    TILE_PX,
    StudyLook,
    draw_block,
)


def dynamic_section(tools: Any) -> Any:
    """The section, ``tools.report`` filled (None where the export has no dynamic faces);
    ``tools``: :class:`emogen.analysis.task_sections.TaskTools`."""
    report, opts = tools.report, tools.opts
    face_curves = tools.table("face_curves")
    finals = tools.table("final_faces")
    if face_curves is None or face_curves.empty:
        return None
    report.heading("Dynamic faces: timing")
    curves = final_curves(finals, face_curves) if finals is not None else face_curves.iloc[:0]
    if curves.empty:
        report.paragraph("No timing analysis: no finished dynamic evolve trial yet.")
        report.data["dynamic"] = {"note": "no finished dynamic trial"}
        return report
    rng = np.random.default_rng(opts.seed)
    timing = participant_timing(curves)
    level = int(100 * (1 - opts.alpha))
    report.paragraph(
        f"{len(timing)} participant × emotion values from {curves['participant_id'].nunique()} "
        "participants' final dynamic faces. The participant is the unit: a face's peak "
        "latency is when its motion (the sum of its genes' squared weights) is greatest, its "
        "onset and offset when that first and last reaches 10% of the peak; a participant's "
        f"value is the mean over their final faces of the emotion; {level}% percentile "
        "bootstrap intervals over participants."
    )
    by_emotion = emotion_timing(timing, rng, opts.alpha)
    report.table(
        by_emotion.round(3),
        name="dynamic_timing",
        caption="Peak latency (s) of each emotion's final faces across participants [interval]; "
        "mean onset and offset latencies (every participant's values: the CSV).",
        data=timing,
    )
    _strip(timing, tools)
    profiles = gene_profiles(curves, rng, opts.alpha)
    shown = profiles.sort_values(
        ["block_name", "emotion", "amplitude"], ascending=[True, True, False]
    ).groupby(["block_name", "emotion"], sort=True)
    report.table(
        shown.head(5).round(3).reset_index(drop=True),
        name="dynamic_gene_profiles",
        caption="Each emotion's five strongest genes: mean amplitude across participants (0 "
        "where not shown) and peak latency (s) of the participants whose faces show the gene, "
        "with intervals (every gene: the CSV).",
        data=profiles,
    )
    tests = []
    for block in sorted(timing["block_name"].unique()):
        test = timing_test(timing, str(block), rng, opts.alpha)
        if test is not None:
            tests.append(test.to_dict())
            _add_test(report, test, tests[-1], 1 - opts.alpha)
    if tests:
        report.table(
            pd.DataFrame(tests).drop(columns=["emotions"]).round(4),
            name="dynamic_timing_test",
            caption="Does timing differ between emotions? Repeated-measures F of participants' "
            f"peak latencies, p from {PERMUTATIONS} permutations of the emotion labels within "
            f"participants; partial η² with its {level}% bootstrap interval over participants "
            "(participants with every emotion of the block).",
        )
    else:
        report.paragraph("No timing test: it needs two emotions and three participants with both.")
    report.data["dynamic"] = {
        "n_participants": int(curves["participant_id"].nunique()),
        "timing_tests": tests,
        "prototypes": _prototypes(tools, curves),
    }
    return report


def _add_test(report: Any, test: TimingTest, record: dict[str, Any], level: float) -> None:
    """The block's timing test as a typed result of the report (``record``: its JSON)."""
    report.add_test(
        f"dynamic.timing_tests[{test.block_name}]",
        record,
        test="repeated-measures F, permutation p",
        p=test.p_value,
        statistic=test.f,
        n=test.n_participants,
        level=level,
        effect=("partial eta2", test.eta2, test.eta2_low, test.eta2_high),
    )


def _strip(timing: pd.DataFrame, tools: Any) -> None:
    """Each participant's peak latency per emotion, with the emotion's mean."""
    fig = tools.new_figure(5.0, 3.0)
    ax = fig.subplots()
    emotions = sorted(timing["emotion"].unique())
    for i, emotion in enumerate(emotions):
        peaks = timing.loc[timing["emotion"] == emotion, "peak_s"].to_numpy()
        jitter = np.linspace(-0.15, 0.15, len(peaks)) if len(peaks) > 1 else np.zeros(1)
        ax.plot(i + jitter, peaks, "o", ms=3, alpha=0.6, color=tools.style(i)["color"])
        ax.plot([i - 0.25, i + 0.25], [peaks.mean()] * 2, "-", color="black")
    ax.set_xticks(range(len(emotions)), emotions)
    ax.set_ylabel("peak latency (s)")
    ax.grid(alpha=0.3, axis="y")
    tools.save_figure(
        fig,
        "dynamic_peak_latency.png",
        "Participants' peak latencies by emotion (one dot per participant; bar: the mean).",
    )


def _prototypes(tools: Any, curves: pd.DataFrame) -> dict[str, Any]:
    """The participants' dynamic prototypes drawn (:mod:`.dynamic_prototypes`): what was
    drawn and how long it took, or why nothing was."""
    report, model = tools.report, tools.model
    report.heading("Participants' dynamic prototypes", level=3)
    if model is None or not tools.opts.render:
        why = "no face model, or --no-render"
        report.paragraph(f"The participants' dynamic prototypes are not drawn: {why}.")
        return {"drawn": False, "why": why}
    started = time.perf_counter()
    drawings = []
    try:
        look = StudyLook.of(tools.table("study"))
        with ExitStack() as stack:
            renderers: dict[str, Renderer] = {}

            def renderer_for(name: str) -> Renderer:
                if name not in renderers:
                    ident = tools.identity(name)
                    r = Renderer(model.with_identity(ident.shape), size=TILE_PX,
                                 appearance=ident.appearance, framing=look.framing)  # fmt: skip
                    renderers[name] = stack.enter_context(r)
                return renderers[name]

            for _, rows in curves.groupby("block_name", sort=True):
                drawings.append(draw_block(rows, look, model.rig, renderer_for, report.figures))
    except EmoGenError as exc:
        report.paragraph(f"The participants' dynamic prototypes are not drawn: {exc}.")
        return {"drawn": False, "why": str(exc)}
    seconds = time.perf_counter() - started
    corrected = (
        "corrected frame by frame as the study corrected its faces"
        if look.correct
        else "uncorrected, as the study showed its faces"
    )
    report.paragraph(
        "Each participant's dynamic prototype of an emotion is the mean, frame by frame, of "
        "the face weights of their final faces of it (one final face: that face's clip); the "
        "emotion's mean and median are taken over participants frame by frame. Each is drawn on "
        f"the identity most of its faces showed, through the study's framing, {corrected}"
        f" — the frames of `emogen render clip`, {FPS:g} frames/s at {TILE_PX} px a face; "
        f"the key-frame sheets (for print) show the {KEY_FRAMES} frames nearest evenly spaced "
        f"times over the clip, {SHEET_ROWS} participants a sheet. Drawn in {seconds:.0f} s "
        "(`--no-render` skips it; every tile: `tables/dynamic_prototype_tiles.csv`)."
    )
    tiles = [row for d in drawings for row in d.tiles]
    report.csv(pd.DataFrame(tiles), "dynamic_prototype_tiles")
    for d in drawings:
        for path, caption in d.figures:
            report.figure(path, caption)
    return {
        "drawn": True,
        "seconds": round(seconds, 1),
        "fps": FPS,
        "tile_px": TILE_PX,
        "files": [p.name for d in drawings for p, _ in d.figures],
    }
