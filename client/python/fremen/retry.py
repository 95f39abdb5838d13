"""Reconnecting after UNAVAILABLE (the daemon restarted, the network dropped): the bounded,
jittered exponential backoff that fremen.connect(reconnect=...) configures.

The Client retries its idempotent unary calls with it (retrying()), and an IngestSession uses its
pauses() between the streams it opens to resume after its stream failed. Why jitter: robots that
lost the same daemon would otherwise all come back at the same instants. Why bounds: a daemon that
stays away must end in fremen.Unavailable, so that the caller can decide, rather than a hang.

Thread-safety: a Backoff is immutable; each pauses() iterator belongs to one thread.
"""

import dataclasses
import random
import time
from typing import Any, Callable, Iterator, Optional, TypeVar

from fremen import errors

Result = TypeVar("Result")


@dataclasses.dataclass(frozen=True)
class Backoff:
    """The pauses between tries after UNAVAILABLE: before retry n (n = 1, 2, ...) a pause of
    min(maximum, initial · multiplier^(n−1)) seconds, shortened by a random fraction of at most
    `jitter`; at most `max_attempts` tries in all (the first one included), and no pause that would
    end more than `max_elapsed` seconds after the first failure."""
    initial: float = 0.1
    multiplier: float = 2.0
    maximum: float = 5.0
    jitter: float = 0.2
    max_attempts: int = 10
    max_elapsed: float = 30.0

    def __post_init__(self) -> None:
        checks = [
            ("initial", self.initial > 0, "> 0"),
            ("multiplier", self.multiplier >= 1, ">= 1"),
            ("maximum", self.maximum >= self.initial, ">= initial"),
            ("jitter", 0 <= self.jitter <= 1, "in [0, 1]"),
            ("max_attempts", isinstance(self.max_attempts, int) and self.max_attempts >= 1, "an integer >= 1"),
            ("max_elapsed", self.max_elapsed >= 0, ">= 0"),
        ]
        for field, ok, requirement in checks:
            if not ok:
                raise errors.InvalidArgument(f"Backoff.{field} must be {requirement}, got {getattr(self, field)!r}")

    def delay(self, retry: int, draw: Callable[[], float] = random.random) -> float:
        """The pause before retry number `retry` (1 = the first retry); `draw` gives a number in
        [0, 1) that picks how much jitter shortens it."""
        base = min(self.maximum, self.initial * self.multiplier ** (retry - 1))
        return base * (1 - self.jitter * draw())

    def pauses(self, clock: Callable[[], float] = time.monotonic,
               draw: Callable[[], float] = random.random) -> Iterator[float]:
        """The pauses before each retry, from the first failure on, until a bound is reached."""
        start = clock()
        for retry in range(1, self.max_attempts):
            pause = self.delay(retry, draw)
            if clock() - start + pause > self.max_elapsed:
                return
            yield pause

    def channel_options(self) -> list[tuple[str, Any]]:
        """gRPC channel options that make the channel's own reconnection attempts (after a lost
        connection it tries again only after its own backoff, 1 s growing to 120 s by default)
        follow the same pace, so that a retry finds the daemon soon after it is back."""
        return [("grpc.initial_reconnect_backoff_ms", max(1, int(self.initial * 1000))),
                ("grpc.max_reconnect_backoff_ms", max(1, int(self.maximum * 1000)))]


def retrying(backoff: Optional[Backoff], attempt: Callable[[], Result],
             sleep: Callable[[float], None] = time.sleep) -> Result:
    """attempt() again, after backoff's pauses, while it raises fremen.Unavailable; its result, or
    the last Unavailable once the bound is reached. backoff None: one try."""
    if backoff is None:
        return attempt()
    pauses = backoff.pauses()
    while True:
        try:
            return attempt()
        except errors.Unavailable:
            pause = next(pauses, None)
            if pause is None:
                raise
            sleep(pause)
