"""The GA's operators (Section III-B): S, B, M, A and R, over a leading run axis.

Every operator works in *gene space*: genes are float in [0, 1], one column per unique core
shape of the rig (a left/right pair is one gene). Symmetry therefore holds by construction —
:meth:`emogen.model.rig.Rig.expand` writes a gene's value to every shape of the gene — and
corrective shapes, not being genes, are never evolved.

B, M and R take their random numbers from a :class:`~emogen.ga.draws.Draws` for R runs at once
(axis 0 is the run; a single participant is a batch of one) and request them in a fixed order,
documented per operator, which is part of the GA's stream (:mod:`emogen.ga.draws`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from emogen.errors import SelectionError, ShapeError
from emogen.ga.draws import Draws


# ---- S: selection ------------------------------------------------------------------------
def select(
    ids: np.ndarray,
    elite: int | Sequence[int] | np.ndarray,
    others: Sequence[int] | np.ndarray = (),
    *,
    min_selections: int = 1,
    max_selections: int | None = None,
) -> tuple[int, np.ndarray]:
    """S(P_g) (eq. 6): check a selection and turn face ids into population indices.

    ids : (n_faces,) int, the shown population's face ids. ``elite`` is one id (a sequence
    must hold exactly one); ``others`` the further selections p_g ⊂ P_g, elite ∉ p_g.
    The count |p_g| + 1 must lie in [min_selections, max_selections].
    Returns (elite index, (|p_g|,) int indices into the population).
    """
    ids = np.asarray(ids)
    if isinstance(elite, Sequence | np.ndarray) and not isinstance(elite, str):
        chosen = list(np.asarray(elite).reshape(-1))
        if len(chosen) != 1:
            raise SelectionError(f"selection must include exactly one elite; got {len(chosen)}")
        elite = chosen[0]
    if isinstance(elite, bool) or not isinstance(elite, int | np.integer):
        raise SelectionError(f"elite must be a face id (an integer); got {elite!r}")
    where = {int(face): i for i, face in enumerate(ids)}
    if int(elite) not in where:
        raise SelectionError(f"elite {elite} is not in the population (ids {sorted(where)})")
    others_list = [int(o) for o in np.asarray(others, dtype=np.int64).reshape(-1)]
    missing = [o for o in others_list if o not in where]
    if missing:
        raise SelectionError(
            f"selected face(s) {missing} are not in the population (ids {sorted(where)})"
        )
    if int(elite) in others_list:
        raise SelectionError(f"the elite {elite} must not also be among the other selections")
    if len(set(others_list)) != len(others_list):
        raise SelectionError(f"other selections must be distinct; got {others_list}")
    count = len(others_list) + 1
    upper = len(ids) if max_selections is None else max_selections
    if not min_selections <= count <= upper:
        raise SelectionError(
            f"number of selections must be in [{min_selections}, {upper}]; got {count}"
        )
    return where[int(elite)], np.array([where[o] for o in others_list], dtype=np.int64)


# ---- B: uniform crossover ----------------------------------------------------------------
def crossover(a: np.ndarray, b: np.ndarray, draws: Draws) -> np.ndarray:
    """B(α_s, α_s') (eq. 7) for every run: each gene from ``b`` if U(0,1) < ½, else from ``a``.

    a, b : (R, K) float, one pair per run, or (R, K, P) for genes of P parameters (a dynamic
    genome: a gene's amplitude and curve go together). Draws: ``uniforms((K,))``.
    Returns (R, K[, P]): every gene is one parent's, independently per gene.
    """
    a, b = _pair(a, b)
    take_b = _gene_mask(draws.uniforms((a.shape[1],)) < 0.5, a)
    return np.where(take_b, b, a)


def crossover_pair(a: np.ndarray, b: np.ndarray, draws: Draws) -> np.ndarray:
    """Uniform crossover giving two complementary children per run (the classical GA).

    a, b : (R, K). Draws: ``uniforms((K,))``. Returns (R, 2, K): the child taking ``b`` where
    U < ½, then its complement.
    """
    a, b = _pair(a, b)
    take_b = _gene_mask(draws.uniforms((a.shape[1],)) < 0.5, a)
    return np.stack([np.where(take_b, b, a), np.where(take_b, a, b)], axis=1)


def _gene_mask(mask: np.ndarray, genes: np.ndarray) -> np.ndarray:
    """An (R, K) mask over whole genes, broadcast over a gene's parameters."""
    return mask.reshape(mask.shape + (1,) * (genes.ndim - 2))


def _pair(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if a.ndim not in (2, 3) or a.shape != b.shape:
        raise ShapeError(
            f"crossover parents must both have shape (n_runs, n_genes); got {a.shape} and {b.shape}"
        )
    return a, b


# ---- M: mutation ---------------------------------------------------------------------------
def mutate(genes: np.ndarray, m: int, draws: Draws) -> np.ndarray:
    """M(α', {i}_m) (eq. 8): in each of M faces per run, m gene indices drawn independently from
    U{0..K−1} get new values from U(0,1).

    genes : (R, M, K) float. Draws (nothing when m = 0 or K = 0): ``integers(K, (M, m))``, then
    ``uniforms((M, m))``. Indices are drawn with replacement, so a face has *at most* m changed
    genes; values cover the whole range [0, 1). Returns a new array.
    """
    genes = np.asarray(genes, dtype=np.float64)
    if genes.ndim != 3:
        raise ShapeError(f"genes must have shape (n_runs, n_faces, n_genes); got {genes.shape}")
    if m < 0:
        raise ShapeError(f"mutation_genes (m) must be >= 0; got {m}")
    out = genes.copy()
    _, n, k = genes.shape
    if m and k:
        _assign(out, draws.integers(k, (n, m)), draws.uniforms((n, m)))
    return out


def _assign(faces: np.ndarray, index: np.ndarray, values: np.ndarray) -> None:
    """faces[r, i, index[r, i, j]] = values[r, i, j], in place (later j wins on a repeat)."""
    r, n, k = faces.shape
    flat = faces.reshape(r * n, k)
    rows = np.repeat(np.arange(r * n), index.shape[-1])
    flat[rows, index.reshape(-1)] = values.reshape(-1)


# ---- A: averaging (whole arithmetic recombination) ------------------------------------------
def average(members: np.ndarray) -> np.ndarray:
    """A({α_s}_S) (eq. 9): the mean of S chromosomes, per run.

    members : (R, S, K) float, S >= 1. Returns (R, K) float, gene by gene within the members'
    range.
    """
    members = np.asarray(members, dtype=np.float64)
    if members.ndim != 3:
        raise ShapeError(f"members must have shape (n_runs, S, n_genes); got {members.shape}")
    if members.shape[1] == 0:
        raise ShapeError("average needs at least one face; got 0")
    mean: np.ndarray = members.mean(axis=1)
    return mean


# ---- R: random generation -------------------------------------------------------------------
def random_faces(n: int, n_genes: int, x: int, draws: Draws) -> np.ndarray:
    """R({i}_x) (eq. 10): n new faces per run, each with x indices from U{0..K−1} set to U(0,1).

    Draws (nothing when n, K or x is 0): ``integers(K, (n, x))``, then ``uniforms((n, x))``.
    Indices are drawn independently (with replacement), so a face has *at most* x active genes;
    all other genes are 0. Returns (R, n, K) float.
    """
    if n < 0 or n_genes < 0 or x < 0:
        raise ShapeError(f"random_faces needs n, n_genes, x >= 0; got {n}, {n_genes}, {x}")
    out = np.zeros((draws.runs, n, n_genes))
    if n and n_genes and x:
        _assign(out, draws.integers(n_genes, (n, x)), draws.uniforms((n, x)))
    return out
