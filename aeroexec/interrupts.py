"""SIGINT, SIGTERM and SIGHUP as an exception; a wall-clock limit on the user's code.

A signal must not interrupt a recording in the middle of a record: an exception raised
inside `mcap`'s writer between two of its bookkeeping steps would leave a chunk index that
disagrees with the chunk, and the footer written afterwards would describe a corrupt file.
So the handler first only notes the signal; long-running loops call `check()` at points
where stopping is safe (the executive once per tick, readers and converters once per
message or batch), and `check()` raises `Interrupted`. Everything above unwinds through
its `finally`/`with` blocks — the recorder writes its footer, a partial output is removed —
and the command line turns `Interrupted` into one line and exit code 128 + signal.

The user's code (a mission, a behaviors module being imported) may never reach a safe
point: `while True: pass`, `time.sleep(1e6)`, a loop at module top level. So the first
signal also arms a watchdog (SIGALRM): if no safe point took the signal within `GRACE_S`,
the watchdog raises `Interrupted` wherever the main thread is — unless it is inside a
*critical file* (the recorder writing a record, `critical_file()`), where it tries again a
few milliseconds later. While the user's code is running (`user_code()`) and keeps
catching the exception (`except BaseException: pass` in a loop), it is raised again at
every safe point and every `REPEAT_S`; if the user's code still holds on `FORCE_AFTER_S`
after the signal, the watchdog finishes what can be finished from the handler (each
recording gets its end record and footer, `at_forced_exit()`), prints the one line and
ends the process with `os._exit(128 + N)`. A second signal of the same kind raises at
once (outside a critical file).

The wall-clock limit (`--timeout`, `limit_user_code()`) works the same way: once the user's
code has run for the limit, `TimedOut` is raised where it is (a mission's failure, exit 1,
at the mission's file:line), again and again while it is caught, then the forced exit
(exit 1) `FORCE_AFTER_S - GRACE_S` later.

`Interrupted` and `TimedOut` derive from `BaseException`, like `KeyboardInterrupt`, so a
mission's `except Exception:` cannot swallow them. What no handler can catch — SIGKILL,
`os._exit()` called by the user's code — leaves a recording without its footer:
`aeroexec recover` makes a complete copy (docs/recording.md).
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import sysconfig
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from types import FrameType

HANDLED: tuple[signal.Signals, ...] = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)

#: How long a signal waits for a safe point before the watchdog raises it where it is.
GRACE_S = 0.5
#: How often it is raised again while the user's code keeps catching it.
REPEAT_S = 0.05
#: When the user's code still holds on this long after the signal: the forced exit.
FORCE_AFTER_S = 1.0
#: A watchdog that finds the main thread inside a critical file tries again this soon.
RETRY_S = 0.005

#: The signal waiting to be raised (by `check()` or the watchdog), and when it came.
_pending: int | None = None
_pending_at = 0.0
#: The signal that asked this process to stop, and when (it stays until the block ends).
_signal: int | None = None
_signal_at = 0.0
#: How many `signals_as_interrupts` blocks are active (they may nest).
_handling = 0
#: In a worker process, a repeated signal is the same request, not the escape hatch.
_worker = False
#: How deep the main thread is in the user's code (`user_code()`), and its deadline.
_user = 0
_deadline: float | None = None
_limit_s: float | None = None
#: Default wall-clock limit of the user's code in this process (`--timeout`).
_default_limit_s: float | None = None
#: May the watchdog end the process when the user's code never lets go?
_may_force = True
#: Who says the forced exit's line (`aeroexec run`).
_who = "aeroexec"
_critical_files: set[str] = set()
_finishers: dict[int, Callable[[str, str], str | None]] = {}
_alarm_installed = False
_previous_alarm: object = None


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


class TimedOut(BaseException):
    """The user's code ran for longer than its wall-clock limit (`--timeout`)."""

    def __init__(self, seconds: float) -> None:
        self.seconds = seconds
        super().__init__(f"still running after {seconds:g} s of wall-clock time (--timeout)")

    def __reduce__(self) -> tuple[object, ...]:
        return (TimedOut, (self.seconds,))


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
    """Raise `Interrupted` if a handled signal arrived since the last check — or at
    every check while the user's code is running after one (it may have caught the
    first) — and `TimedOut` when the user's code ran past its limit."""
    global _pending
    if _pending is not None:
        signum, _pending = _pending, None
        raise Interrupted(signum)
    if _user:
        if _signal is not None:
            raise Interrupted(_signal)
        if _deadline is not None and _limit_s is not None and time.monotonic() >= _deadline:
            raise TimedOut(_limit_s)


