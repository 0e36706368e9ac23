"""Separability of face distributions (Table I, Fig. 8): PCA, a Gaussian mixture, a confusion table.

The paper's procedure, step by step:

1. **PCA** (scikit-learn) of the combined samples *and* the targets (when known), on the full
   weight vectors; the GMM is fitted in the first ``n_pca`` components (2 by default: Fig. 8
   shows the separation in the first two; a fraction in (0, 1) keeps the components explaining
   that share of variance instead).
2. **A Gaussian mixture** with as many components as groups (3 in Table I), full covariances,
   ``n_init`` restarts, fixed seed.
3. **Cluster-to-group correspondence**: the cluster the GMM assigns to each group's mean (the
   paper: "what cluster label the GMM assigns to each original target or simulated target
   distribution mean"); the cluster of each known target is reported beside it. A cluster that
   no group's mean falls in is *unnamed*; one that two groups' means fall in is named after both
   (e.g. "target 1 and target 3") — those groups are not separated.
4. **Confusion table**: rows are the groups' samples, columns the clusters by name; a sample is
   correctly classified when it lies in the cluster named after its group alone. ``accuracy`` is
   that share; ``ari`` the adjusted Rand index (label-free agreement of clusters and groups).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from emogen.errors import ConfigError, ShapeError

if TYPE_CHECKING:
    from sklearn.mixture import GaussianMixture


@dataclass(frozen=True, eq=False)
class Separability:
    """Result of :func:`gmm_separability` (arrays for plotting included)."""

    groups: tuple[str, ...]
    cluster_names: tuple[str, ...]
    confusion: pd.DataFrame
    cluster_of_group: dict[str, int]
    cluster_of_target: dict[str, int]
    accuracy: float
    per_group_accuracy: dict[str, float]
    ari: float
    one_to_one: bool
    n_pca: int
    explained_variance: float
    coords: np.ndarray  # (n_samples, n_pca)
    labels: np.ndarray  # (n_samples,) group index
    predicted: np.ndarray  # (n_samples,) cluster index
    means: np.ndarray  # (k, n_pca) GMM means
    covariances: np.ndarray  # (k, n_pca, n_pca)
    group_means: np.ndarray  # (n_groups, n_pca)
    target_coords: np.ndarray | None = None  # (n_groups, n_pca)
    notes: list[str] = field(default_factory=list)


def _cluster_names(groups: tuple[str, ...], cluster_of_group: dict[str, int], k: int) -> list[str]:
    names = []
    for c in range(k):
        owners = [g for g in groups if cluster_of_group[g] == c]
        names.append(" and ".join(owners) if owners else "unnamed")
    # two unnamed clusters would collide as column names
    seen: dict[str, int] = {}
    out = []
    for n in names:
        seen[n] = seen.get(n, 0) + 1
        out.append(n if seen[n] == 1 else f"{n} {seen[n]}")
    return out


def _full_covariances(gmm: object, k: int) -> np.ndarray:
    """(k, d, d) covariances whatever the mixture's covariance type."""
    cov = np.asarray(gmm.covariances_)  # type: ignore[attr-defined]
    kind = gmm.covariance_type  # type: ignore[attr-defined]
    if kind == "full":
        return cov
    if kind == "tied":
        return np.broadcast_to(cov, (k, *cov.shape)).copy()
    if kind == "diag":
        return np.stack([np.diag(c) for c in cov])
    d = np.asarray(gmm.means_).shape[1]  # type: ignore[attr-defined]
    return np.stack([np.eye(d) * c for c in cov])


def _check_input(
    x: np.ndarray, y: np.ndarray, groups: tuple[str, ...], n_components: int | None
) -> int:
    """The number of clusters, after checking samples and labels."""
    if x.ndim != 2 or y.shape != (len(x),):
        raise ShapeError(f"weights (n, S) and labels (n,) must agree; got {x.shape}, {y.shape}")
    k = len(groups) if n_components is None else int(n_components)
    if k < 2:
        raise ConfigError(f"separability needs at least 2 clusters; got {k}")
    present = np.unique(y)
    if len(present) != len(groups) or present.min() < 0 or present.max() >= len(groups):
        raise ConfigError(f"every group of {list(groups)} needs samples; labels hold {present}")
    if len(x) < 2 * k:
        raise ConfigError(
            f"separability needs at least {2 * k} samples for {k} clusters; got {len(x)}"
        )
    return k


