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
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from types import CodeType
from typing import Any

from aeroexec.errors import Mark, MissionError
from aeroexec.mission.api import MODULE_NAME, MissionAPI

ENTRY_POINTS = ("runMission", "run_mission", "main")


@dataclass(frozen=True, slots=True)
class MissionScript:
    path: str
    text: str
    code: CodeType
    #: The directory the script was read from (importable while it runs); None for a
    #: script that was not read from a file (a recording's attachment).
    directory: str | None = None


@dataclass(frozen=True, slots=True)
class MissionOutcome:
    """How the mission function ended: returned (with its value) or raised."""

    returned: bool
    value: Any = None
    error: str = ""
    traceback: str = ""


def load_mission(path: str | Path) -> MissionScript:
    """Read and compile a mission script; `MissionError` with file:line:col if it can't."""
    file = str(path)
    p = Path(path)
    if not p.exists():
        raise MissionError("no such file", Mark(file))
    if p.is_dir():
        raise MissionError("is a directory, not a mission script", Mark(file))
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise MissionError(f"not UTF-8 text (byte {exc.start})", Mark(file)) from None
    except OSError as exc:
        raise MissionError(f"cannot read: {exc.strerror}", Mark(file)) from None
    script = compile_mission(text, file)
    return MissionScript(script.path, script.text, script.code, str(p.resolve().parent))


def compile_mission(text: str, file: str = "<mission>") -> MissionScript:
    try:
        code = compile(text, file, "exec", dont_inherit=True)
    except SyntaxError as exc:
        mark = Mark(file, exc.lineno or 0, exc.offset or 0)
        raise MissionError(f"invalid Python: {exc.msg}", mark) from None
    except ValueError as exc:  # e.g. null bytes
        raise MissionError(f"invalid Python: {exc}", Mark(file)) from None
    return MissionScript(file, text, code)


def run_script(script: MissionScript, api: MissionAPI) -> MissionOutcome:
    """Execute the script's top level, then its entry point, with the API importable.

    Exceptions raised by the mission are the mission's failure (an outcome), not ours;
    a script without an entry point is unusable input (`MissionError`).
    """
    namespace: dict[str, Any] = {"__name__": "__aeroexec_mission__", "__file__": script.path}
    previous = sys.modules.get(MODULE_NAME)
    sys.modules[MODULE_NAME] = api.as_module()
    try:
        with _importable(script.directory):
            try:
                exec(script.code, namespace)
            except Exception as exc:
                return _failed(exc)
            entry = next((namespace[n] for n in ENTRY_POINTS if callable(namespace.get(n))), None)
            if entry is None:
                raise MissionError(
                    f"defines none of {', '.join(n + '()' for n in ENTRY_POINTS)}",
                    Mark(script.path),
                )
            try:
                value = entry()
            except Exception as exc:
                return _failed(exc)
            return MissionOutcome(True, value)
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


def _failed(exc: Exception) -> MissionOutcome:
    message = exc.message if isinstance(exc, MissionError) else f"{type(exc).__name__}: {exc}"
    return MissionOutcome(False, None, message, traceback.format_exc())
