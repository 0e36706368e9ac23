"""The report's drawings of participants' dynamic prototypes: the weights a tile plays are the
curve formula at the frame times (a plain loop), averaged per participant then over them; the
animation of a participant's prototype is, pixel for pixel, `emogen render clip` of that
participant's final face from the export; bad input is refused by name and loses nothing."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from scipy.signal import fftconvolve

from emogen.errors import ConfigError
from emogen.ga.genome import DynamicGenome
from emogen.tasks.evolve.dynamic_prototypes import (
    StudyLook,
    emotion_tiles,
    face_genes,
    frame_times,
    key_frames,
)
from tests.ga.test_genome import curve_loop

GENOME = DynamicGenome()


def _rows(who: str, trial: int, genes: dict[str, list[float]], identity: str) -> list[dict]:
    """A final face's ``final_curves`` rows (latencies by the documented formula)."""
    out = []
    for gene, (amp, *timing) in genes.items():
        o, _, p, _, f = timing
        d, s = GENOME.clip_s, GENOME.min_segment_s
        t_on = o * (d - 2 * s)
        t_peak = t_on + s + p * (d - 2 * s - t_on)
        t_off = t_peak + s + f * (d - s - t_peak)
        out.append(
            {
                "participant_id": who, "session_id": hash(who) % 1000, "trial": trial,
                "block": 0, "block_name": "b", "emotion": "sad", "identity": identity,
                "gene": gene, "amplitude": amp, "onset": o, "acceleration": timing[1],
                "peak": p, "deceleration": timing[3], "offset": f,
                "onset_s": t_on, "peak_s": t_peak, "offset_s": t_off, "clip_s": d,
            }
        )  # fmt: skip
    return out


FACES = {
    ("p2", 0, "generic"): {"browInnerUp": [0.9, 0.1, 0.3, 0.2, 0.5, 0.5], "jawOpen": [0.4] * 6},
    ("p2", 1, "female"): {"browInnerUp": [0.5, 0.6, 0.9, 0.1, 0.0, 0.9]},
    ("p1", 0, "female"): {"mouthFrown": [0.7, 0.0, 0.5, 0.5, 0.5, 0.5]},
    ("p3", 0, "female"): {"eyeWide": [1.0, 0.3, 0.1, 0.6, 0.8, 0.2], "jawOpen": [0.2] * 6},
}


def _reference(rig: Any, genes: dict[str, list[float]], times: np.ndarray) -> np.ndarray:
    """Shape weights (T, S) of one face, a time, a gene and a shape at a time."""
    shapes = list(rig.shape_names)
    active = {g.name: g.shapes for g in rig.active_genes(True)}
    out = np.zeros((len(times), len(shapes)))
    for i, t in enumerate(times):
        for gene, (amp, *timing) in genes.items():
            for shape in active[gene]:
                out[i, shapes.index(shape)] = amp * curve_loop(timing, float(t))
    return out


def test_tiles_play_the_curve_formula_per_participant_then_over_them(ict_model: Any) -> None:
    rig = ict_model.rig
    rows = [r for (who, trial, ident), g in FACES.items() for r in _rows(who, trial, g, ident)]
    times = frame_times(GENOME)
    assert len(times) == 16 + 9  # 0 … 1.25 s at 12/s, then 0.75 s at rest
    tiles = emotion_tiles(pd.DataFrame(rows), rig, GENOME, times, eye_motion=True)
    assert [t.label for t in tiles] == ["mean of 3", "median of 3", "p1", "p2", "p3"]
    want = {
        "p1": _reference(rig, FACES[("p1", 0, "female")], times),
        "p2": (
            _reference(rig, FACES[("p2", 0, "generic")], times)
            + _reference(rig, FACES[("p2", 1, "female")], times)
        )
        / 2,
        "p3": _reference(rig, FACES[("p3", 0, "female")], times),
    }
    for tile in tiles[2:]:
        np.testing.assert_allclose(tile.weights, want[tile.label], atol=1e-12)
    stack = np.stack(list(want.values()))
    np.testing.assert_allclose(tiles[0].weights, stack.mean(axis=0), atol=1e-12)
    np.testing.assert_allclose(tiles[1].weights, np.median(stack, axis=0), atol=1e-12)
    assert tiles[3].n_faces == 2 and tiles[0].n_faces == 4
    # drawn on the identity most of its faces showed (a tie: the first name)
    assert [t.identity for t in tiles] == ["female", "female", "female", "female", "female"]
    assert key_frames(times, GENOME.clip_s).tolist() == [0, 3, 6, 9, 12, 15]


