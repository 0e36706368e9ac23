"""Power analysis by simulation: how many participants to tell two groups' prototypes apart?

Model. Group A's participants hold prototype α_A, group B's α_B (optionally each participant
their own: the prototype plus N(0, ``participant_sd``²) per gene, clipped to [0, 1]). Every
trial is a simulated GA run (the study's GA settings, an observer — CD by default — with
choice noise ``noise_temperature``) toward the participant's prototype, so its final face
carries the GA noise. A participant's measured prototype is the mean of their ``trials`` final
faces. Participant spread and choice noise are assumptions of the study design: 0 and 0 (the
defaults of the library) is the most optimistic case, and ``emogen power`` flags it.

Test. For n participants per group, the statistic is the CD (eq. 12) between the two groups'
mean measured prototypes (``statistic="cd"``, blind to intensity: prototypes differing only in
scale have CD 0) or their Euclidean distance (``"ed"``, intensity-aware); its null comes from
``permutations`` random relabellings of the 2n participants, p = (1 + #{T_perm ≥ T}) /
(1 + permutations). Power is the share of ``replicates`` simulated experiments with p ≤ α
(± its binomial standard error).

**Fresh participants.** Every simulated experiment draws its own participants (a
:data:`Sampler` returns new, independent ones on every call): replicate r holds a sequence of
participants per group, extended as n grows, and its experiment at n uses the first n of each.
Within one n the replicates share no participant, so the estimate is exactly Binomial(replicates,
power)/replicates; curves at different n are positively correlated (nested), which smooths them
without biasing any point. (Resampling two fixed pools with replacement, as this module once
did, makes the pools' own difference a real effect: false positives grew with n.)

**False-positive rate beside every power curve.** The same participants also give null
experiments — replicate 2k's group-A participants against replicate 2k+1's, and likewise for
B — in which both groups share one prototype: the share with p ≤ α is the test's false-positive
rate at that n (α for a calibrated test: the participants are exchangeable there).

The result is the power curve over n, a logistic curve in log n fitted to it by binomial
maximum likelihood (floor α: power → α as the effect vanishes), and the smallest n whose fitted
power reaches the wanted power. A permutation test cannot go below p = 2 / C(2n, n) (the
labelling and its mirror image give the same statistic), so α = 0.05 needs at least n = 4
however large the difference.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from emogen.analysis.power_required import (
    Required,
    fit_power_curve,
    fitted_power,
    required_n,
)
from emogen.config import SimulationConfig
from emogen.errors import ConfigError

if TYPE_CHECKING:
    from emogen.model.face import FaceModel
    from emogen.model.rig import Rig

#: ``sample(count) -> (count, S)``: the measured prototypes of ``count`` NEW participants of a
#: group, independent of every earlier call.
Sampler = Callable[[int], np.ndarray]
STATISTICS = ("cd", "ed")


@dataclass(frozen=True)
class PowerResult:
    """curve: n, simulated power, its standard error, the fitted curve, and the false-positive
    rate of the same test on null experiments (``false_positive``, ``fp_se``). ``n_required``:
    the smallest n whose *fitted* power reaches the target (None: not within max_n) — the fit
    smooths the Monte Carlo noise of single points — or, where the fit misfits the simulated
    points, their interpolation (``required``: which, the fit check, a 95% interval;
    :mod:`emogen.analysis.power_required`); ``n_observed``: the smallest simulated n whose own
    estimate reached it."""

    curve: pd.DataFrame
    n_required: int | None
    target_power: float
    alpha: float
    effect_cd: float  # CD between the two groups' mean measured prototypes (all simulated)
    settings: dict[str, object]
    n_observed: int | None = None
    fit: tuple[float, float] | None = None
    effect_ed: float = float("nan")
    required: Required | None = None  # n_required with its fit check and 95% interval

    @property
    def max_false_positive(self) -> float:
        return float(self.curve["false_positive"].max())


@dataclass(eq=False)
class GroupSampler:
    """Fresh simulated participants of one group: each call simulates ``count`` new ones
    (their own jittered prototype when ``participant_sd`` > 0, ``trials`` GA runs each) and
    returns their measured prototypes (count, S). Run seeds are children of ``seed`` in order,
    the jitter comes from its own generator: the k-th participant is the same whatever the
    calls' sizes."""

    config: SimulationConfig
    source: Rig | FaceModel
    prototype: np.ndarray
    seed: int
    participant_sd: float = 0.0
    trials: int = 1
    _state: dict[str, object] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        from emogen.simulate import build_problem

        w = np.asarray(self.prototype, dtype=np.float64)
        if not np.any(w > 0):
            raise ConfigError("a prototype needs at least one non-zero weight")
        if self.trials < 1 or self.participant_sd < 0:
            raise ConfigError(
                f"trials must be >= 1 and participant_sd >= 0; got {self.trials}, "
                f"{self.participant_sd}"
            )
        rig = self.source.rig if hasattr(self.source, "rig") else self.source
        named = {s: float(v) for s, v in zip(rig.shape_names, w, strict=True) if v > 0}
        cfg = self.config.model_copy(
            update={"target": named, "target_file": None, "runs": 1, "seed": self.seed}
        )
        problem = build_problem(cfg, self.source, all_weights=True)
        self._state.update(
            problem=problem,
            rig=rig,
            seeds=np.random.SeedSequence(self.seed),
            jitter=np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(0x5D,))),
        )

    def targets(self, count: int) -> np.ndarray:
        """(count, S) the next participants' own prototypes (full weights)."""
        rig: Rig = self._state["rig"]  # type: ignore[assignment]
        eye = self.config.ga.eye_motion
        w = np.asarray(self.prototype, dtype=np.float64)
        if self.participant_sd <= 0:
            return np.tile(w, (count, 1))
        genes = rig.contract(w[None], eye)[0]
        rng: np.random.Generator = self._state["jitter"]  # type: ignore[assignment]
        g = np.clip(genes + rng.normal(0.0, self.participant_sd, (count, len(genes))), 0, 1)
        g[~np.any(g > 0, axis=1)] = genes  # a participant needs some expression
        return np.asarray(rig.expand(g, eye))

    def __call__(self, count: int) -> np.ndarray:
        from emogen.analysis.elites import simulate_elites
        from emogen.rng import _to_seed

        targets = np.repeat(self.targets(count), self.trials, axis=0)
        ss: np.random.SeedSequence = self._state["seeds"]  # type: ignore[assignment]
        seeds = np.array([_to_seed(c) for c in ss.spawn(len(targets))], dtype=np.int64)
        out = np.empty((len(targets), targets.shape[1]))
        for lo in range(0, len(targets), 4096):  # bounded memory
            hi = min(lo + 4096, len(targets))
            el = simulate_elites(
                self._state["problem"],  # type: ignore[arg-type]
                np.arange(lo, hi),
                seeds[lo:hi],
                target=targets[lo:hi],
            )
            out[lo:hi] = el.final
        return out.reshape(count, self.trials, -1).mean(axis=1)


