"""Identity effects within participants: does the face a participant makes for an emotion
depend on the identity it is made on? (Murray et al. 2024, *Emotion* 24:495.)

* **Distances** (:func:`identity_distances`, :func:`within_between_test`): per participant and
  emotion, the mean gene-space Euclidean distance between two of their final faces made on the
  *same* identity (repetitions) and between two made on *different* identities; averaged over
  emotions, one pair of numbers per participant. If identity does not matter, the two are
  exchangeable and their difference (between − within) has mean 0: a paired t-test over
  participants with its CI (participant the unit; assumption: the differences are roughly
  normal or the sample large — a sign-flip permutation p is given beside it).
* **Cross-identity decoding** (:func:`cross_identity_decoding`): a classifier of emotion from
  genes (linear discriminant analysis, shrinkage by Ledoit–Wolf) trained on the faces made on
  identity A decodes the emotion of the faces made on identity B, in both directions, with
  participants never split across train and test (grouped K-fold over participants: trained on
  A-faces of the training participants, tested on B-faces of the held-out ones). Accuracy is
  the mean over participants of their share decoded right; chance comes from a permutation of
  the emotion labels within each participant × identity (the participant's own faces keep
  their count per emotion), p = (1 + #perm ≥ observed) / (1 + n_perm).
"""

from __future__ import annotations

from itertools import permutations
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from scipy import stats

from emogen.analysis.analyse_options import AnalysisOptions
from emogen.analysis.people import People
from emogen.analysis.results import Section

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

#: Label permutations of the report's decoding chance (p resolution 1 / (1 + this)).
DECODING_PERMUTATIONS = 99


def identity_distances(people: People) -> pd.DataFrame:
    """One row per participant × emotion with faces on at least two identities: mean distance
    between same-identity pairs (``within``, NaN without repetitions) and different-identity
    pairs (``between``), and the number of each."""
    g = people.gene_matrix()
    f = people.faces.reset_index(drop=True)
    rows = []
    groups = f.groupby(["participant_id", "emotion"]).indices
    for key in sorted(groups, key=str):
        p, e = (str(v) for v in key)  # type: ignore[attr-defined]
        idx = np.asarray(groups[key])
        ident = f["identity"].astype(str).to_numpy()[idx]
        if len(np.unique(ident)) < 2:
            continue
        x = g[idx]
        d = np.sqrt(((x[:, None, :] - x[None, :, :]) ** 2).sum(axis=-1))
        upper = np.triu(np.ones_like(d, dtype=bool), 1)
        same = (ident[:, None] == ident[None, :]) & upper
        diff = (ident[:, None] != ident[None, :]) & upper
        rows.append(
            {
                "participant_id": str(p),
                "emotion": str(e),
                "within": float(d[same].mean()) if same.any() else np.nan,
                "between": float(d[diff].mean()),
                "n_within": int(same.sum()),
                "n_between": int(diff.sum()),
            }
        )
    return pd.DataFrame(rows)


def within_between_test(
    distances: pd.DataFrame, *, alpha: float = 0.05, rng: np.random.Generator, n_perm: int = 9999
) -> dict[str, float]:
    """Paired test over participants of between − within identity distance (each averaged
    over the participant's emotions with both): mean, t CI, dz, t-test p and sign-flip p."""
    d = distances.dropna(subset=["within"])
    per = d.groupby("participant_id")[["within", "between"]].mean()
    diff = (per["between"] - per["within"]).to_numpy(dtype=np.float64)
    n = len(diff)
    if n < 3:
        return {"n": float(n)}
    res = stats.ttest_1samp(diff, 0.0)
    ci = res.confidence_interval(1 - alpha)
    signs = rng.choice([-1.0, 1.0], size=(n_perm, n))
    perm = np.abs((signs * diff).mean(axis=1))
    p_perm = float((1 + np.sum(perm >= abs(diff.mean()) - 1e-12)) / (1 + n_perm))
    sd = diff.std(ddof=1)
    return {
        "n": float(n),
        "within": float(per["within"].mean()),
        "between": float(per["between"].mean()),
        "difference": float(diff.mean()),
        "ci_low": float(ci.low),
        "ci_high": float(ci.high),
        "t": float(res.statistic),
        "df": float(n - 1),
        "p": float(res.pvalue),
        "p_sign_flip": p_perm,
        "dz": float(diff.mean() / sd) if sd > 0 else np.nan,
    }


