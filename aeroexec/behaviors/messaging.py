"""BROADCAST_MESSAGE."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from aeroexec.executive.behavior import Behavior, Finished
from aeroexec.executive.messages import EventCode


class BroadcastMessage(Behavior):
    """Publish TEXT on the log and end at the first tick with GOAL_ACHIEVED.

    The text goes out in `on_start`, so it is recorded at the activation itself; the end
    event has to wait for the first tick because a behavior reports its end from `on_run`.
    """

    name = "BROADCAST_MESSAGE"
    argument_names = ("TEXT",)

    def on_start(self, args: Mapping[str, Any]) -> None:
        if "TEXT" not in args:
            raise ValueError("BROADCAST_MESSAGE needs TEXT")
        self.text = str(args["TEXT"])
        self.log(self.text)

    def on_run(self) -> Finished | None:
        return Finished(EventCode.GOAL_ACHIEVED, f"broadcast: {self.text}")
