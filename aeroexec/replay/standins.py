"""Stand-in behaviors for open-loop replay: they end as the recording says.

A stand-in does not fly anything. Before each replayed activation the `Script` is told
the recorded command; the stand-in then

* answers `check_situation` with the recorded answer of that activation (the situation
  depended on the real world, which open loop cannot rebuild); when none was recorded
  (the activation was refused before the check), it asks the real behavior class being
  replayed (the standard library's or a developer's), against the beliefs fed from the
  recorded vehicle state;
* ends with the recorded code at the recorded instant, for activations that ended by
  themselves (GOAL_ACHIEVED, WRONG_PROGRESS, ASSUMPTION_CONFLICT, PROCESS_FAILURE): at
  the first tick at or after the time its end event was recorded (at once, in
  `on_start`, when that time has already come). The instant, not the duration after the
  replayed start: replay starts a command at the first tick at or after its recorded
  time, so a duration counted from there would end the behavior up to a tick late, after
  the next command, which in a wall-clock recording follows the end event by a fraction
  of a millisecond and would then interrupt it. Activations that were interrupted,
  timed out or still running are left running: the replayed commands interrupt them
  again, and the catalog's (new) timeout ends them, so a shortened timeout shows as
  TIME_OUT.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

from aeroexec.catalog.model import Catalog
from aeroexec.executive.behavior import ALLOWED, Behavior, Finished, Situation
from aeroexec.executive.beliefs import Beliefs
from aeroexec.executive.clock import NS_PER_S
from aeroexec.executive.messages import EventCode
from aeroexec.replay.outcome import CommandOutcome

#: Codes a behavior ends with by itself (the others come from outside it).
SELF_ENDED = frozenset(
    {
        EventCode.GOAL_ACHIEVED,
        EventCode.WRONG_PROGRESS,
        EventCode.ASSUMPTION_CONFLICT,
        EventCode.PROCESS_FAILURE,
    }
)


@dataclass(frozen=True, slots=True)
class RecordedEnd:
    code: EventCode
    duration_ns: int
    detail: str = ""
    #: When it ended, in seconds of the replay's clock (the recorded time less the
    #: replay's offset); None: unknown, the duration after the start counts.
    at_s: float | None = None


def recorded_end(command: CommandOutcome, offset_ns: int | None = None) -> RecordedEnd | None:
    """How `command`'s activation ended by itself, if it did; with `offset_ns` (the
    recorded time of the replay clock's zero), also the instant it ended."""
    if not command.accepted or command.end_code is None or command.duration_ns is None:
        return None
    try:
        code = EventCode(command.end_code)
    except ValueError:
        return None
    if code not in SELF_ENDED:
        return None
    at_s = None
    if offset_ns is not None and command.end_ns is not None:
        at_s = (command.end_ns - offset_ns) / NS_PER_S
    return RecordedEnd(code, command.duration_ns, command.end_detail, at_s)


class Script:
    """What the next activation of each behavior should do (set by the player).
    `offset_ns`: the recorded time of the replay clock's zero (None: ends count from the
    replayed start)."""

    def __init__(self, offset_ns: int | None = None) -> None:
        self.offset_ns = offset_ns
        self._ends: dict[str, RecordedEnd | None] = {}
        self._situations: dict[str, tuple[bool, str] | None] = {}

    def arm(self, command: CommandOutcome) -> None:
        self._ends[command.behavior] = recorded_end(command, self.offset_ns)
        self._situations[command.behavior] = command.situation

    def end_for(self, behavior: str) -> RecordedEnd | None:
        return self._ends.get(behavior)

    def situation_for(self, behavior: str) -> tuple[bool, str] | None:
        return self._situations.get(behavior)


class StandIn(Behavior):
    """Base of the generated stand-in classes (see the module docstring)."""

    script: ClassVar[Script]
    _end: RecordedEnd | None = None

    def check_situation(self, beliefs: Beliefs) -> Situation:
        recorded = self.script.situation_for(self.behavior_name)
        if recorded is None:
            return super().check_situation(beliefs)
        ok, error = recorded
        if ok:
            return ALLOWED
        prefix = f"{self.behavior_name}: "
        return Situation(False, error[len(prefix) :] if error.startswith(prefix) else error)

    def on_start(self, args: Mapping[str, Any]) -> None:
        self._end = self.script.end_for(self.behavior_name)
        if self._end is not None and self._due(self._end):
            self.finish(self._end.code, self._end.detail)

    def on_run(self) -> Finished | None:
        end = self._end
        if end is not None and self._due(end):
            return Finished(end.code, end.detail)
        return None

    def _due(self, end: RecordedEnd) -> bool:
        if end.at_s is not None:
            return self.now >= end.at_s
        return self.elapsed >= end.duration_ns / NS_PER_S

    def on_stop(self) -> None:
        pass


def stand_in_library(
    catalog: Catalog, script: Script, real: Mapping[str, type[Behavior]]
) -> dict[str, type[Behavior]]:
    """One stand-in class per catalog behavior; each inherits `check_situation` from the
    real class of `real` (the behaviors being replayed) when there is one."""
    library: dict[str, type[Behavior]] = {}
    for name in catalog.behaviors:
        base = real.get(name)
        bases: tuple[type[Behavior], ...] = (StandIn,) if base is None else (StandIn, base)
        library[name] = type(f"StandIn_{name}", bases, {"name": name, "script": script})
    return library
