"""Per-client rate limits: a token bucket per client address, and the 429 answer.

A bucket holds at most ``burst`` tokens and gains ``per_minute / 60`` tokens a second; an action
takes one. An empty bucket answers 429 with ``Retry-After`` (whole seconds until a token is back).
Behind a reverse proxy, the client address is the proxy's unless the server trusts its
``X-Forwarded-For`` (uvicorn ``--forwarded-allow-ips``; see docs/study.md).
"""

from __future__ import annotations

import math
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass

from fastapi import HTTPException, Request

#: Buckets kept at most (least recently used forgotten first): memory stays bounded.
MAX_CLIENTS = 10_000


@dataclass(frozen=True)
class RateLimit:
    """``burst`` actions at once, then ``per_minute`` a minute (``per_minute=0``: no limit)."""

    burst: int
    per_minute: float

    def __post_init__(self) -> None:
        if self.burst < 1:
            raise ValueError(f"rate limit burst must be at least 1; got {self.burst}")
        if self.per_minute < 0:
            raise ValueError(f"rate limit per_minute must be ≥ 0; got {self.per_minute}")

    @classmethod
    def parse(cls, text: str) -> RateLimit:
        """``"20/min"`` (burst 20, 20 a minute), ``"5/min,burst=10"`` or ``"off"``."""
        spec = text.strip().lower()
        if spec in ("off", "0", "none"):
            return cls(burst=1, per_minute=0)
        rate, _, extra = spec.partition(",")
        number, _, unit = rate.partition("/")
        try:
            per_minute = float(number) * {"min": 1, "s": 60, "h": 1 / 60}[unit or "min"]
            burst = int(extra.removeprefix("burst=")) if extra else max(1, math.ceil(per_minute))
            return cls(burst=burst, per_minute=per_minute)
        except (ValueError, KeyError):
            raise ValueError(
                f"rate limit must look like '20/min', '5/min,burst=10' or 'off'; got {text!r}"
            ) from None

    @property
    def enabled(self) -> bool:
        return self.per_minute > 0


class TokenBuckets:
    """One token bucket per key (a client address); thread-safe."""

    def __init__(self, limit: RateLimit, clock: Callable[[], float] = time.monotonic) -> None:
        self.limit = limit
        self.clock = clock
        self._buckets: OrderedDict[str, tuple[float, float]] = OrderedDict()
        self._lock = threading.Lock()

    def _level(self, key: str, now: float) -> float:
        tokens, then = self._buckets.get(key, (float(self.limit.burst), now))
        return min(float(self.limit.burst), tokens + (now - then) * self.limit.per_minute / 60)

    def wait(self, key: str) -> float:
        """Seconds until ``key`` may act again (0: now), taking nothing."""
        if not self.limit.enabled:
            return 0.0
        with self._lock:
            tokens = self._level(key, self.clock())
        return 0.0 if tokens >= 1 else (1 - tokens) * 60 / self.limit.per_minute

    def take(self, key: str) -> float:
        """Take a token for ``key``: 0 when it had one, else the seconds until it will."""
        if not self.limit.enabled:
            return 0.0
        with self._lock:
            now = self.clock()
            tokens = self._level(key, now)
            if tokens < 1:
                self._buckets[key] = (tokens, now)
                return (1 - tokens) * 60 / self.limit.per_minute
            self._buckets[key] = (tokens - 1, now)
            self._buckets.move_to_end(key)
            while len(self._buckets) > MAX_CLIENTS:
                self._buckets.popitem(last=False)
            return 0.0


def client_key(request: Request) -> str:
    """The client's address as the server sees it (a proxy's unless it is trusted)."""
    return request.client.host if request.client is not None else "unknown"


def too_many(wait_s: float, what: str) -> HTTPException:
    """429 with ``Retry-After`` and a sentence saying what was limited and when to retry."""
    seconds = max(1, math.ceil(wait_s))
    return HTTPException(
        429,
        f"too many {what} from this address; try again in {seconds} s",
        headers={"Retry-After": str(seconds)},
    )
