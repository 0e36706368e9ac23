"""Expression perceptive fields: each participant's density over the face space, per emotion.

A participant's *perceptive field* of an emotion (after "Expression perceptive fields explain
individual differences in the recognition of facial emotions", *Communications Psychology*
2024, doi:10.1038/s44271-024-00111-7) is a probability density over the space of faces: where
in that space this participant's faces of the emotion lie. Here:

* the **space** is the study's own PCA of every final face's genes (all participants, emotions
  and identities), the leading components that explain ``variance`` of the gene variance (at
  most ``max_components``); scores are unwhitened, so distances are gene-space Euclidean
  distances within the kept subspace (:func:`face_space`);
* a **field** is a Gaussian kernel density estimate (isotropic kernel, bandwidth ``h``) of the
  participant's final faces of the emotion in that space. A participant has few faces per
  emotion (identities × repetitions, often 3–6), far too few to choose a bandwidth of their
  own, so ``h`` is **shared** by every participant's field of an emotion and chosen by
  **leave-one-out cross-validated likelihood pooled over all participants' fields** of that
  emotion (:func:`pooled_bandwidth`). A field is then the participant's faces blurred by the
  typical within-participant scatter — its location and shape are theirs, its smoothness the
  study's;
* the **overlap** of two fields p, q is the normalised probability-product kernel
  ∫pq / √(∫p²∫q²) (Jebara, Kondor & Howard 2004, *JMLR* 5:819; ρ = 1), exact for Gaussian
  KDEs: 1 for identical fields, 0 for disjoint ones (:func:`overlaps`). Beside it, the
  Bhattacharyya coefficient ∫√(pq) by Monte Carlo from the mixture (p+q)/2, whose integrand is
  bounded by 1 (:func:`bhattacharyya`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.special import logsumexp

from emogen.analysis.people import People
from emogen.errors import DataError

#: Bandwidth grid: multiples of the emotion's pooled within-field standard deviation.
BANDWIDTH_GRID = np.geomspace(0.05, 4.0, 45)


@dataclass(frozen=True)
class FaceSpace:
    """The study's PCA of the final faces' genes: ``scores = (genes - mean) @ components.T``."""

    genes: tuple[str, ...]
    mean: np.ndarray
    components: np.ndarray  # (k, n_genes)
    explained: np.ndarray  # (k,) share of the gene variance each kept component explains

    @property
    def k(self) -> int:
        return int(self.components.shape[0])

    def scores(self, genes: np.ndarray) -> np.ndarray:
        return (np.asarray(genes, dtype=np.float64) - self.mean) @ self.components.T


def face_space(people: People, *, variance: float = 0.8, max_components: int = 10) -> FaceSpace:
    """The leading principal components of all final faces' genes explaining ``variance``."""
    from sklearn.decomposition import PCA

    g = people.gene_matrix()
    if len(g) < 3:
        raise DataError(f"a face space needs at least 3 final faces; the study has {len(g)}")
    pca = PCA().fit(g)
    ratio = pca.explained_variance_ratio_
    k = int(np.searchsorted(np.cumsum(ratio), variance) + 1)
    k = max(1, min(k, max_components, len(ratio)))
    return FaceSpace(people.genes, pca.mean_, pca.components_[:k].copy(), ratio[:k].copy())


@dataclass(frozen=True, eq=False)
class Fields:
    """Every participant's field of every emotion: ``points[(participant, emotion)]`` are the
    field's faces in ``space`` (n_faces, k); ``bandwidth[emotion]`` the shared kernel SD."""

    space: FaceSpace
    points: dict[tuple[str, str], np.ndarray]
    bandwidth: dict[str, float]
    #: per emotion: the bandwidth grid searched and the pooled LOO log-likelihood on it
    cv: dict[str, pd.DataFrame]

    @property
    def emotions(self) -> tuple[str, ...]:
        return tuple(sorted({e for _, e in self.points}))

    def participants(self, emotion: str) -> list[str]:
        return sorted(p for p, e in self.points if e == emotion)

    def table(self) -> pd.DataFrame:
        """One row per field: its size, centre and spread (RMS distance of its faces to their
        mean) in the face space, and the emotion's bandwidth."""
        rows = []
        for (p, e), x in sorted(self.points.items()):
            centre = x.mean(axis=0)
            rows.append(
                {
                    "participant_id": p,
                    "emotion": e,
                    "n_faces": len(x),
                    "pc1": float(centre[0]),
                    "pc2": float(centre[1]) if len(centre) > 1 else 0.0,
                    "spread": float(np.sqrt(((x - centre) ** 2).sum(axis=1).mean())),
                    "bandwidth": self.bandwidth[e],
                }
            )
        return pd.DataFrame(rows)


