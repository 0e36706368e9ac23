"""Power analysis by simulation: how many participants to tell two groups' prototypes apart?

Model. Group A's participants hold prototype α_A, group B's α_B (optionally each participant
their own: the prototype plus N(0, ``participant_sd``²) per gene, clipped to [0, 1]). Every
trial is a simulated GA run (the study's GA settings, a CD observer with optional choice noise
``noise_temperature``) toward the participant's prototype, so its final face carries the GA
noise. A participant's measured prototype is the mean of their ``trials`` final faces.

Test. For n participants per group, the statistic is the CD (eq. 12) between the two groups'
mean measured prototypes (``statistic="cd"``; ``"ed"``: their Euclidean distance); its null
distribution comes from ``permutations`` random relabellings of the 2n participants, p =
(1 + #{T_perm ≥ T}) / (1 + permutations). Power is the share of ``replicates`` simulated
experiments with p ≤ α (± its binomial standard error). The simulated final faces are drawn
from pools of ``pool`` GA runs per group (with replacement), so no simulation is repeated for
every n. The result is the power curve over n, a logistic curve in log n fitted to it by
binomial maximum likelihood (floor α: power → α as the effect vanishes), and the smallest n
whose fitted power reaches the wanted power.
A permutation test cannot go below p = 2 / C(2n, n) (the labelling and its mirror image give
the same statistic), so α = 0.05 needs at least n = 4 however large the difference.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from emogen.config import SimulationConfig
from emogen.errors import ConfigError
from emogen.model.rig import Rig


@dataclass(frozen=True)
class PowerResult:
    """curve: n, simulated power, its standard error and the fitted curve. ``n_required``: the
    smallest n whose *fitted* power reaches the target (None: not within max_n) — the fit
    smooths the Monte Carlo noise of single points; ``n_observed``: the smallest simulated n
    whose own estimate reached it."""

    curve: pd.DataFrame
    n_required: int | None
    target_power: float
    alpha: float
    effect_cd: float  # CD between the two pools' mean final faces (the effect the GA delivers)
    settings: dict[str, object]
    n_observed: int | None = None
    fit: tuple[float, float] | None = None


def final_faces_pool(
    config: SimulationConfig,
    rig: Rig,
    prototype: np.ndarray,
    *,
    pool: int,
    seed: int,
    participant_sd: float = 0.0,
) -> np.ndarray:
    """Final faces (pool, S) of GA runs toward ``prototype`` (full weights), one per
    simulated participant (each its own jittered prototype when ``participant_sd`` > 0)."""
    from emogen.analysis.elites import simulate_elites, simulate_participants
    from emogen.rng import spawn_seeds
    from emogen.simulate import build_problem

    named = {s: float(v) for s, v in zip(rig.shape_names, prototype, strict=True) if v > 0}
    if not named:
        raise ConfigError("a prototype needs at least one non-zero weight")
    cfg = config.model_copy(
        update={"target": named, "target_file": None, "runs": pool, "seed": seed}
    )
    problem = build_problem(cfg.model_copy(update={"runs": 1}), rig, all_weights=True)
    if participant_sd <= 0:
        seeds = np.array(spawn_seeds(seed, pool), dtype=np.int64)
        return simulate_elites(problem, np.arange(pool), seeds).final
    genes = rig.contract(np.asarray(prototype, dtype=np.float64)[None], cfg.ga.eye_motion)[0]
    rng = np.random.default_rng(seed)
    targets = []
    for _ in range(pool):
        g = np.clip(genes + rng.normal(0.0, participant_sd, size=genes.shape), 0.0, 1.0)
        if not np.any(g > 0):
            g = genes
        targets.append(rig.expand(g[None], cfg.ga.eye_motion)[0])
    elites = simulate_participants(problem, np.stack(targets), spawn_seeds(seed, pool))
    return np.stack([e.final[0] for e in elites])


def _statistic(mean_a: np.ndarray, mean_b: np.ndarray, kind: str) -> np.ndarray:
    from emogen.metrics import cosine_distance

    if kind == "cd":
        return np.asarray(cosine_distance(mean_a, mean_b))
    return np.asarray(np.linalg.norm(mean_a - mean_b, axis=-1))


def power_at(
    pool_a: np.ndarray,
    pool_b: np.ndarray,
    n: int,
    *,
    trials: int = 1,
    alpha: float = 0.05,
    replicates: int = 400,
    permutations: int = 400,
    statistic: str = "cd",
    rng: np.random.Generator,
) -> float:
    """Share of simulated experiments with n participants per group that reject H0 at α."""
    if n < 2:
        raise ConfigError(f"power needs at least 2 participants per group; got {n}")
    rejections = 0
    labels = np.concatenate([np.ones(n), np.zeros(n)])
    perms = np.stack([rng.permutation(labels) for _ in range(permutations)])  # (P, 2n)
    for _ in range(replicates):
        a = pool_a[rng.integers(len(pool_a), size=(n, trials))].mean(axis=1)
        b = pool_b[rng.integers(len(pool_b), size=(n, trials))].mean(axis=1)
        x = np.concatenate([a, b])  # (2n, S)
        observed = _statistic(a.mean(0), b.mean(0), statistic)
        mean_a = perms @ x / n
        mean_b = (1.0 - perms) @ x / n
        null = _statistic(mean_a, mean_b, statistic)
        p = (1 + np.sum(null >= observed)) / (1 + permutations)
        rejections += int(p <= alpha)
    return rejections / replicates


def participants_grid(max_n: int) -> list[int]:
    """2, 3, … up to max_n, roughly geometric (about 16 values)."""
    if max_n < 2:
        raise ConfigError(f"max participants must be at least 2; got {max_n}")
    return sorted({int(v) for v in np.rint(np.geomspace(2, max_n, 16))})


def power_analysis(
    pool_a: np.ndarray,
    pool_b: np.ndarray,
    *,
    target_power: float = 0.8,
    alpha: float = 0.05,
    trials: int = 1,
    max_n: int = 100,
    replicates: int = 400,
    permutations: int = 400,
    statistic: str = "cd",
    seed: int = 0,
    settings: dict[str, object] | None = None,
) -> PowerResult:
    """The power curve over n — a roughly geometric grid up to three points past the wanted
    power, with four more n between the grid points where it is first reached — a fitted
    curve through it (:func:`fit_power_curve`) and the smallest n reaching the wanted power."""
    if not 0 < target_power < 1 or not 0 < alpha < 1:
        raise ConfigError(f"power and alpha must be in (0, 1); got {target_power}, {alpha}")
    if statistic not in ("cd", "ed"):
        raise ConfigError(f"statistic must be 'cd' or 'ed'; got {statistic!r}")
    rng = np.random.default_rng(seed)

    def at(n: int) -> float:
        return power_at(
            pool_a,
            pool_b,
            n,
            trials=trials,
            alpha=alpha,
            replicates=replicates,
            permutations=permutations,
            statistic=statistic,
            rng=rng,
        )

    opts = {
        "trials": trials,
        "alpha": alpha,
        "replicates": replicates,
        "permutations": permutations,
        "statistic": statistic,
    }
    powers: dict[int, float] = {}
    grid = participants_grid(max_n)
    above = 0
    for i, n in enumerate(grid):
        powers[n] = at(n)
        if powers[n] >= target_power:
            if above == 0 and i > 0:  # a few points between the bracketing grid points
                inner = np.unique(np.linspace(grid[i - 1], n, 6).round().astype(int))[1:-1]
                for m in inner.tolist():
                    powers[m] = at(m)
            above += 1
            if above == 3:  # anchor the fitted curve above the wanted power, then stop
                break
    ns = sorted(powers)
    pw = np.array([powers[n] for n in ns])
    fit = fit_power_curve(np.array(ns), pw, replicates, alpha)
    curve = pd.DataFrame(
        {
            "n": ns,
            "power": pw,
            "se": np.sqrt(pw * (1 - pw) / replicates),
            "fitted": fitted_power(np.array(ns), fit, alpha),
        }
    )
    observed = next((n for n in ns if powers[n] >= target_power), None)
    required = None
    if fit is not None:
        a_, b_ = fit
        x = (np.log((target_power - alpha) / (1 - target_power)) - a_) / b_
        n_fit = int(np.ceil(np.exp(x)))
        required = max(n_fit, _smallest_testable(alpha)) if n_fit <= max_n else None
    from emogen.metrics import cosine_distance

    effect = float(cosine_distance(pool_a.mean(0), pool_b.mean(0)))
    return PowerResult(
        curve, required, target_power, alpha, effect, dict(settings or {}) | opts, observed, fit
    )


def _smallest_testable(alpha: float) -> int:
    """Smallest n per group whose permutation test can reach p <= alpha: 2 / C(2n, n) <= alpha."""
    from math import comb

    n = 2
    while 2 / comb(2 * n, n) > alpha:
        n += 1
    return n


def fitted_power(n: np.ndarray, fit: tuple[float, float] | None, alpha: float) -> np.ndarray:
    """α + (1 − α) · sigmoid(a + b log n), the fitted power curve (NaN without a fit)."""
    if fit is None:
        return np.full(len(n), np.nan)
    a, b = fit
    return np.asarray(alpha + (1 - alpha) / (1 + np.exp(-(a + b * np.log(n)))))


def fit_power_curve(
    n: np.ndarray, power: np.ndarray, replicates: int, alpha: float
) -> tuple[float, float] | None:
    """Binomial maximum-likelihood fit of power(n) = α + (1 − α) sigmoid(a + b log n) to the
    simulated powers (each from ``replicates`` experiments), over the n whose permutation test
    can reach α. None when fewer than two such n, or when the fit does not rise with n."""
    from scipy.optimize import minimize

    keep = n >= _smallest_testable(alpha)
    x, k = np.log(n[keep]), np.round(power[keep] * replicates)
    if len(x) < 2:
        return None

    def nll(theta: np.ndarray) -> float:
        p = alpha + (1 - alpha) / (1 + np.exp(-(theta[0] + theta[1] * x)))
        p = np.clip(p, 1e-9, 1 - 1e-9)
        return float(-(k * np.log(p) + (replicates - k) * np.log(1 - p)).sum())

    res = minimize(
        nll,
        np.array([-3.0, 1.0]),
        method="Nelder-Mead",
        options={"xatol": 1e-6, "fatol": 1e-9, "maxiter": 4000},
    )
    a, b = (float(v) for v in res.x)
    return (a, b) if b > 0 else None