def _decode(
    x: np.ndarray,
    y: np.ndarray,
    who: np.ndarray,
    ident: np.ndarray,
    trained_on: str,
    tested_on: list[str],
    folds: list[np.ndarray],
) -> dict[str, float]:
    """Per identity ``b`` of ``tested_on``: the mean over test participants of the share of
    their ``b`` faces decoded right by an LDA trained on the ``trained_on`` faces of the other
    folds' participants. One fit per fold serves every tested identity (the training set does
    not depend on it): half the fits of one per ordered pair (benchmarks/bench_analyse.py, 336
    participants: 26 s of 137 s in 2000 fits before)."""
    from sklearn.discriminant_analysis import LinearDiscriminantAnalysis

    acc: dict[str, list[float]] = {b: [] for b in tested_on}
    for test in folds:
        held = np.isin(who, test)
        train = ~held & (ident == trained_on)
        targets = {b: held & (ident == b) for b in tested_on}
        targets = {b: t for b, t in targets.items() if t.any()}
        if not targets or len(np.unique(y[train])) < 2:
            continue
        lda = LinearDiscriminantAnalysis(solver="lsqr", shrinkage="auto").fit(x[train], y[train])
        for b, target in targets.items():
            hit = lda.predict(x[target]) == y[target]
            acc[b].extend(pd.Series(hit).groupby(who[target]).mean().to_list())
    return {b: float(np.mean(a)) if a else np.nan for b, a in acc.items()}


def _decode_pairs(
    x: np.ndarray,
    y: np.ndarray,
    who: np.ndarray,
    ident: np.ndarray,
    pairs: list[tuple[str, str]],
    folds: list[np.ndarray],
) -> dict[tuple[str, str], float]:
    """:func:`_decode` for every (train, test) identity pair, in the order of ``pairs``."""
    tested: dict[str, list[str]] = {}
    for a, b in pairs:
        tested.setdefault(a, []).append(b)
    by_train = {a: _decode(x, y, who, ident, a, bs, folds) for a, bs in tested.items()}
    return {(a, b): by_train[a][b] for a, b in pairs}


