"""SIGINT, SIGTERM and SIGHUP as a cooperative exception at safe points.

A signal must not interrupt a recording in the middle of a record: an exception raised
inside `mcap`'s writer between two of its bookkeeping steps would leave a chunk index that
disagrees with the chunk, and the footer written afterwards would describe a corrupt file.
So the handler only notes the signal; long-running loops call `check()` at points where
stopping is safe (the executive once per tick, readers and converters once per message or
batch), and `check()` raises `Interrupted`. Everything above unwinds through its
`finally`/`with` blocks — the recorder writes its footer, a partial output is removed —
and the command line turns `Interrupted` into one line and exit code 128 + signal.

A second signal of the same kind while the first is still pending raises at once: the
escape hatch for code that never reaches a safe point (a mission spinning in its own
`while True:`).

`Interrupted` derives from `BaseException`, like `KeyboardInterrupt`, so a mission's
`except Exception:` cannot swallow the user's Ctrl-C.
"""

from __future__ import annotations

import signal
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

HANDLED: tuple[signal.Signals, ...] = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)

_pending: int | None = None
#: How many `signals_as_interrupts` blocks are active (they may nest).
_handling = 0


class Interrupted(BaseException):
    """The user (or the system) asked the process to stop with `signum`."""

    def __init__(self, signum: int) -> None:
        self.signum = signum
        self.name = signal.Signals(signum).name
        #: What was done about it ("recording finalized: out.mcap"), said in the one line.
        self.notes: list[str] = []
        super().__init__(f"interrupted by {self.name}")

    def __reduce__(self) -> tuple[object, ...]:
        # Raised in a worker process (replay --jobs), re-raised in the parent.
        return (_rebuild, (self.signum, tuple(self.notes)))

    def line(self) -> str:
        """The one line the command line prints."""
        return "; ".join([f"interrupted by {self.name}", *self.notes])

    @property
    def exit_code(self) -> int:
        """The shell's convention for a process ended by a signal."""
        return 128 + self.signum


def _rebuild(signum: int, notes: tuple[str, ...]) -> Interrupted:
    stop = Interrupted(signum)
    stop.notes.extend(notes)
    return stop


def pending() -> int | None:
    """The signal waiting to be acted on, if any (without consuming it)."""
    return _pending


def handling() -> bool:
    """Are signals being turned into `Interrupted` here? Then a `KeyboardInterrupt` can
    only have been raised by code (a mission's own `raise KeyboardInterrupt`)."""
    return _handling > 0


def check() -> None:
    """Raise `Interrupted` if a handled signal arrived since the last check."""
    global _pending
    if _pending is not None:
        signum, _pending = _pending, None
        raise Interrupted(signum)


def _note(signum: int, frame: FrameType | None) -> None:
    global _pending
    if _pending == signum:
        # Second signal of the same kind: the safe point never came; stop now.
        _pending = None
        raise Interrupted(signum)
    _pending = signum


def _note_only(signum: int, frame: FrameType | None) -> None:
    global _pending
    _pending = signum


def in_worker_process(signums: tuple[signal.Signals, ...] = HANDLED) -> None:
    """For a worker process of a command (replay --jobs): signals are noted for `check()`
    and never raise at once. A Ctrl-C reaches the parent and its workers alike, and the
    parent passes a signal it got alone on to them, so a worker may see the same signal
    twice: that must not count as the "second signal" escape hatch, which could stop it
    in the middle of writing a record. (The parent keeps the escape hatch.)"""
    global _handling
    for signum in signums:
        signal.signal(signum, _note_only)
    _handling = 1


@contextmanager
def signals_as_interrupts(signums: tuple[signal.Signals, ...] = HANDLED) -> Iterator[None]:
    """Within the block, `signums` are noted for `check()` instead of killing the process.

    Only the main thread can install handlers; elsewhere (a worker thread, an embedding
    application) the block leaves the handlers as they are.
    """
    global _pending, _handling
    previous: dict[int, object] = {}
    try:
        for signum in signums:
            previous[signum] = signal.signal(signum, _note)
    except ValueError:  # not the main thread
        pass
    installed = signal.SIGINT in previous
    _handling += installed
    try:
        yield
    finally:
        _handling -= installed
        for signum, handler in previous.items():
            signal.signal(signum, handler)  # type: ignore[arg-type]
        _pending = None