def _fit_mixture(
    z: np.ndarray,
    y: np.ndarray,
    n_groups: int,
    k: int,
    covariance_type: str | None,
    n_init: int,
    seed: int,
) -> tuple[GaussianMixture, list[str]]:
    """A k-component Gaussian mixture fitted to z (n, d), and notes on how it was fitted."""
    from sklearn.exceptions import ConvergenceWarning
    from sklearn.mixture import GaussianMixture

    notes: list[str] = []
    d = z.shape[1]
    smallest = int(np.bincount(y, minlength=n_groups).min())
    cov = covariance_type or ("full" if smallest >= 10 * d * (d + 1) // 2 else "tied")
    if cov != "full":
        notes.append(
            f"{cov} covariances: {smallest} samples in the smallest group are too few for a full "
            f"covariance per component in {d} dimensions"
        )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ConvergenceWarning)
        gmm = GaussianMixture(
            n_components=k,
            covariance_type=cov,
            n_init=n_init,
            max_iter=500,
            reg_covar=1e-6,
            random_state=seed,
        ).fit(z)
    if any(issubclass(w.category, ConvergenceWarning) for w in caught):
        notes.append("the Gaussian mixture's best initialisation did not fully converge")
    return gmm, notes


def _confusion(
    y: np.ndarray,
    pred: np.ndarray,
    groups: tuple[str, ...],
    names: list[str],
    of_group: dict[str, int],
) -> pd.DataFrame:
    """Samples per (group, cluster), the clusters in the groups' order, unnamed ones last."""
    k = len(names)
    counts = np.zeros((len(groups), k), dtype=np.int64)
    np.add.at(counts, (y, pred), 1)
    confusion = pd.DataFrame(
        counts,
        index=pd.Index([f"{g} samples" for g in groups], name="classified as →"),
        columns=names,
    )
    # columns in the groups' order, unnamed clusters last
    rank = {
        c: min((i for i, g in enumerate(groups) if of_group[g] == c), default=len(groups))
        for c in range(k)
    }
    confusion = confusion.iloc[:, sorted(range(k), key=lambda c: (rank[c], c))]
    return confusion


def gmm_separability(
    weights: np.ndarray,
    labels: np.ndarray,
    groups: list[str] | tuple[str, ...],
    *,
    targets: np.ndarray | None = None,
    n_components: int | None = None,
    n_pca: float = 2,
    n_init: int = 10,
    seed: int = 0,
    covariance_type: str | None = None,
) -> Separability:
    """PCA + GMM separability of samples ``weights (n, S)`` labelled ``labels (n,)`` (indices
    into ``groups``); ``targets (n_groups, S)`` join the PCA and get their cluster reported.

    ``covariance_type`` None: ``full`` when every group has at least 10 samples per covariance
    parameter of a component (d (d + 1) / 2 in d PCA dimensions), else ``tied`` (one shared
    covariance): with few samples a full-covariance component can collapse onto one outlier.
    """
    from sklearn.decomposition import PCA
    from sklearn.metrics import adjusted_rand_score

    x = np.asarray(weights, dtype=np.float64)
    y = np.asarray(labels, dtype=np.int64)
    groups = tuple(groups)
    k = _check_input(x, y, groups, n_components)
    t = None if targets is None else np.asarray(targets, dtype=np.float64)
    fit_on = x if t is None else np.concatenate([x, t])
    max_dims = min(fit_on.shape[0] - 1, fit_on.shape[1])
    if 0 < n_pca < 1:
        pca = PCA(n_components=n_pca, svd_solver="full").fit(fit_on)
    else:
        pca = PCA(n_components=min(int(n_pca), max_dims), svd_solver="full").fit(fit_on)
    z = pca.transform(x)
    gmm, notes = _fit_mixture(z, y, len(groups), k, covariance_type, n_init, seed)
    pred = gmm.predict(z)
    group_means = np.stack([z[y == i].mean(0) for i in range(len(groups))])
    of_group = dict(zip(groups, (int(c) for c in gmm.predict(group_means)), strict=True))
    target_coords = None
    of_target: dict[str, int] = {}
    if t is not None:
        target_coords = pca.transform(t)
        of_target = dict(zip(groups, (int(c) for c in gmm.predict(target_coords)), strict=True))
    names = _cluster_names(groups, of_group, k)
    confusion = _confusion(y, pred, groups, names, of_group)
    owners = {c: [g for g in groups if of_group[g] == c] for c in range(k)}
    correct = np.array(
        [pred[i] == of_group[groups[y[i]]] and len(owners[pred[i]]) == 1 for i in range(len(y))]
    )
    per_group = {g: float(correct[y == i].mean()) for i, g in enumerate(groups)}
    return Separability(
        groups=groups,
        cluster_names=tuple(names),
        confusion=confusion,
        cluster_of_group=of_group,
        cluster_of_target=of_target,
        accuracy=float(correct.mean()),
        per_group_accuracy=per_group,
        ari=float(adjusted_rand_score(y, pred)),
        one_to_one=len(set(of_group.values())) == len(groups),
        n_pca=int(pca.n_components_),
        explained_variance=float(pca.explained_variance_ratio_.sum()),
        coords=z,
        labels=y,
        predicted=pred,
        means=gmm.means_,
        covariances=_full_covariances(gmm, k),
        group_means=group_means,
        target_coords=target_coords,
        notes=notes,
    )