def test_bad_curves_and_study_records_are_refused_by_name(ict_model: Any) -> None:
    names = ict_model.rig.gene_names(True)
    rows = pd.DataFrame(_rows("p", 0, {"jawOpen": [0.5] * 6}, "generic"))
    with pytest.raises(ConfigError, match="'jawOpenWide'"):
        face_genes(rows.assign(gene="jawOpenWide"), names, GENOME)
    with pytest.raises(ConfigError, match=r"min-segment-s 0\.2"):
        face_genes(rows, names, DynamicGenome(min_segment_s=0.2))
    with pytest.raises(ConfigError, match="no study table"):
        StudyLook.of(None)
    static = pd.DataFrame({"config_json": [json.dumps({"blocks": [{"task": "evolve"}]})]})
    with pytest.raises(ConfigError, match="block 0 of the study's config has no dynamic"):
        StudyLook.of(static).genome(0)


# ---- the report's drawings against `emogen render clip` -----------------------------------
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def drawn(tmp_path_factory: pytest.TempPathFactory, ict_model: Any) -> dict[str, Any]:
    """A corrected dynamic study of 3 simulated participants (2 emotions, 3 generations),
    exported and analysed with its drawings, as ``emogen analyse`` does."""
    from emogen.analysis.analyse_options import AnalysisOptions
    from emogen.analysis.results import Section, write_analysis
    from emogen.analysis.study_export import StudyExport
    from emogen.analysis.task_sections import TaskTools
    from emogen.study.config import load_study_config
    from emogen.study.export_stream import export_study
    from emogen.study.simulate import SimulationPlan, simulate_study
    from emogen.study.storage import Store
    from emogen.tasks.evolve.dynamic_report import dynamic_section
    from emogen.tasks.simulated import SimulatedDesign

    tmp = tmp_path_factory.mktemp("prototypes")
    study = load_study_config(ROOT / "examples" / "dynamic.toml")
    study = study.model_copy(
        update={
            "blocks": study.blocks[:1],
            "emotions": ("sad", "fearful"),
            "ga": study.ga.model_copy(update={"generations": 3}),
            "correct": True,
        }
    )
    url = f"sqlite:///{tmp / 'study.sqlite'}"
    plan = SimulationPlan(study, url, 5, 3, SimulatedDesign(), shuffle_prototypes=False)
    simulate_study(plan, model=ict_model)
    store = Store(url)
    try:
        export_study(store, tmp / "export", "csv")
    finally:
        store.dispose()

    def analyse(export: Path, out: Path) -> dict[str, Any]:
        opts = AnalysisOptions(exclusions=None)
        tools = TaskTools(StudyExport(export), Section(out), opts, ict_model)
        report = dynamic_section(tools)
        assert report is tools.report
        write_analysis("dynamic", out, [report], {})
        result: dict[str, Any] = report.data["dynamic"]
        return result

    return {"tmp": tmp, "summary": analyse(tmp / "export", tmp / "report"), "analyse": analyse}


def _find(image: np.ndarray, tile: np.ndarray) -> tuple[int, int, float]:
    """Where ``tile`` sits in ``image`` (top-left y, x) by least squared difference (summed
    over channels, by FFT), and its mean absolute difference there."""
    a, t = image.astype(np.float64), tile.astype(np.float64)
    ones = np.ones(t.shape[:2])
    sq = fftconvolve((a**2).sum(-1), ones, mode="valid")
    cross = sum(fftconvolve(a[..., c], t[::-1, ::-1, c], mode="valid") for c in range(3))
    ssd = sq - 2 * cross + (t**2).sum()
    y, x = np.unravel_index(int(np.argmin(ssd)), ssd.shape)
    h, w = t.shape[:2]
    return int(y), int(x), float(np.abs(a[y : y + h, x : x + w] - t).mean())


