"""How big a replication is: runs per condition, simulated participants, the power analysis."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

#: --quick's own first seed: its runs are not a prefix of the full run's (seed 1)
QUICK_SEED = 101


@dataclass(frozen=True)
class ReplicateSettings:
    """How big the replication is; :meth:`quick_settings` / :meth:`full_settings`."""

    quick: bool = False
    runs: int = 500
    participants: int = 240
    seed: int = 1
    # independent seeds: seed, seed + 1, …; every verdict combines them (seed-level t intervals
    # over the seeds' fitted objects: 10, as docs/replication uses; --quick: 3, a smoke run)
    seeds: int = 10
    render: bool = True
    participant_noise: float = 0.05  # simulated participants' choice noise (softmax T, CD units)
    power_replicates: int = 300
    power_permutations: int = 300
    power_max_n: int = 120

    @classmethod
    def quick_settings(cls, **kw: Any) -> ReplicateSettings:
        base = {
            "quick": True,
            "seed": QUICK_SEED,
            "runs": 100,
            "seeds": 3,
            "participants": 60,
            "power_replicates": 100,
            "power_permutations": 100,
            "power_max_n": 60,
        }
        return cls(**(base | kw))

    @property
    def seed_list(self) -> list[int]:
        return [self.seed + k for k in range(self.seeds)]

    @classmethod
    def full_settings(cls, **kw: Any) -> ReplicateSettings:
        return cls(**kw)