def loo_loglik(points: np.ndarray, h: float) -> np.ndarray:
    """Leave-one-out log density of each face under the Gaussian KDE (kernel SD ``h``) of the
    field's other faces: (n,) for a field of n ≥ 2 faces."""
    x = np.asarray(points, dtype=np.float64)
    n, k = x.shape
    d2 = ((x[:, None, :] - x[None, :, :]) ** 2).sum(axis=-1)
    logk = -0.5 * d2 / h**2 - 0.5 * k * np.log(2 * np.pi * h**2)
    np.fill_diagonal(logk, -np.inf)
    return np.asarray(logsumexp(logk, axis=1) - np.log(n - 1))


def pooled_bandwidth(fields: list[np.ndarray]) -> tuple[float, pd.DataFrame]:
    """The kernel SD maximising the leave-one-out log-likelihood summed over every face of
    every field (fields of one face add nothing); the grid is :data:`BANDWIDTH_GRID` times the
    pooled within-field SD per dimension. Returns (h, table of the grid and its likelihood)."""
    usable = [f for f in fields if len(f) >= 2]
    if not usable:
        raise DataError("no participant has two faces of this emotion: no bandwidth by CV")
    resid = np.vstack([f - f.mean(axis=0) for f in usable])
    dof = sum(len(f) - 1 for f in usable) * resid.shape[1]
    scale = float(np.sqrt((resid**2).sum() / dof)) if dof else 0.0
    if scale <= 0:
        raise DataError("every participant's faces of this emotion are identical: no bandwidth")
    grid = BANDWIDTH_GRID * scale
    ll = np.zeros(len(grid))
    for f in usable:
        n, k = f.shape
        d2 = ((f[:, None, :] - f[None, :, :]) ** 2).sum(axis=-1)[~np.eye(n, dtype=bool)]
        logk = -0.5 * d2[None, :] / grid[:, None] ** 2  # (grid, n·(n−1)), row-major by face
        per_face = logsumexp(logk.reshape(len(grid), n, n - 1), axis=2) - np.log(n - 1)
        ll += per_face.sum(axis=1) - 0.5 * n * k * np.log(2 * np.pi * grid**2)
    best = int(np.argmax(ll))
    table = pd.DataFrame(
        {"bandwidth": grid, "loo_loglik": ll, "chosen": np.arange(len(grid)) == best}
    )
    return float(grid[best]), table


def perceptive_fields(
    people: People,
    space: FaceSpace | None = None,
    *,
    min_faces: int = 2,
    bandwidth: float | None = None,
) -> Fields:
    """Every participant's field per emotion from at least ``min_faces`` final faces (fewer:
    no field); bandwidth per emotion by pooled leave-one-out likelihood, or ``bandwidth``."""
    space = space or face_space(people)
    faces = people.faces
    scores = space.scores(people.gene_matrix())
    points: dict[tuple[str, str], np.ndarray] = {}
    key = faces["participant_id"].astype(str) + "\x00" + faces["emotion"].astype(str)
    for k, idx in faces.groupby(key.to_numpy()).indices.items():
        if len(idx) >= min_faces:
            p, e = str(k).split("\x00")
            points[(p, e)] = scores[np.sort(idx)]
    if not points:
        raise DataError(f"no participant has {min_faces} final faces of any emotion")
    bw, cv = {}, {}
    for e in sorted({e for _, e in points}):
        own = [x for (_, em), x in points.items() if em == e]
        if bandwidth is not None:
            bw[e], cv[e] = float(bandwidth), pd.DataFrame()
        else:
            bw[e], cv[e] = pooled_bandwidth(own)
    return Fields(space, points, bw, cv)


