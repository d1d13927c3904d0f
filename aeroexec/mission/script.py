"""Load and run a mission script (a Python file in the style of the thesis' Appendix C).

The script imports `executive_engine_api` and defines `runMission()` (also accepted:
`run_mission()` or `main()`). The runner provides that module, bound to the executive,
only while the script runs, and never runs a script that does not compile.
"""

from __future__ import annotations

import sys
import traceback
from dataclasses import dataclass
from pathlib import Path
from types import CodeType
from typing import Any

from aeroexec.errors import Mark, MissionError
from aeroexec.inputs import read_text
from aeroexec.mission.api import MODULE_NAME, MissionAPI

ENTRY_POINTS = ("runMission", "run_mission", "main")


@dataclass(frozen=True, slots=True)
class MissionScript:
    path: str
    text: str
    code: CodeType


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
    text = read_text(path, "a mission script", MissionError)
    return compile_mission(text, file)


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
        try:
            exec(script.code, namespace)
        except Exception as exc:
            return _failed(exc)
        entry = next((namespace[n] for n in ENTRY_POINTS if callable(namespace.get(n))), None)
        if entry is None:
            raise MissionError(
                f"defines none of {', '.join(n + '()' for n in ENTRY_POINTS)}", Mark(script.path)
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


def _failed(exc: Exception) -> MissionOutcome:
    message = exc.message if isinstance(exc, MissionError) else f"{type(exc).__name__}: {exc}"
    return MissionOutcome(False, None, message, traceback.format_exc())