def _shuffled(y: np.ndarray, cells: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    out = y.copy()
    for idx in pd.Series(np.arange(len(y))).groupby(cells).indices.values():
        out[idx] = y[rng.permutation(idx)]
    return out


def cross_identity_decoding(
    people: People, *, rng: np.random.Generator, n_perm: int = 199, n_folds: int = 5
) -> pd.DataFrame:
    """Per ordered pair of identities (train → test) and per identity (train = test, held-out
    participants: the within-identity reference): decoding accuracy, chance (permutation mean),
    the permutation 95% upper point and p."""
    f = people.faces.reset_index(drop=True)
    x = people.gene_matrix(f)
    y = f["emotion"].astype(str).to_numpy()
    who = f["participant_id"].astype(str).to_numpy()
    ident = f["identity"].astype(str).to_numpy()
    ids = sorted(set(ident))
    order = rng.permutation(np.array(sorted(set(who))))
    folds = [a for a in np.array_split(order, min(n_folds, len(order))) if len(a)]
    pairs = [*permutations(ids, 2), *((i, i) for i in ids)]
    cells = np.char.add(np.char.add(who.astype(str), "\x00"), ident.astype(str))
    observed = _decode_pairs(x, y, who, ident, pairs, folds)
    null = {pair: np.empty(n_perm) for pair in pairs}
    for k in range(n_perm):
        shuffled = _decode_pairs(x, _shuffled(y, cells, rng), who, ident, pairs, folds)
        for pair in pairs:
            null[pair][k] = shuffled[pair]
    rows = []
    for (a, b), acc in observed.items():
        nl = null[(a, b)]
        rows.append(
            {
                "train_identity": a,
                "test_identity": b,
                "cross": a != b,
                "accuracy": acc,
                "chance": float(np.nanmean(nl)),
                "null_95": float(np.nanquantile(nl, 0.95)),
                "p": float((1 + np.sum(nl >= acc)) / (1 + n_perm)),
                "n_perm": n_perm,
                "n_participants": len(set(who[ident == b])),
            }
        )
    return pd.DataFrame(rows)


def _register_distance(report: Section, test: dict[str, Any], level: float) -> None:
    """The within- against between-identity distance test in the plan (dz without interval)."""
    dz = test["dz"]
    report.add_test(
        "identity.distance",
        test,
        test="paired t (between − within identity distance)",
        p=test["p"],
        n=int(test["n"]),
        statistic=test["t"],
        df=test["df"],
        estimate=test["difference"],
        interval=(test["ci_low"], test["ci_high"]),
        level=level,
        effect=("dz", dz, None, None) if np.isfinite(dz) else None,
    )


def identity_section(
    people: People, folder: Path, opts: AnalysisOptions, model: FaceModel | None
) -> Section:
    """Identity effects within participants: distances within against between identities, and
    cross-identity decoding of the emotion."""
    report = Section(folder)
    del model  # nothing is rendered here
    report.heading("Identity effects")
    names = people.identity_names
    if len(names) < 2:
        report.paragraph(
            f"Skipped: every face was made on one identity ({names[0] if names else 'none'}), "
            "so there is no identity effect to measure."
        )
        return report
    rng = np.random.default_rng(opts.seed)
    out: dict[str, Any] = {}
    dist = identity_distances(people)
    test = within_between_test(dist, alpha=opts.alpha, rng=rng)
    if test.get("n", 0) < 3 or not np.isfinite(test.get("p", np.nan)):
        why = (
            "it needs participants who made an emotion at least twice on one identity and on "
            f"another (repetitions), and spread among them; {int(test.get('n', 0))} did"
        )
        report.paragraph(f"No within- against between-identity distance test: {why}.")
        report.not_run("identity.distance", why, n=int(test.get("n", 0)))
    else:
        report.paragraph(
            "Distance within against between identities (gene-space Euclidean distance between "
            "two final faces of one participant and emotion, on the same identity or on two "
            "different ones; per participant averaged over pairs and emotions). Unit: "
            "participant; test: paired t-test of between − within over participants with its "
            f"{100 * (1 - opts.alpha):.0f} % CI, and a sign-flip permutation p (9999 flips). "
            "Assumptions: participants independent; differences roughly normal (the t-test) or "
            "symmetric about 0 under the null (the sign flip); identity is not confounded with "
            "time — if each identity had its own block, drift over the session reads as an "
            "identity effect (Murray et al. 2024)."
        )
        report.table(
            pd.DataFrame([test]),
            "identity_distance_test",
            "Between − within identity distance over participants",
        )
        out["distance"] = test
        _register_distance(report, test, 1 - opts.alpha)
    report.table(dist, "identity_distances", "Per participant and emotion: mean distances")
    dec = cross_identity_decoding(people, rng=rng, n_perm=DECODING_PERMUTATIONS)
    report.paragraph(
        "Cross-identity decoding: linear discriminant analysis (Ledoit–Wolf shrinkage) of the "
        "emotion from the genes, trained on the faces made on one identity, tested on the faces "
        "made on another, with participants never split across training and test (5-fold "
        "grouped by participant). Accuracy: mean over test participants of their share "
        "decoded right. Chance: the emotion labels permuted within each participant × identity "
        f"({DECODING_PERMUTATIONS} permutations, seed {opts.seed}); p = (1 + #permuted ≥ "
        f"observed) / {DECODING_PERMUTATIONS + 1}. Rows "
        "with the same identity for training and test are the within-identity reference: "
        "decoding that holds across identities, near that reference, means the participants' "
        "faces of an emotion keep their form across identities."
    )
    report.table(dec, "identity_decoding", "Decoding the emotion across identities")
    out["decoding"] = dec.to_dict(orient="records")
    for row in out["decoding"]:
        report.add_test(
            f"identity.decoding[{row['train_identity']} → {row['test_identity']}]",
            row,
            test="permutation (emotion labels within participant × identity)",
            p=row["p"],
            n=row["n_participants"],
            estimate=row["accuracy"],
        )
    report.data["identity"] = out
    return report