def _product_integrals(a: list[np.ndarray], b: list[np.ndarray], h: float) -> np.ndarray:
    """∫ p_i q_j for Gaussian KDEs (kernel SD h) of fields a_i, b_j: the mean over their face
    pairs of the N(0, 2h²I) density at the pair's difference. (len(a), len(b))."""
    xa, xb = np.vstack(a), np.vstack(b)
    k = xa.shape[1]
    d2 = _sq_distances(xa, xb)
    dens = np.exp(-0.25 * d2 / h**2) / (4 * np.pi * h**2) ** (k / 2)
    # block sums by reduceat, not a dense (fields × faces) averaging matrix: the clustering
    # null calls this 400 times per analysis (benchmarks/bench_analyse.py; docs/analysis.md)
    na, nb = np.array([len(x) for x in a]), np.array([len(x) for x in b])
    sums = np.add.reduceat(np.add.reduceat(dens, _starts(na), axis=0), _starts(nb), axis=1)
    return sums / np.outer(na, nb)


def _sq_distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(len(a), len(b)) squared Euclidean distances."""
    d2 = (a**2).sum(axis=1)[:, None] + (b**2).sum(axis=1)[None, :] - 2.0 * a @ b.T
    return np.clip(d2, 0.0, None)


def _starts(sizes: np.ndarray) -> np.ndarray:
    """First row of each field's faces in the stacked faces."""
    return np.concatenate([[0], np.cumsum(sizes)[:-1]])


def overlap_matrix(a: list[np.ndarray], b: list[np.ndarray], h: float) -> np.ndarray:
    """Normalised probability-product overlap ∫pq/√(∫p²∫q²) of every field of ``a`` with every
    field of ``b`` (Gaussian KDEs with kernel SD ``h``): (len(a), len(b)) in [0, 1]."""
    cross = _product_integrals(a, b, h)
    self_a = np.diag(cross) if b is a else np.diag(_product_integrals(a, a, h))
    self_b = np.diag(cross) if b is a else np.diag(_product_integrals(b, b, h))
    return np.clip(cross / np.sqrt(np.outer(self_a, self_b)), 0.0, 1.0)


def overlaps(fields: Fields, emotion: str) -> pd.DataFrame:
    """The participants × participants overlap matrix of one emotion's fields (labelled)."""
    who = fields.participants(emotion)
    pts = [fields.points[(p, emotion)] for p in who]
    m = overlap_matrix(pts, pts, fields.bandwidth[emotion])
    return pd.DataFrame(m, index=pd.Index(who, name="participant_id"), columns=who)


