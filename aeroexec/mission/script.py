"""Load and run a mission script (a Python file in the style of the thesis' Appendix C).

The script imports `executive_engine_api` and defines `runMission()` (also accepted:
`run_mission()` or `main()`). The runner provides that module, bound to the executive,
only while the script runs, and never runs a script that does not compile. A script read
from a file can import modules from its own directory while it runs (the directory is
on `sys.path` for that time, and what was imported from it is forgotten afterwards).
"""

from __future__ import annotations

import contextlib
import sys
import traceback
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from types import CodeType
from typing import Any

from aeroexec.errors import AeroexecError, Mark, MissionError, one_line
from aeroexec.executive.executive import StopRequested, TimeLimitReached
from aeroexec.inputs import read_text
from aeroexec.interrupts import TimedOut, deadline, user_code
from aeroexec.interrupts import handling as handling_signals
from aeroexec.mission.api import MISSION_NAMESPACE, MODULE_NAME, MissionAPI

ENTRY_POINTS = ("runMission", "run_mission", "main")


@dataclass(frozen=True, slots=True)
class MissionScript:
    path: str
    text: str
    code: CodeType
    #: The directory the script was read from (importable while it runs); None for a
    #: script that was not read from a file (a recording's attachment).
    directory: str | None = None


class Ending(str, Enum):
    """How a session's mission ended (recorded as the session's end reason)."""

    RETURNED = "returned"
    RAISED = "raised"
    EXITED = "exited"  # the mission called sys.exit()
    TIME_LIMIT = "max_sim_time"
    TIMEOUT = "timeout"  # ran past its wall-clock limit (--timeout)
    STOPPED = "property"  # a violated property's action ended it (`--spec`)
    ABORTED = "abort"  # an operator aborted it (a live viewer's /abort_mission)

    @property
    def stopped(self) -> bool:
        """Stopped from outside at a tick boundary (`StopRequested`): the session's
        ending (its `action`) follows."""
        return self in (Ending.STOPPED, Ending.ABORTED)


@dataclass(frozen=True, slots=True)
class MissionOutcome:
    """How the mission function ended: returned (with its value) or not, and why."""

    returned: bool
    value: Any = None
    error: str = ""
    traceback: str = ""
    ending: Ending = Ending.RETURNED
    #: `file:line` of the mission's own line where it failed ('' when unknown).
    where: str = ""


def load_mission(path: str | Path) -> MissionScript:
    """Read and compile a mission script; `MissionError` with file:line:col if it can't."""
    file = str(path)
    text = read_text(path, "a mission script", MissionError)
    script = compile_mission(text, file)
    return MissionScript(script.path, script.text, script.code, str(Path(path).resolve().parent))


def compile_mission(text: str, file: str = "<mission>") -> MissionScript:
    try:
        code = compile(text, file, "exec", dont_inherit=True)
    except SyntaxError as exc:
        mark = Mark(file, exc.lineno or 0, exc.offset or 0)
        raise MissionError(f"invalid Python: {exc.msg}", mark) from None
    except ValueError as exc:  # e.g. null bytes
        raise MissionError(f"invalid Python: {exc}", Mark(file)) from None
    except (RecursionError, MemoryError):
        # CPython's compiler recurses once per level of nesting (5,000 unary minus signs,
        # `not not ...`, `lambda: lambda: ...`): no mission is written like that.
        raise MissionError("invalid Python: nested too deeply to compile", Mark(file)) from None
    return MissionScript(file, text, code)


def run_script(
    script: MissionScript,
    api: MissionAPI,
    time_limit_s: float | None = None,
    *,
    forced_exit: bool = True,
) -> MissionOutcome:
    """Execute the script's top level, then its entry point, with the API importable.

    Exceptions raised by the mission are the mission's failure (an outcome), not ours;
    a script without an entry point is unusable input (`MissionError`). The mission runs
    as the user's code (`interrupts.user_code`): a signal stops it wherever it is, and so
    does its wall-clock limit (`time_limit_s`, default `--timeout`'s), an outcome
    (`Ending.TIMEOUT`). `forced_exit=False`: a mission that never lets go of a signal is
    not ended by exiting the process (a live flight must get its ending).
    """
    until = deadline(time_limit_s)
    namespace: dict[str, Any] = {"__name__": MISSION_NAMESPACE, "__file__": script.path}
    previous = sys.modules.get(MODULE_NAME)
    sys.modules[MODULE_NAME] = api.as_module()
    try:
        with _importable(script.directory):
            ended = _run(lambda: exec(script.code, namespace), script, until, forced_exit)
            if ended is not None:
                return ended
            entry = next((namespace[n] for n in ENTRY_POINTS if callable(namespace.get(n))), None)
            if entry is None:
                raise MissionError(
                    f"defines none of {', '.join(n + '()' for n in ENTRY_POINTS)}",
                    Mark(script.path),
                )
            result: list[Any] = []
            ended = _run(lambda: result.append(entry()), script, until, forced_exit)
            return ended if ended is not None else MissionOutcome(True, result[0])
    finally:
        if previous is None:
            sys.modules.pop(MODULE_NAME, None)
        else:
            sys.modules[MODULE_NAME] = previous


