"""How far one replay is, for a progress bar: the pass that reads the recording, in bytes
of the file, then the re-run, in the recording's own time (the clock the replay advances
through; messages would not do: a replay publishes fewer than the recording holds, whose
derived channels it writes only when it records)."""

from __future__ import annotations

from aeroexec.executive.messages import ServiceCallRecord, TopicRecord
from aeroexec.progress import Advance

_NS_PER_MS = 1_000_000
#: A bar moves in at most this many steps (each one a call into the drawing library).
_STEPS = 500


class ReadProgress:
    """`on_read(offset)` for `RecordingSource.scan`: advances by the bytes read past."""

    def __init__(self, advance: Advance) -> None:
        self._advance = advance
        self._done = 0

    def __call__(self, offset: int) -> None:
        if offset > self._done:
            self._advance(offset - self._done)
            self._done = offset


class ReplayedTime:
    """A bus observer that advances by the replay's clock, in milliseconds from its first
    message, up to `total_ms` (the recording's span); `finish()` fills the rest."""

    def __init__(self, advance: Advance, total_ms: int) -> None:
        self._advance = advance
        self._total = total_ms
        self._step = max(1, total_ms // _STEPS)
        self._origin: int | None = None
        self._done = 0

    def on_service_call(self, record: ServiceCallRecord) -> None:
        self._at(record.log_time_ns)

    def on_topic(self, record: TopicRecord) -> None:
        self._at(record.log_time_ns)

    def finish(self) -> None:
        if self._done < self._total:
            self._advance(self._total - self._done)
            self._done = self._total

    def _at(self, log_time_ns: int) -> None:
        if self._origin is None:
            self._origin = log_time_ns
        ms = min((log_time_ns - self._origin) // _NS_PER_MS, self._total)
        if ms - self._done >= self._step:
            self._advance(ms - self._done)
            self._done = ms
