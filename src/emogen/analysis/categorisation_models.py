"""Categorisation predicted by the distance of a test face to the participant's own faces
(Binetti et al. 2022, PNAS 119:e2201380119): P(label = e) as a function of d_e, the distance from
the test face to the participant's own final faces of emotion e.

**Distances.** Gene space (the GA's search space, ``g_*`` in [0, 1]), Euclidean, from the test
face's genes to the mean genes of the participant's final faces of e (every identity and
repetition pooled). File faces have no genes and are not in the model.

**Which answers.** Answers to faces the participant did *not* make (``other`` and ``random``
faces, fallbacks included; answers ``none`` left out). Own faces are left out because the
participant's other repetitions of an emotion were made toward the same internal face as the test
face: their distance predicts the label of an own face even when the labelling owes nothing to
the labeller's own prototypes (a maker effect, not a labeller effect) — leaving the test face out
of its own mean does not remove that.

**The null and the competing covariate.** Distance to one's own faces of e predicts the label e
even without any individual prototype, because everyone's faces of e lie near the population's
prototype of e. The test of the individual effect therefore sets own distance against the same
distance to another participant's faces: each participant i is given a reference participant
σ(i) (σ a random derangement: nobody is their own reference), d_ref,e the distance to σ(i)'s
final faces of e, and answers to faces σ(i) made are left out. Without an individual effect own
and reference faces are exchangeable, so the two slopes have the same distribution: the test is
the contrast β_own − β_ref = 0 (negative: one's own faces predict one's labels better).

**Models.**

* primary: the pooled conditional logit (McFadden 1974) of the label chosen among those
  offered on d_own, d_ref and one constant per label, its slopes and contrast with participant-
  and stimulus-level (two-way) cluster-robust intervals (Cameron, Gelbach & Miller 2011; why
  this and not a crossed random-effects GLMM: :mod:`emogen.analysis.categorisation_clogit`),
  tested by the shuffled-prototype permutation over participants below (the two-way t test of
  the contrast on min(participants, faces) − 1 degrees of freedom is kept as ``p_two_way``: on
  planted studies it found an own-face effect less often than the unclustered pooled fit, and a
  swap of each participant's own and reference faces was conservative (1.5% at α 0.05) and
  weaker still — docs/analysis.md);
* secondary, population-averaged: a GEE on the long table (answer × offered label, chosen
  0/1, d_own, d_ref, one intercept per label), binomial family, logit link, exchangeable
  working correlation within participant (independence as the named fallback when that fit
  fails), robust (sandwich) standard errors over participants (statsmodels ``GEE``; Liang &
  Zeger 1986); faces are not clusters here;
* secondary, two-stage: per participant the maximum-likelihood conditional logit of the chosen
  label on d_own and d_ref (unpenalised; a participant whose labels are perfectly separated
  has no estimate and is named and left out), then a one-sample t and a Wilcoxon signed-rank
  test of the per-participant contrasts over participants;
* the primary test, shuffled prototypes, a permutation over participants: the pooled
  conditional-logit slope on own distance against the same slope with every participant's own faces replaced by
  another participant's (``n_shuffles`` random derangements; answers to faces made by the
  stand-in left out); one-sided p = (1 + #{shuffled ≤ own}) / (1 + n_shuffles).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from emogen.analysis.categorisation_clogit import clogit_contrast, conditional_logit
from emogen.analysis.categorisation_fits import (
    gee_contrast,
    label_constants,
    per_participant_slopes,
    two_stage,
)
from emogen.analysis.people import People


@dataclass(frozen=True, eq=False)
class ModelAnswers:
    """The answers the model reads, as arrays. participants: everyone with final faces (the
    index space of ``who``, ``maker`` and a reference); means: (participants, emotions, genes)
    mean genes of each one's final faces of each emotion (NaN where none); who, maker: (answers,)
    the answerer and the face's maker (-1: nobody's, a random face); genes: (answers, genes);
    offered: (answers, emotions) the labels offered; chosen: (answers,) the label's index;
    stimulus: (answers,) which face was shown (answers to identical genes share a number)."""

    participants: tuple[str, ...]
    emotions: tuple[str, ...]
    means: np.ndarray
    who: np.ndarray
    maker: np.ndarray
    genes: np.ndarray
    offered: np.ndarray
    chosen: np.ndarray
    source: np.ndarray
    trial: np.ndarray
    stimulus: np.ndarray


def model_answers(people: People) -> ModelAnswers | str:
    """The answers to faces the participant did not make, with their genes; or why none."""
    r = people.responses
    if r is None or r.empty or "label" not in r.columns:
        return "no categorise answers (no categorise block, or nobody has reached it yet)"
    genes = list(people.genes)
    missing = sorted({"participant_id", "source", *genes} - set(r.columns))
    if missing:
        return f"the responses table lacks column(s) {missing[:3]}"
    emotions = people.emotions
    r = r[r["label"].isin(emotions) & r["source"].isin(["other", "random"])]
    r = r[np.isfinite(r[genes].to_numpy(dtype=np.float64)).all(axis=1)]
    if r.empty:
        return "no answer names an emotion for a face of another participant or a random face"
    ids = tuple(sorted(people.faces["participant_id"].astype(str).unique()))
    index = {p: i for i, p in enumerate(ids)}
    who = r["participant_id"].astype(str).map(index)
    r, who = r[who.notna()], who[who.notna()]
    maker_col = r["source_participant_id"] if "source_participant_id" in r.columns else None
    maker = (
        maker_col.astype(str).map(index).fillna(-1).to_numpy(dtype=np.int64)
        if maker_col is not None
        else np.full(len(r), -1)
    )
    maker[r["source"].to_numpy() != "other"] = -1
    offered = _offered(r, emotions)
    means = np.full((len(ids), len(emotions), len(genes)), np.nan)
    f = people.faces.assign(participant_id=people.faces["participant_id"].astype(str))
    for (pid, emotion), rows in f.groupby(["participant_id", "emotion"])[genes]:
        means[index[pid], emotions.index(str(emotion))] = rows.to_numpy(dtype=np.float64).mean(0)
    gene_values = r[genes].to_numpy(dtype=np.float64)
    _faces, stimulus = np.unique(np.round(gene_values, 9), axis=0, return_inverse=True)
    return ModelAnswers(
        participants=ids,
        emotions=emotions,
        means=means,
        who=who.to_numpy(dtype=np.int64),
        maker=maker,
        genes=gene_values,
        offered=offered,
        chosen=r["label"].map({e: k for k, e in enumerate(emotions)}).to_numpy(dtype=np.int64),
        source=r["source"].astype(str).to_numpy(),
        trial=(r["trial"] if "trial" in r.columns else pd.Series(np.arange(len(r)))).to_numpy(
            dtype=np.int64
        ),
        stimulus=stimulus.reshape(-1).astype(np.int64),
    )


def _offered(r: pd.DataFrame, emotions: tuple[str, ...]) -> np.ndarray:
    """(answers, emotions) which labels each answer offered (every emotion without ``labels``)."""
    if "labels" not in r.columns:
        return np.ones((len(r), len(emotions)), dtype=bool)
    sets = [set(str(s).split("|")) if isinstance(s, str) else set(emotions) for s in r["labels"]]
    return np.array([[e in s for e in emotions] for s in sets], dtype=bool).reshape(len(r), -1)


def derangement(n: int, rng: np.random.Generator) -> np.ndarray:
    """A random permutation of range(n) with no fixed point (n >= 2)."""
    while True:
        p = rng.permutation(n)
        if not np.any(p == np.arange(n)):
            return p


def distances(ans: ModelAnswers, reference: np.ndarray) -> np.ndarray:
    """(answers, emotions) gene ED from each test face to the mean face of each emotion of the
    answerer's ``reference`` participant (``reference = arange``: their own faces)."""
    centres = ans.means[reference[ans.who]]  # (answers, emotions, genes)
    return np.asarray(np.linalg.norm(ans.genes[:, None, :] - centres, axis=2))


