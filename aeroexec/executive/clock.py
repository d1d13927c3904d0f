"""Time for the executive: the only place the core may learn what time it is.

`SimClock` makes runs reproducible (time advances only when the executive steps);
`WallClock` is for live flights. Both count nanoseconds from the session start, which
is what the recording uses as log time.
"""

from __future__ import annotations

import time
from typing import Protocol

NS_PER_S = 1_000_000_000
#: The thesis' "low-rate loop" for behavior run(): 10 Hz.
DEFAULT_TICK_NS = 100_000_000


class Clock(Protocol):
    kind: str
    tick_ns: int

    def now_ns(self) -> int: ...

    def advance(self) -> int:
        """Move to the next tick (waiting for it on a wall clock); return the new time."""
        ...


class SimClock:
    kind = "sim"

    def __init__(self, tick_ns: int = DEFAULT_TICK_NS) -> None:
        if tick_ns <= 0:
            raise ValueError("tick must be positive")
        self.tick_ns = tick_ns
        self._now = 0

    def now_ns(self) -> int:
        return self._now

    def advance(self) -> int:
        self._now += self.tick_ns
        return self._now


class Paced:
    """Any clock that steps by itself (a simulated one, or the recorded ticks of a
    flight) kept to the wall clock (`run --live --speed`, `replay --live --speed`), so a
    viewer sees the session as it would happen. The session and its recording are those
    of the unpaced clock: everything but `advance` is the clock's own (`kind`, ...).
    Tick time `now` is due `now / speed` of real time after the first tick (set-up
    before it is not waited for); only when each tick runs is paced, never what it
    computes."""

    def __init__(self, clock: Clock, speed: float = 1.0) -> None:
        if not speed > 0:
            raise ValueError("speed must be positive")
        self.clock = clock
        self.speed = speed
        self._wall_start: int | None = None

    @property
    def kind(self) -> str:
        return self.clock.kind

    @property
    def tick_ns(self) -> int:
        return self.clock.tick_ns

    def now_ns(self) -> int:
        return self.clock.now_ns()

    def advance(self) -> int:
        now = self.clock.advance()
        if self._wall_start is None:
            self._wall_start = time.monotonic_ns() - round(now / self.speed)
        delay = self._wall_start + round(now / self.speed) - time.monotonic_ns()
        if delay > 0:
            time.sleep(delay / NS_PER_S)
        return now

    def __getattr__(self, name: str) -> object:
        return getattr(self.clock, name)


def paced(clock: Clock, speed: float | None) -> Clock:
    """`clock`, kept to the wall clock at `speed` (None: as fast as it runs)."""
    return clock if speed is None else Paced(clock, speed)


class WallClock:
    kind = "wall"

    def __init__(self, tick_ns: int = DEFAULT_TICK_NS) -> None:
        self.tick_ns = tick_ns
        self._start = time.monotonic_ns()
        self._next = tick_ns

    def now_ns(self) -> int:
        return time.monotonic_ns() - self._start

    def advance(self) -> int:
        now = self.now_ns()
        delay = self._next - now
        if delay > 0:
            time.sleep(delay / NS_PER_S)
            now = self.now_ns()
        # A tick that came late (the executive was busy: a command waiting for its ack)
        # is not made up for with a burst of back-to-back ticks: the next one is the
        # next slot of the grid that is still ahead.
        missed = max(0, (now - self._next) // self.tick_ns)
        self._next += (missed + 1) * self.tick_ns
        return now