# -- what the watchdog needs to know ------------------------------------------------------
def critical_file(path: str) -> None:
    """Code in `path` (a module's `__file__`) must never be cut short by an exception
    raised from a signal handler: the watchdog waits until the main thread has left it."""
    _critical_files.add(path)


def at_forced_exit(finish: Callable[[str, str], str | None]) -> Callable[[], None]:
    """`finish(reason, detail)` runs before a forced exit (a recorder writes its end
    record and footer) and returns a note for the one line; returns the unregistering
    function."""
    key = id(finish)
    _finishers[key] = finish
    return lambda: _finishers.pop(key, None)


def limit_user_code(seconds: float | None) -> None:
    """The wall-clock limit of each run of the user's code in this process (each
    mission run, each behaviors import); None: no limit."""
    global _default_limit_s
    _default_limit_s = seconds if seconds and seconds != float("inf") else None


def user_code_limit() -> float | None:
    return _default_limit_s


def deadline(seconds: float | None = None) -> tuple[float, float] | None:
    """(monotonic deadline, limit) for a run of the user's code starting now, limited to
    `seconds` (default: `limit_user_code()`'s)."""
    limit = seconds if seconds is not None else _default_limit_s
    return (time.monotonic() + limit, limit) if limit else None


@contextmanager
def user_code(
    until: tuple[float, float] | None = None, *, forced_exit: bool = True
) -> Iterator[None]:
    """The block runs the user's code (a mission, a behaviors module's import): after a
    signal it is interrupted wherever it is, and by `TimedOut` once `until` (from
    `deadline()`) has passed. `forced_exit=False`: the watchdog never ends the process
    from the handler (a live flight must get its ending)."""
    global _user, _deadline, _limit_s, _may_force
    outer = (_deadline, _limit_s, _may_force)
    if until is not None and (_deadline is None or until[0] < _deadline):
        _deadline, _limit_s = until
    _may_force = _may_force and forced_exit
    _user += 1
    # Outside a command (a library caller) the alarm serves only the time limit.
    installed = until is not None and _install_alarm()
    _schedule()
    try:
        yield
    finally:
        _user -= 1
        _deadline, _limit_s, _may_force = outer
        if installed:
            _uninstall_alarm()
        else:
            _schedule()


# -- the handlers ---------------------------------------------------------------------------
def _note(signum: int, frame: FrameType | None) -> None:
    global _pending, _pending_at, _signal, _signal_at
    now = time.monotonic()
    if _signal is None:
        _signal, _signal_at = signum, now
        _pending, _pending_at = signum, now
    elif _pending == signum and not _worker and not _in_critical(frame):
        # Second signal of the same kind: the safe point never came; stop now.
        _pending = None
        raise Interrupted(signum)
    elif _pending is None and not _worker:
        # A signal during the clean-up of the first (a live flight's ending): the next
        # safe point, or the watchdog after its own grace, raises it.
        _pending, _pending_at = signum, now
    _schedule()


def _alarm(signum: int, frame: FrameType | None) -> None:
    """The watchdog: raise what is due where the main thread is, or end the process."""
    global _pending
    now = time.monotonic()
    due: BaseException | None = None
    if _pending is not None and now >= _pending_at + GRACE_S:
        due = Interrupted(_pending)
    elif _signal is not None and _user and now >= _signal_at + GRACE_S:
        due = Interrupted(_signal)
    elif _user and _deadline is not None and _limit_s is not None and now >= _deadline:
        due = TimedOut(_limit_s)
    if due is None:
        _schedule()
        return
    if _in_critical(frame):
        _arm(RETRY_S)
        return
    if _user and _may_force and now >= _forced_at():
        _force(due, frame)
    _pending = None
    _arm(REPEAT_S)
    raise due


def _forced_at() -> float:
    if _signal is not None:
        return _signal_at + FORCE_AFTER_S
    assert _deadline is not None
    return _deadline + FORCE_AFTER_S - GRACE_S


def _in_critical(frame: FrameType | None) -> bool:
    while frame is not None:
        if frame.f_code.co_filename in _critical_files:
            return True
        frame = frame.f_back
    return False


def _force(due: BaseException, frame: FrameType | None) -> None:
    """The user's code never let go: finish the recordings here, say so, exit."""
    if isinstance(due, Interrupted):
        reason, detail, code = "interrupted", due.name, due.exit_code
        head = f"{_who}: interrupted by {due.name}"
    else:
        where = user_place(frame)
        reason, detail, code = "timeout", str(due), 1
        head = f"{where + ': ' if where else _who + ': '}mission stopped: {due}"
    notes = []
    for finish in list(_finishers.values()):
        try:
            note = finish(reason, detail)
        except BaseException as exc:
            note = f"a recording could not be finished ({type(exc).__name__})"
        if note:
            notes.append(note)
    notes.append("the user's code kept running, so aeroexec exited without unwinding")
    with contextlib.suppress(BaseException):
        sys.stdout.flush()
    if not _worker:  # a worker's parent says the one line
        with contextlib.suppress(OSError):
            os.write(2, ("; ".join([head, *notes]) + "\n").encode("utf-8", "replace"))
    os._exit(code)