def _statistic(mean_a: np.ndarray, mean_b: np.ndarray, kind: str) -> np.ndarray:
    from emogen.metrics import cosine_distance

    if kind == "cd":
        return np.asarray(cosine_distance(mean_a, mean_b))
    return np.asarray(np.linalg.norm(mean_a - mean_b, axis=-1))


def permutation_p(a: np.ndarray, b: np.ndarray, perms: np.ndarray, statistic: str = "cd") -> float:
    """p of the permutation test of two groups (n, S) each, relabellings ``perms`` (P, 2n)."""
    n = len(a)
    x = np.concatenate([a, b])
    observed = _statistic(a.mean(0), b.mean(0), statistic)
    null = _statistic(perms @ x / n, (1.0 - perms) @ x / n, statistic)
    return float((1 + np.sum(null >= observed)) / (1 + len(perms)))


def rejection_rates(
    a: np.ndarray,
    b: np.ndarray,
    n: int,
    *,
    alpha: float = 0.05,
    permutations: int = 400,
    statistic: str = "cd",
    rng: np.random.Generator,
) -> tuple[float, float]:
    """(power, false-positive rate) at n from participants a, b (R, ≥ n, S): replicate r's
    experiment compares a[r, :n] with b[r, :n]; the null experiments compare a[2k] with
    a[2k+1] and b[2k] with b[2k+1] (both groups one prototype)."""
    if n < 2:
        raise ConfigError(f"power needs at least 2 participants per group; got {n}")
    labels = np.concatenate([np.ones(n), np.zeros(n)])
    perms = np.stack([rng.permutation(labels) for _ in range(permutations)])
    reps = len(a)
    hits = [permutation_p(a[r, :n], b[r, :n], perms, statistic) <= alpha for r in range(reps)]
    null = [
        permutation_p(g[k, :n], g[k + 1, :n], perms, statistic) <= alpha
        for g in (a, b)
        for k in range(0, reps - 1, 2)
    ]
    return float(np.mean(hits)), float(np.mean(null))


