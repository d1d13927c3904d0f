"""WAIT: for some time, or until a visual marker has been observed."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from aeroexec.behaviors._support import holds, visual_marker
from aeroexec.executive.behavior import Behavior, Finished
from aeroexec.executive.messages import EventCode


class Wait(Behavior):
    """Wait DURATION seconds, or until the belief `visual_marker(ID)` holds for
    ID = UNTIL_OBSERVED_VISUAL_MARKER. With both, the marker ends the wait successfully
    and DURATION bounds it (TIME_OUT). Needs no vehicle, so it is always allowed."""

    name = "WAIT"
    argument_names = ("DURATION", "UNTIL_OBSERVED_VISUAL_MARKER")

    def on_start(self, args: Mapping[str, Any]) -> None:
        duration = args.get("DURATION")
        marker = args.get("UNTIL_OBSERVED_VISUAL_MARKER")
        if duration is None and marker is None:
            raise ValueError("WAIT needs DURATION or UNTIL_OBSERVED_VISUAL_MARKER")
        self.duration = None if duration is None else float(duration)
        self.marker = None if marker is None else int(marker)
        self.query = None if self.marker is None else visual_marker(self.marker)

    def on_run(self) -> Finished | None:
        if self.query is not None and holds(self.beliefs, self.query):
            return Finished(EventCode.GOAL_ACHIEVED, f"marker {self.marker} observed")
        if self.duration is not None and self.elapsed >= self.duration:
            if self.marker is None:
                return Finished(EventCode.GOAL_ACHIEVED, f"waited {self.duration:g} s")
            return Finished(
                EventCode.TIME_OUT,
                f"marker {self.marker} not observed within {self.duration:g} s",
            )
        return None