@contextlib.contextmanager
def _importable(directory: str | None) -> Iterator[None]:
    """`directory` on `sys.path` while the block runs; afterwards it is removed, and the
    modules first imported from it are forgotten (the next run imports them afresh)."""
    if directory is None:
        yield
        return
    before = set(sys.modules)
    sys.path.insert(0, directory)
    try:
        yield
    finally:
        with contextlib.suppress(ValueError):
            sys.path.remove(directory)
        inside = Path(directory)
        for name in set(sys.modules) - before:
            file = getattr(sys.modules.get(name), "__file__", None)
            if file and Path(file).is_relative_to(inside):
                del sys.modules[name]


def _run(
    step: Callable[[], object],
    script: MissionScript,
    until: tuple[float, float] | None = None,
    forced_exit: bool = True,
) -> MissionOutcome | None:
    """Run one part of the mission; None if it went through, else how the mission ended.

    Whatever the mission raises or calls is the mission's ending, not aeroexec's:
    `sys.exit(7)` ends the mission (a failure unless the code is 0), and so does a
    `KeyboardInterrupt` the mission raises itself. A real Ctrl-C is not one of those:
    while signals are handled (`aeroexec.interrupts`) it arrives as `Interrupted`,
    which passes through like the executive's `TimeLimitReached` and aeroexec's own
    input/output errors (the recorder's, say) other than `MissionError`.
    `sys.exit()` and `sys.exit(0)` end the mission as if it had returned.
    """
    try:
        with user_code(until, forced_exit=forced_exit):
            step()
    except TimeLimitReached as exc:
        return MissionOutcome(
            False, None, str(exc), traceback.format_exc(), Ending.TIME_LIMIT, _where(exc, script)
        )
    except TimedOut as exc:
        return MissionOutcome(
            False, None, str(exc), traceback.format_exc(), Ending.TIMEOUT, _where(exc, script)
        )
    except StopRequested as exc:
        ending = Ending.ABORTED if exc.by == Ending.ABORTED.value else Ending.STOPPED
        return MissionOutcome(
            False, None, exc.reason, traceback.format_exc(), ending, _where(exc, script)
        )
    except SystemExit as exc:
        where = _where(exc, script)
        if exc.code is None or exc.code == 0:
            return MissionOutcome(True, None, ending=Ending.EXITED, where=where)
        return MissionOutcome(
            False,
            None,
            f"the mission called sys.exit({exc.code!r})",
            traceback.format_exc(),
            Ending.EXITED,
            where,
        )
    except KeyboardInterrupt as exc:
        if not handling_signals():
            raise  # possibly the user's Ctrl-C: not ours to swallow
        return _failed(exc, script)
    except AeroexecError as exc:
        if not isinstance(exc, MissionError):
            raise
        return _failed(exc, script)
    except Exception as exc:
        return _failed(exc, script)
    return None


def _failed(exc: BaseException, script: MissionScript) -> MissionOutcome:
    if isinstance(exc, MissionError):
        message = exc.message
    else:
        message = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
    return MissionOutcome(
        False, None, one_line(message), traceback.format_exc(), Ending.RAISED, _where(exc, script)
    )


def _where(exc: BaseException, script: MissionScript) -> str:
    """`file:line` of the innermost frame of the mission script in the traceback."""
    line = 0
    for frame in traceback.extract_tb(exc.__traceback__):
        if frame.filename == script.path and frame.lineno:
            line = frame.lineno
    if line == 0 and isinstance(exc, SyntaxError) and exc.filename == script.path:
        line = exc.lineno or 0
    return f"{script.path}:{line}" if line else ""
