"""Feed a recorded `mission/command` stream to an executive at the recorded times.

Used by open-loop replay (always) and by closed-loop replay of a recording without a
mission script. Each command is published on `mission/command` exactly as the mission
API publishes it, then carried out the way the API does, except that nothing blocks:
the recorded times pace the commands. With `wait_for_execute` (closed loop) the command
after an `execute_behavior` also waits for that activation's end event, as the script
did, so a behavior that now takes longer is not cut short by the next command.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterable
from typing import Any

from aeroexec.executive.beliefs import BeliefSyntaxError
from aeroexec.executive.executive import Executive, StopRequested
from aeroexec.executive.messages import BehaviorEvent
from aeroexec.replay.outcome import ACTIVATIONS, CommandOutcome

#: How long a replayed `execute_behavior` may wait for its end event (clock seconds),
#: as the mission API's default.
MAX_WAIT_S = 3600.0


def command_message(command: CommandOutcome) -> dict[str, Any]:
    """The `mission/command` payload the mission API published for `command`."""
    data: dict[str, Any] = {"command": command.command}
    if command.command in ACTIVATIONS:
        data["behavior"] = command.behavior
        data["arguments"] = dict(command.arguments)
    elif command.command == "inhibit_behavior":
        data["behavior"] = command.behavior
    elif command.command == "consult_belief":
        data["query"] = command.text
    elif command.command in ("add_belief", "remove_belief"):
        data["belief"] = command.text
    if command.line is not None:  # the recorded script's line, for reports
        data["line"] = command.line
    return data


class CommandPlayer:
    def __init__(
        self,
        executive: Executive,
        *,
        offset_ns: int = 0,
        arm: Callable[[CommandOutcome], None] | None = None,
        wait_for_execute: bool = False,
        max_wait_s: float = MAX_WAIT_S,
    ) -> None:
        """`offset_ns`: the recorded time of the executive's clock zero; `arm` is told
        each activation command just before it is carried out (open loop's stand-ins)."""
        self.executive = executive
        self.offset_ns = offset_ns
        self.arm = arm
        self.wait_for_execute = wait_for_execute
        self.max_wait_s = max_wait_s
        self._ended: set[int] = set()
        executive.add_event_listener(self._on_event)

    def _on_event(self, event: BehaviorEvent) -> None:
        self._ended.add(event.uid)

    def play(
        self, commands: Iterable[CommandOutcome], until_ns: int | None = None
    ) -> StopRequested | None:
        """Every command at its recorded time, then run on to `until_ns` (recorded time).
        An observer's stop (a live viewer's abort: `Executive.request_stop`) ends the play
        at that tick, the commands after it unplayed: that stop is returned (the caller
        ends the session), else None."""
        try:
            for command in commands:
                self._advance_to(command.time_ns)
                self._carry_out(command)
            if until_ns is not None:
                self._advance_to(until_ns)
        except StopRequested as stop:
            return stop
        return None

    def _advance_to(self, recorded_ns: int) -> None:
        target = recorded_ns - self.offset_ns
        clock = self.executive.clock
        upcoming = getattr(clock, "upcoming_ns", None)
        if upcoming is not None:
            # A clock that knows its next tick (a live flight's recorded ticks): the
            # command goes in before the first tick after its recorded time, as it did.
            while upcoming() <= target:
                self.executive.step()
            return
        while clock.now_ns() < target:
            self.executive.step()

    def _carry_out(self, command: CommandOutcome) -> None:
        executive = self.executive
        executive.bus.publish("mission/command", command_message(command))
        kind = command.command
        if kind in ACTIVATIONS:
            descriptor = executive.catalog.behaviors.get(command.behavior)
            if kind == "execute_behavior" and descriptor is not None and descriptor.recurrent:
                return  # the mission API refuses this before asking the executive
            if self.arm is not None:
                self.arm(command)
            result = executive.activate_behavior(command.behavior, command.arguments)
            if result.ok and kind == "execute_behavior" and self.wait_for_execute:
                uid = result.payload["uid"]
                timeout = descriptor.timeout if descriptor and descriptor.timeout else None
                wait = (timeout + 1.0) if timeout else self.max_wait_s
                executive.run_until(lambda: uid in self._ended, wait)
            self._ended.clear()
        elif kind == "inhibit_behavior":
            executive.inhibit_behavior(command.behavior)
        elif kind in ("consult_belief", "add_belief", "remove_belief"):
            beliefs = executive.beliefs
            action = {
                "consult_belief": beliefs.query,
                "add_belief": beliefs.add,
                "remove_belief": beliefs.remove,
            }[kind]
            # A malformed belief raised into the mission; the executive saw nothing.
            with contextlib.suppress(BeliefSyntaxError):
                action(command.text)