def participants_grid(max_n: int) -> list[int]:
    """2, 3, … up to max_n, roughly geometric (about 16 values)."""
    if max_n < 2:
        raise ConfigError(f"max participants must be at least 2; got {max_n}")
    return sorted({int(v) for v in np.rint(np.geomspace(2, max_n, 16))})


def power_analysis(
    sample_a: Sampler,
    sample_b: Sampler,
    *,
    target_power: float = 0.8,
    alpha: float = 0.05,
    max_n: int = 100,
    replicates: int = 400,
    permutations: int = 400,
    statistic: str = "cd",
    seed: int = 0,
    settings: dict[str, object] | None = None,
) -> PowerResult:
    """The power curve over n — a roughly geometric grid up to three points past the wanted
    power, with four more n between the grid points where it is first reached — with the
    false-positive rate at each n, a fitted curve (:func:`fit_power_curve`) and the smallest n
    reaching the wanted power. ``sample_a``/``sample_b`` give fresh participants (module doc)."""
    if not 0 < target_power < 1 or not 0 < alpha < 1:
        raise ConfigError(f"power and alpha must be in (0, 1); got {target_power}, {alpha}")
    if statistic not in STATISTICS:
        raise ConfigError(f"statistic must be one of {STATISTICS}; got {statistic!r}")
    if replicates < 2:
        raise ConfigError(f"replicates must be at least 2; got {replicates}")
    rng = np.random.default_rng(seed)
    drawn: list[np.ndarray] = []

    def participants(n: int) -> tuple[np.ndarray, np.ndarray]:
        have = drawn[0].shape[1] if drawn else 0
        if n > have:  # extend every replicate's sequence with fresh participants
            new = [
                f(replicates * (n - have)).reshape(replicates, n - have, -1)
                for f in (sample_a, sample_b)
            ]
            if drawn:
                new = [np.concatenate([old, x], axis=1) for old, x in zip(drawn, new, strict=True)]
            drawn[:] = new
        return drawn[0], drawn[1]

    rates: dict[int, tuple[float, float]] = {}

    def at(n: int) -> float:
        a, b = participants(n)
        rates[n] = rejection_rates(
            a, b, n, alpha=alpha, permutations=permutations, statistic=statistic, rng=rng
        )
        return rates[n][0]

    grid = participants_grid(max_n)
    above = 0
    for i, n in enumerate(grid):
        if at(n) >= target_power:
            if above == 0 and i > 0:  # a few points between the bracketing grid points
                inner = np.unique(np.linspace(grid[i - 1], n, 6).round().astype(int))[1:-1]
                for m in inner.tolist():
                    at(m)
            above += 1
            if above == 3:  # anchor the fitted curve above the wanted power, then stop
                break
    return _result(
        rates,
        drawn,
        target_power,
        alpha,
        replicates,
        max_n,
        settings,
        {
            "alpha": alpha,
            "replicates": replicates,
            "permutations": permutations,
            "statistic": statistic,
            "participants": "fresh per simulated experiment",
        },
        rng,
    )


def _result(
    rates: dict[int, tuple[float, float]],
    drawn: list[np.ndarray],
    target_power: float,
    alpha: float,
    replicates: int,
    max_n: int,
    settings: dict[str, object] | None,
    opts: dict[str, object],
    rng: np.random.Generator,
) -> PowerResult:
    from emogen.metrics import cosine_distance

    ns = sorted(rates)
    pw = np.array([rates[n][0] for n in ns])
    fp = np.array([rates[n][1] for n in ns])
    n_null = 2 * (replicates // 2)
    fit = fit_power_curve(np.array(ns), pw, replicates, alpha)
    curve = pd.DataFrame(
        {
            "n": ns,
            "power": pw,
            "se": np.sqrt(pw * (1 - pw) / replicates),
            "fitted": fitted_power(np.array(ns), fit, alpha),
            "false_positive": fp,
            "fp_se": np.sqrt(fp * (1 - fp) / n_null),
        }
    )
    observed = next((n for n in ns if rates[n][0] >= target_power), None)
    required = required_n(
        np.array(ns), pw, replicates, target=target_power, alpha=alpha, max_n=max_n, rng=rng
    )
    ma = drawn[0].reshape(-1, drawn[0].shape[-1]).mean(0)
    mb = drawn[1].reshape(-1, drawn[1].shape[-1]).mean(0)
    return PowerResult(
        curve,
        required.n,
        target_power,
        alpha,
        float(cosine_distance(ma, mb)),
        dict(settings or {}) | opts,
        observed,
        fit,
        float(np.linalg.norm(ma - mb)),
        required,
    )
