"""Data quality per participant and session: durations, response times and where on screen the
picks were (position bias).

**Which tile a pick was on.** A selection's ``face_id`` is looked up in the export's ``faces``
table (its ``position``, 0 … K−1 on screen, in display order). Only **generation 0** is
position-neutral: its population is the shuffled protocol initialisation, whereas from
generation 1 on tile 0 holds the carried elite and each further tile a fixed operator (elitism,
crossovers, mutants: Algorithm 1), so a conscientious participant who keeps their best face
picks tile 0 often. Position bias is therefore tested on generation-0 picks, and the share of
elites on tile 0 over all generations is shown for description only.

**Position-bias test** (:func:`position_bias`): per participant, the chi-square statistic of
their generation-0 pick counts per tile against uniform; its p-value by Monte Carlo under the
null that each generation's m picks are a uniformly random m-subset of the K tiles (exact in the
limit, valid for few picks, and for several picks without replacement, where the multinomial
chi-square would not be). Overall: the sum of the participants' statistics against the sum of
independent nulls (the participant the unit: each contributes one statistic).

**Response time**: ``client_response_ms`` (faces drawn → submit, in the browser); where the
browser did not report it, ``server_response_ms`` (includes the network) for real participants,
and none for simulated ones (``participant_source = simulated``: their server times are machine
times, not decisions).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from emogen.analysis.people import People
from emogen.errors import ConfigError

PICK_KEY = ["session_id", "trial", "attempt", "generation", "face_id"]


def selection_positions(people: People) -> pd.DataFrame | None:
    """The selections with ``position`` (tile), ``n_tiles`` and ``rt_ms`` (see the module
    docstring); None when the export has no selections or no faces table to place them."""
    sel = people.selections
    if sel is None or sel.empty:
        return None
    tiles = sel["position"].max() if "position" in sel.columns else np.nan
    if "position" not in sel.columns:
        faces = None if people.export is None else people.export.table("faces")
        if faces is None or "position" not in faces.columns:
            return None
        sel = sel.merge(faces[[*PICK_KEY, "position"]], on=PICK_KEY, how="left")
        tiles = faces["position"].max()
    return sel.assign(
        participant_id=sel["participant_id"].astype(str),
        position=pd.to_numeric(sel["position"], errors="coerce"),
        rt_ms=_response_times(sel),
        n_tiles=int(tiles) + 1,
    )


def _response_times(sel: pd.DataFrame) -> pd.Series:
    nan = pd.Series(np.nan, index=sel.index)
    client = (
        pd.to_numeric(sel["client_response_ms"], errors="coerce")
        if "client_response_ms" in sel
        else nan
    )
    server = (
        pd.to_numeric(sel["server_response_ms"], errors="coerce")
        if "server_response_ms" in sel
        else nan
    )
    source = (
        sel["participant_source"] if "participant_source" in sel else pd.Series("", index=sel.index)
    )
    return client.fillna(server.where(source != "simulated")).astype(float)


def _chi2(counts: np.ndarray, total: np.ndarray) -> np.ndarray:
    """Chi-square of count rows (…, K) against uniform over K, per row."""
    k = counts.shape[-1]
    expect = total[..., None] / k
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(
            expect > 0, (counts - expect) ** 2 / np.where(expect > 0, expect, 1), 0
        ).sum(axis=-1)


def _null_counts(m: np.ndarray, k: int, draws: int, rng: np.random.Generator) -> np.ndarray:
    """(draws, K) tile counts when each of the events picks m[j] tiles uniformly at random."""
    counts = np.zeros((draws, k))
    for size in np.unique(m):
        events = int((m == size).sum())
        keys = rng.random((draws, events, k)).argsort(axis=2)[:, :, : int(size)]
        for d in range(draws):
            counts[d] += np.bincount(keys[d].ravel(), minlength=k)
    return counts


def position_bias(
    picks: pd.DataFrame, n_tiles: int, *, draws: int, rng: np.random.Generator
) -> tuple[pd.DataFrame, dict[str, float]]:
    """Per participant: generation-0 picks per tile, the chi-square against uniform and its
    Monte Carlo p; and the overall test (see the module docstring). ``picks``: rows with
    ``participant_id``, ``session_id``, ``trial``, ``attempt``, ``generation``, ``position``."""
    g0 = picks[(picks["generation"] == 0) & picks["position"].notna()]
    if g0.empty:
        raise ConfigError("no generation-0 selections with a tile position")
    rows, null_sum = [], np.zeros(draws)
    for pid, mine in g0.groupby("participant_id", sort=True):
        counts = np.bincount(mine["position"].astype(int), minlength=n_tiles)[:n_tiles]
        m = mine.groupby(["session_id", "trial", "attempt"]).size().to_numpy()
        stat = float(_chi2(counts[None].astype(float), np.array([counts.sum()]))[0])
        null = _null_counts(m, n_tiles, draws, rng)
        null_stat = _chi2(null, null.sum(axis=1))
        null_sum += null_stat
        top = int(np.argmax(counts))
        rows.append(
            {
                "participant_id": str(pid),
                "picks": int(counts.sum()),
                "events": len(m),
                "top_tile": top,
                "top_tile_share": counts[top] / counts.sum(),
                "chi2": stat,
                "p_mc": (1 + int((null_stat >= stat - 1e-9).sum())) / (draws + 1),
            }
        )
    table = pd.DataFrame(rows)
    total = float(table["chi2"].sum())
    overall = {
        "chi2_sum": total,
        "p_mc": (1 + int((null_sum >= total - 1e-9).sum())) / (draws + 1),
        "participants": float(len(table)),
        "draws": float(draws),
    }
    return table, overall


def participant_quality(people: People) -> pd.DataFrame:
    """One row per participant × session: ``session_minutes`` (consent → completion),
    ``trials_planned``, ``trials_finished``, ``finished_share``, ``median_trial_s``,
    ``median_rt_ms`` (all selections), ``elite_tile0_share`` (all generations, descriptive)."""
    t = people.trials
    base = t.groupby(["participant_id", "session_id"]).agg(
        trials_planned=("trial", "size"),
        trials_finished=("status", lambda s: int((s == "done").sum())),
    )
    base["finished_share"] = base["trials_finished"] / base["trials_planned"]
    dur = people.faces.groupby(["participant_id", "session_id"])["duration_s"].median()
    base["median_trial_s"] = dur.reindex(base.index)
    base["session_minutes"] = _session_minutes(people).reindex(base.index)
    sel = selection_positions(people)
    if sel is not None:
        key = ["participant_id", "session_id"]
        base["median_rt_ms"] = sel.groupby(key)["rt_ms"].median().reindex(base.index)
        elite = sel[sel["role"] == "elite"] if "role" in sel.columns else sel
        tile0 = (elite["position"] == 0).groupby([elite[k] for k in key]).mean()
        base["elite_tile0_share"] = tile0.reindex(base.index)
    else:
        base["median_rt_ms"] = np.nan
        base["elite_tile0_share"] = np.nan
    return base.reset_index()


def _session_minutes(people: People) -> pd.Series:
    s = people.sessions
    if s is None or "completed_at" not in s.columns:
        return pd.Series(dtype=float)
    start_col = "consented_at" if "consented_at" in s.columns else "started_at"
    start = pd.to_datetime(s[start_col], utc=True, errors="coerce")
    end = pd.to_datetime(s["completed_at"], utc=True, errors="coerce")
    idx = pd.MultiIndex.from_arrays([s["participant_id"].astype(str), s["session_id"]])
    return pd.Series(((end - start).dt.total_seconds() / 60).to_numpy(), index=idx)
