"""The GA's operators (Section III-B): S, B, M, A and R, pure functions of arrays and an rng.

Every operator works in *gene space*: ``genes : (n_faces, n_genes) float`` in [0, 1], one
column per unique core shape of the rig (a left/right pair is one gene). Symmetry therefore
holds by construction — :meth:`emogen.model.rig.Rig.expand` writes a gene's value to every
shape of the gene — and corrective shapes, not being genes, are never evolved.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from emogen.errors import SelectionError, ShapeError


def check_genes(genes: np.ndarray, name: str = "genes") -> np.ndarray:
    genes = np.asarray(genes, dtype=np.float64)
    if genes.ndim != 2:
        raise ShapeError(f"{name} must have shape (n_faces, n_genes); got {genes.shape}")
    return genes


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
def crossover(a: np.ndarray, b: np.ndarray, *, rng: np.random.Generator) -> np.ndarray:
    """B(α_s, α_s') (eq. 7): each gene from ``b`` if U(0,1) < ½, else from ``a``.

    a, b : (n_faces, n_genes) float, the pairs (row i of a with row i of b).
    Returns (n_faces, n_genes): every gene is one parent's, independently per gene.
    """
    a, b = check_genes(a, "a"), check_genes(b, "b")
    if a.shape != b.shape:
        raise ShapeError(f"crossover parents must have equal shapes; got {a.shape} and {b.shape}")
    take_b = rng.random(a.shape) < 0.5
    return np.where(take_b, b, a)


def crossover_pair(
    a: np.ndarray, b: np.ndarray, *, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Uniform crossover giving two complementary children (for the classical GA)."""
    a, b = check_genes(a, "a"), check_genes(b, "b")
    if a.shape != b.shape:
        raise ShapeError(f"crossover parents must have equal shapes; got {a.shape} and {b.shape}")
    take_b = rng.random(a.shape) < 0.5
    return np.where(take_b, b, a), np.where(take_b, a, b)


# ---- M: mutation ---------------------------------------------------------------------------
def mutate(genes: np.ndarray, m: int, *, rng: np.random.Generator) -> np.ndarray:
    """M(α', {i}_m) (eq. 8): m gene indices drawn independently from U{0..K−1}, new values U(0,1).

    genes : (n_faces, K) float. Indices are drawn with replacement, so a face has *at most*
    m changed genes. Values cover the whole range [0, 1). Returns a new array.
    """
    genes = check_genes(genes)
    if m < 0:
        raise ShapeError(f"mutation_genes (m) must be >= 0; got {m}")
    out = genes.copy()
    n, k = genes.shape
    if m == 0 or k == 0:
        return out
    index = rng.integers(0, k, size=(n, m))
    values = rng.random((n, m))
    rows = np.repeat(np.arange(n), m)
    out[rows, index.reshape(-1)] = values.reshape(-1)
    return out


# ---- A: averaging (whole arithmetic recombination) ------------------------------------------
def average(members: np.ndarray) -> np.ndarray:
    """A({α_s}_S) (eq. 9): the mean of S chromosomes.

    members : (S, n_genes) float, S >= 1. Returns (n_genes,) float, gene by gene within the
    members' range.
    """
    members = check_genes(members, "members")
    if members.shape[0] == 0:
        raise ShapeError("average needs at least one face; got 0")
    return members.mean(axis=0)


# ---- R: random generation -------------------------------------------------------------------
def random_faces(n: int, n_genes: int, x: int, *, rng: np.random.Generator) -> np.ndarray:
    """R({i}_x) (eq. 10): n new faces, each with x indices drawn from U{0..K−1} set to U(0,1).

    Indices are drawn independently (with replacement), so a face has *at most* x active genes;
    all other genes are 0. Returns (n, n_genes) float.
    """
    if n < 0 or n_genes < 0 or x < 0:
        raise ShapeError(f"random_faces needs n, n_genes, x >= 0; got {n}, {n_genes}, {x}")
    out = np.zeros((n, n_genes))
    if n == 0 or n_genes == 0 or x == 0:
        return out
    index = rng.integers(0, n_genes, size=(n, x))
    values = rng.random((n, x))
    rows = np.repeat(np.arange(n), x)
    out[rows, index.reshape(-1)] = values.reshape(-1)
    return out