def _clip_frames(drawn: dict[str, Any], ict_dir: Path, face: pd.Series) -> np.ndarray:
    """`emogen render clip` of the export's final face ``face``, as the study showed it."""
    from typer.testing import CliRunner

    from emogen.render.images import read_png
    from tests.render.test_clip import app

    folder = drawn["tmp"] / f"clip-{face.session_id}-{face.trial}"
    select = [
        f"--select={k}={face[k]}"
        for k in ("session_id", "trial", "attempt", "generation", "face_id")
    ]
    args = ["render", "clip", str(drawn["tmp"] / "export" / "face_curves.csv"), *select,
            "--model", str(ict_dir), "--identity", str(face.identity), "--size", "128",
            "--fps", "12", "--correct", "--out", str(folder)]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    return np.stack([read_png(p) for p in sorted(folder.glob("frame_*.png"))])


def test_each_participants_animation_is_their_final_face_as_render_clip_draws_it(
    drawn: dict[str, Any], ict_dir: Path
) -> None:
    from emogen.render.animation import read_animation
    from emogen.render.images import read_png
    from tests.render.test_golden import MAX_FRACTION_OFF, MAX_MEAN_ABS, compare

    summary = drawn["summary"]["prototypes"]
    assert summary["drawn"] and "dynamic_block1_sad.webp" in summary["files"]
    figures = drawn["tmp"] / "report" / "figures"
    packed, durations = read_animation(figures / "dynamic_block1_sad.webp")
    frames = np.repeat(packed, [round(d / 83) for d in durations], axis=0)  # 83 ms a frame
    finals = pd.read_csv(drawn["tmp"] / "export" / "final_faces.csv")
    finals = finals[finals.emotion == "sad"].sort_values("participant_id")
    columns = []
    for _, face in finals.iterrows():
        want = _clip_frames(drawn, ict_dir, face)
        assert len(want) == len(frames) == 25  # 0 … 1.25 s at 12/s, then the hold at rest
        moving = int(np.argmax([np.abs(w.astype(int) - want[0]).sum() for w in want]))
        y, x, off = _find(frames[moving], want[moving])
        assert off < MAX_MEAN_ABS, (face.participant_id, off)
        for got, ref in zip(frames[:, y : y + 128, x : x + 128], want, strict=True):
            mean_abs, fraction = compare(got, ref)
            assert mean_abs < MAX_MEAN_ABS and fraction < MAX_FRACTION_OFF
        columns.append(x)
        if face.participant_id == finals.participant_id.iloc[0]:  # the first one's sheet row
            sheet = read_png(figures / "dynamic_block1_sad_keys_1.png")
            for k in (3, 6, 9):  # key frames at 0.25, 0.5, 0.75 s
                assert _find(sheet, want[k])[2] < MAX_MEAN_ABS
    # the mean and the median first, then the participants by id, left to right
    assert columns == sorted(columns) and columns[0] > 2 * 128
    html = (drawn["tmp"] / "report" / "index.html").read_text()
    assert '<img src="figures/dynamic_block1_sad.webp"' in html
    assert (
        "](figures/dynamic_block1_sad.webp)" in (drawn["tmp"] / "report" / "README.md").read_text()
    )


def test_a_drawing_that_fails_says_why_and_keeps_the_analysis(
    drawn: dict[str, Any], tmp_path: Path
) -> None:
    import shutil

    export = tmp_path / "export"
    shutil.copytree(drawn["tmp"] / "export", export)
    finals = pd.read_csv(export / "final_faces.csv")
    finals.assign(identity="nobody").to_csv(export / "final_faces.csv", index=False)
    summary = drawn["analyse"](export, tmp_path / "report")
    assert not summary["prototypes"]["drawn"]
    assert "unknown identity 'nobody'" in summary["prototypes"]["why"]
    text = (tmp_path / "report" / "README.md").read_text()
    assert "prototypes are not drawn: unknown identity 'nobody'" in text
    assert (tmp_path / "report" / "tables" / "dynamic_timing.csv").is_file()
    assert summary["timing_tests"], "the timing test is kept"