def user_place(frame: FrameType | None) -> str:
    """`file:line` of the innermost frame of the user's code (not aeroexec's, not
    Python's own library) on the stack of `frame`; '' when there is none."""
    ours = str(Path(__file__).resolve().parent) + os.sep
    library = sysconfig.get_paths()["stdlib"] + os.sep
    while frame is not None:
        file = frame.f_code.co_filename
        path = os.path.abspath(file)
        python_own = path.startswith(library) and "site-packages" not in path
        if not (file.startswith("<") or path.startswith(ours) or python_own):
            return f"{file}:{frame.f_lineno}"
        frame = frame.f_back
    return ""


# -- the timer ------------------------------------------------------------------------------
#: The longest the timer is set for (a huge --timeout wakes it up to look again).
_LONGEST_S = 86400.0


def _arm(delay: float) -> None:
    if _alarm_installed:
        signal.setitimer(signal.ITIMER_REAL, min(max(delay, 0.001), _LONGEST_S))


def _schedule() -> None:
    """Set the timer for the next thing the watchdog may have to do (or clear it)."""
    if not _alarm_installed:
        return
    now = time.monotonic()
    wake: float | None = None
    for since in (
        _pending_at if _pending is not None else None,
        _signal_at if _signal is not None and _user else None,
    ):
        if since is not None:
            at = since + GRACE_S if now < since + GRACE_S else now + REPEAT_S
            wake = at if wake is None else min(wake, at)
    if _user and _deadline is not None:
        at = _deadline if now < _deadline else now + REPEAT_S
        wake = at if wake is None else min(wake, at)
    if wake is None:
        signal.setitimer(signal.ITIMER_REAL, 0)
    else:
        _arm(wake - now)


def _install_alarm() -> bool:
    """Install the watchdog's SIGALRM handler (main thread only); True if done here."""
    global _alarm_installed, _previous_alarm
    if _alarm_installed:
        return False
    try:
        _previous_alarm = signal.signal(signal.SIGALRM, _alarm)
    except ValueError:  # not the main thread: no watchdog
        return False
    _alarm_installed = True
    return True


def _uninstall_alarm() -> None:
    global _alarm_installed
    if not _alarm_installed:
        return
    signal.setitimer(signal.ITIMER_REAL, 0)
    signal.signal(signal.SIGALRM, _previous_alarm)  # type: ignore[arg-type]
    _alarm_installed = False


def _reset() -> None:
    global _pending, _signal
    _pending = None
    _signal = None


def in_worker_process(signums: tuple[signal.Signals, ...] = HANDLED) -> None:
    """For a worker process of a command (replay --jobs): signals are noted for `check()`
    and the watchdog, never raised at once. A Ctrl-C reaches the parent and its workers
    alike, and the parent passes a signal it got alone on to them, so a worker may see
    the same signal twice: that must not count as the "second signal" escape hatch."""
    global _handling, _worker
    _reset()
    _worker = True
    for signum in signums:
        signal.signal(signum, _note)
    _install_alarm()
    _handling = 1


@contextmanager
def signals_as_interrupts(
    signums: tuple[signal.Signals, ...] = HANDLED, who: str = "aeroexec"
) -> Iterator[None]:
    """Within the block, `signums` are noted for `check()` and the watchdog instead of
    killing the process. `who` says the forced exit's line (`aeroexec run`).

    Only the main thread can install handlers; elsewhere (a worker thread, an embedding
    application) the block leaves the handlers as they are.
    """
    global _handling, _who, _default_limit_s
    previous: dict[int, object] = {}
    try:
        for signum in signums:
            previous[signum] = signal.signal(signum, _note)
    except ValueError:  # not the main thread
        pass
    installed = signal.SIGINT in previous
    alarm = installed and _install_alarm()
    outer_who, _who = _who, who
    _handling += installed
    try:
        yield
    finally:
        _handling -= installed
        _who = outer_who
        if installed and not _handling:
            _default_limit_s = None  # a command's --timeout ends with the command
        if alarm:
            _uninstall_alarm()
        for signum, handler in previous.items():
            signal.signal(signum, handler)  # type: ignore[arg-type]
        _reset()