def usable(
    ans: ModelAnswers, *dists: np.ndarray, reference: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(answers,) which answers a model can use and (answers, emotions) which labels: offered,
    with finite distances, the chosen label among them, >= 2 labels; a face the ``reference``
    participant made is left out."""
    avail = ans.offered.copy()
    for d in dists:
        avail &= np.isfinite(d)
    keep = avail[np.arange(len(ans.chosen)), ans.chosen] & (avail.sum(axis=1) >= 2)
    if reference is not None:
        keep &= ans.maker != reference[ans.who]
    return keep, avail


def long_table(ans: ModelAnswers, reference: np.ndarray) -> pd.DataFrame:
    """The model's long table: one row per usable answer × offered label (see docs/data.md)."""
    own = distances(ans, np.arange(len(ans.participants)))
    ref = distances(ans, reference)
    keep, avail = usable(ans, own, ref, reference=reference)
    n, e = np.nonzero(avail & keep[:, None])
    ids = np.array(ans.participants, dtype=object)
    return pd.DataFrame(
        {
            "participant_id": ids[ans.who[n]],
            "answer": n.astype(np.int64),
            "trial": ans.trial[n],
            "source": ans.source[n],
            "stimulus": ans.stimulus[n],
            "reference_participant_id": ids[reference[ans.who[n]]],
            "label": np.array(ans.emotions, dtype=object)[e],
            "chosen": (ans.chosen[n] == e).astype(np.int64),
            "d_own": own[n, e],
            "d_ref": ref[n, e],
        }
    )


def shuffled_control(
    ans: ModelAnswers, *, n_shuffles: int, rng: np.random.Generator
) -> dict[str, Any]:
    """The pooled conditional-logit slope on own distance (with label constants) against the
    same slope with each participant's faces replaced by a derangement's (module docstring).
    A shuffle whose fit has no estimate is left out and counted; without the observed slope,
    ``status`` is ``failed``."""
    n_people = len(ans.participants)

    def slope(reference: np.ndarray) -> tuple[float, str]:
        d = distances(ans, reference)
        keep, avail = usable(ans, d, reference=reference)
        avail = avail[keep] & (np.bincount(ans.chosen[keep], minlength=avail.shape[1]) > 0)
        keep_rows = avail.sum(axis=1) >= 2
        x = np.concatenate([d[keep][..., None], label_constants(avail)], axis=2)
        fit = conditional_logit(x[keep_rows], avail[keep_rows], ans.chosen[keep][keep_rows])
        return (float(fit.beta[0]), "") if fit.converged else (float("nan"), fit.reason)

    out: dict[str, Any] = {
        "test": "permutation over participants (own faces replaced by another's, derangements)",
        "unit": "participant",
        "n_shuffles": n_shuffles,
        "warnings": [],
    }
    observed, reason = slope(np.arange(n_people))
    if not np.isfinite(observed):
        gone = ("slope_own", "control_mean", "control_low", "control_high", "p")
        return out | dict.fromkeys(gone) | {"status": "failed", "reason": reason}
    control = np.array([slope(derangement(n_people, rng))[0] for _ in range(n_shuffles)])
    failed = int(np.sum(~np.isfinite(control)))
    control = control[np.isfinite(control)]
    if failed:
        out["warnings"].append(f"{failed} of {n_shuffles} shuffles had no estimate; left out")
    if not len(control):
        keys = ("control_mean", "control_low", "control_high", "p")
        reason = "no shuffle had an estimate"
        return (
            out
            | dict.fromkeys(keys)
            | {"slope_own": observed, "status": "failed", "reason": reason}
        )
    return out | {
        "status": "ok",
        "reason": "",
        "slope_own": observed,
        "control_mean": float(control.mean()),
        "control_low": float(np.quantile(control, 0.025)),
        "control_high": float(np.quantile(control, 0.975)),
        "n_shuffles_fitted": len(control),
        "p": float((1 + np.sum(control <= observed)) / (1 + len(control))),
        "control": control,
    }


#: The fewest participants with usable answers the own-distance model is fitted on.
MIN_PARTICIPANTS = 6


@dataclass(frozen=True, eq=False)
class OwnDistance:
    """The own-distance model of a study: the long table, the per-participant slopes, and the
    four tests as dicts: the primary (:func:`primary_test`: the conditional logit with two-way
    clustered CIs, tested by the shuffled-prototype permutation), and the secondary GEE
    contrast, two-stage and shuffled-prototype control (the primary test's details)."""

    table: pd.DataFrame
    slopes: pd.DataFrame
    primary: dict[str, Any]
    gee: dict[str, Any]
    two_stage: dict[str, Any]
    control: dict[str, Any]


def own_distance(
    people: People, *, rng: np.random.Generator, n_shuffles: int = 199, confidence: float = 0.95
) -> OwnDistance | str:
    """The own-distance model of ``people`` (module docstring), or one line why it cannot be
    fitted. The reference participants are one derangement drawn from ``rng``; the shuffled
    control draws ``n_shuffles`` more."""
    ans = model_answers(people)
    if isinstance(ans, str):
        return ans
    if len(ans.participants) < MIN_PARTICIPANTS:
        return (
            f"{len(ans.participants)} participants made faces; the own-distance model needs "
            f"at least {MIN_PARTICIPANTS}"
        )
    reference = derangement(len(ans.participants), rng)
    table = long_table(ans, reference)
    people_n = table["participant_id"].nunique()
    if people_n < MIN_PARTICIPANTS:
        return (
            f"{people_n} participants answered faces they did not make (other participants' or "
            f"random faces); the own-distance model needs at least {MIN_PARTICIPANTS}"
        )
    slopes = per_participant_slopes(table)
    control = shuffled_control(ans, n_shuffles=n_shuffles, rng=rng)
    return OwnDistance(
        table=table,
        slopes=slopes,
        primary=primary_test(clogit_contrast(table, confidence), control),
        gee=gee_contrast(table, confidence),
        two_stage=two_stage(slopes, confidence),
        control=control,
    )


def primary_test(clogit: dict[str, Any], control: dict[str, Any]) -> dict[str, Any]:
    """The primary result: the pooled conditional logit's slopes and contrast with their two-way
    cluster-robust CIs (``clogit``), tested by the shuffled-prototype permutation over
    participants (``control``'s one-sided p; the two-way t test's two-sided p is kept as
    ``p_two_way``). Chosen on planted studies (docs/analysis.md): at α under the null and more
    powerful than the two-way t test and the unclustered pooled fit. Without an estimate from
    either part, ``status`` is ``failed`` with its reason."""
    out = clogit | {
        "test": "shuffled-prototype permutation over participants (one-sided: own faces "
        "predict labels better than another participant's)",
        "unit": "participant (test); participant and face (two-way cluster-robust CIs)",
        "p_two_way": clogit["p"],
        "p": control["p"] if clogit["status"] == "ok" else None,
        "n_shuffles": control["n_shuffles"],
        "warnings": clogit["warnings"] + control["warnings"],
    }
    if clogit["status"] == "ok" and control["status"] != "ok":
        out.update(status="failed", reason=f"the permutation test failed: {control['reason']}")
    return out
