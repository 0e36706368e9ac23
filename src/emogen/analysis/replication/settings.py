"""How big a replication is: runs per condition, simulated participants, the power analysis."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class ReplicateSettings:
    """How big the replication is; :meth:`quick_settings` / :meth:`full_settings`."""

    quick: bool = False
    runs: int = 500
    participants: int = 240
    seed: int = 1
    render: bool = True
    participant_noise: float = 0.05  # simulated participants' choice noise (softmax T, CD units)
    power_replicates: int = 300
    power_permutations: int = 300
    power_max_n: int = 120

    @classmethod
    def quick_settings(cls, **kw: Any) -> ReplicateSettings:
        base = {
            "quick": True,
            "runs": 100,
            "participants": 60,
            "power_replicates": 100,
            "power_permutations": 100,
            "power_max_n": 60,
        }
        return cls(**(base | kw))

    @classmethod
    def full_settings(cls, **kw: Any) -> ReplicateSettings:
        return cls(**kw)