def bhattacharyya(
    fields: list[np.ndarray], h: float, *, rng: np.random.Generator, samples: int = 256
) -> tuple[np.ndarray, np.ndarray]:
    """Monte Carlo Bhattacharyya coefficients ∫√(pq) and overlap integrals ∫min(p, q) of every
    pair of Gaussian-KDE fields (kernel SD h): ``samples`` draws from each field, and a pair
    uses both sets — a sample of (p+q)/2, against which √(pq) and min(p, q) are at most 1 — so
    each estimate's standard error is below 1/√(2·samples). Returns two (n, n) matrices.

    At a draw where the two log densities differ by δ, √(pq)/((p+q)/2) = 1/cosh(δ/2) and
    min(p, q)/((p+q)/2) = 2/(1 + e^δ): both symmetric in p and q, so the sum over field i's
    draws of the pair (i, j) is one entry of an (n, n) matrix over (field, draw set), and the
    pair's estimate is that entry plus its transpose's over 2·samples."""
    n = len(fields)
    draws = []
    for x in fields:
        c = x[rng.integers(0, len(x), samples)]
        draws.append(c + rng.normal(0.0, h, c.shape))
    allx = np.vstack(draws)
    sums_bc, sums_mn = np.empty((n, n)), np.empty((n, n))
    # every field at the draws of a block of fields at once: one numpy pass per block of
    # n·block·samples log densities (quadratic in people: at 336, 29 million per emotion)
    block = max(1, _BLOCK_VALUES // (n * samples))
    for lo in range(0, n, block):
        hi = min(n, lo + block)
        logp = _kde_logpdfs(fields, allx[lo * samples : hi * samples], h)
        logp = logp.reshape(n, hi - lo, samples)
        own = logp[np.arange(lo, hi), np.arange(hi - lo)]  # each field at its own draws
        t = np.exp(-0.5 * np.abs(logp - own[None]))  # e^(−δ/2)
        share = 2.0 / (1.0 + t * t)
        sums_bc[:, lo:hi] = (t * share).sum(axis=2)
        sums_mn[:, lo:hi] = (t * t * share).sum(axis=2)
    bc = (sums_bc + sums_bc.T) / (2 * samples)
    mn = (sums_mn + sums_mn.T) / (2 * samples)
    np.fill_diagonal(bc, 1.0)
    np.fill_diagonal(mn, 1.0)
    return bc, mn


#: Log densities per block of :func:`bhattacharyya` (2²¹ floats: 16 MB, a few per block).
_BLOCK_VALUES = 2**21


def _kde_logpdfs(fields: list[np.ndarray], x: np.ndarray, h: float) -> np.ndarray:
    """(len(fields), len(x)) log densities of each field's Gaussian KDE (kernel SD h) at ``x``:
    every kernel centre at every point in one pass, each field's log-sum-exp by its block of
    centres (``np.maximum.reduceat`` / ``np.add.reduceat``)."""
    k = x.shape[1]
    sizes = np.array([len(c) for c in fields])
    starts = _starts(sizes)
    logk = -0.5 * _sq_distances(np.vstack(fields), x) / h**2  # (centres, points)
    top = np.maximum.reduceat(logk, starts, axis=0)  # (fields, points)
    dens = np.add.reduceat(np.exp(logk - np.repeat(top, sizes, axis=0)), starts, axis=0)
    return top + np.log(dens) - 0.5 * k * np.log(2 * np.pi * h**2) - np.log(sizes)[:, None]


def split_halves(faces: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """Positional indices of two halves of one participant's faces of an emotion: ordered by
    identity then repetition, alternately (so both halves hold every identity they can)."""
    order = np.lexsort((faces["repetition"].to_numpy(), faces["identity"].astype(str).to_numpy()))
    return order[0::2], order[1::2]


def field_individuality(people: People, fields: Fields, *, min_half: int = 2) -> pd.DataFrame:
    """Split-half test of whether fields are the participant's own: per participant and
    emotion, the overlap of the field of one half of their faces with the field of their other
    half (``self``) and with the other halves of everyone else (``others``, their mean), and
    whether their own other half is their best match (``identified``). Halves of fewer than
    ``min_half`` faces: no row. Same space and bandwidth as ``fields``."""
    scores = fields.space.scores(people.gene_matrix())
    faces = people.faces.reset_index(drop=True)
    rows = []
    for e in fields.emotions:
        a, b, who = [], [], []
        sub = faces[faces["emotion"].astype(str) == e]
        for p, idx in sorted(sub.groupby("participant_id").indices.items()):
            pos = sub.index.to_numpy()[idx]
            ia, ib = split_halves(faces.iloc[pos])
            if min(len(ia), len(ib)) >= min_half:
                a.append(scores[pos[ia]])
                b.append(scores[pos[ib]])
                who.append(str(p))
        if len(who) < 3:
            continue
        m = overlap_matrix(a, b, fields.bandwidth[e])
        for i, p in enumerate(who):
            others = np.delete(m[i], i)
            rows.append(
                {
                    "participant_id": p,
                    "emotion": e,
                    "self": float(m[i, i]),
                    "others": float(others.mean()),
                    "identified": bool(m[i, i] > others.max()),
                    "n_candidates": len(who),
                }
            )
    return pd.DataFrame(rows)
