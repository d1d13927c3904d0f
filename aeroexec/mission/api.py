"""The mission API: what a mission script calls, bound to one executive.

The functions of Aerostack's `executive_engine_api` (2017), in snake_case and in the
thesis' camelCase, so the thesis' Appendix C mission runs unchanged but for its
Python 2 prints:

* `execute_behavior(name, **args)`: activate, then advance the executive until that
  activation's event; returns the event code as a string ("GOAL_ACHIEVED", ...), or
  "ERROR" when the activation was refused (as Aerostack's API did; `last_error()` says
  why). Executing a recurrent behavior is refused at once: it would never return.
* `activate_behavior(name, **args)` -> bool: activate and return at once.
* `inhibit_behavior(name)` -> bool.
* `consult_belief(query)` -> (bool, {var: value}); `true_belief(query)` -> bool;
  `add_belief(belief)`, `remove_belief(belief)` -> bool.

Every call is published on `mission/command` first: those are the session's external
inputs, which replay feeds back. Each names the line of the mission script that made it
(`line`, the innermost frame of the script's own code), so a report can point at it.
"""

from __future__ import annotations

import sys
import types
from collections.abc import Callable
from typing import Any

from aeroexec.errors import MissionError
from aeroexec.executive.beliefs import BeliefSyntaxError
from aeroexec.executive.clock import NS_PER_S
from aeroexec.executive.executive import Executive
from aeroexec.executive.messages import BehaviorEvent
from aeroexec.interrupts import check as check_interrupts

MODULE_NAME = "executive_engine_api"
#: The `__name__` a mission script runs under (`script.run_script`).
MISSION_NAMESPACE = "__aeroexec_mission__"
REFUSED = "ERROR"
#: How long `execute_behavior` waits for a behavior with no timeout (clock seconds).
DEFAULT_WAIT_S = 3600.0


Spelling = Callable[[str], str]


def _mission_line() -> int:
    """The line of the mission script's own code that is calling the API (0: none, as
    for the recorded commands replay feeds back)."""
    frame = sys._getframe(1)
    while frame is not None:
        if frame.f_globals.get("__name__") == MISSION_NAMESPACE:
            return frame.f_lineno or 0
        frame = frame.f_back  # type: ignore[assignment]
    return 0


def _snake(name: str) -> str:
    return name


def _camel(name: str) -> str:
    """`activate_behavior` as the thesis' missions spell it: `activateBehavior`."""
    head, *rest = name.split("_")
    return head + "".join(part.capitalize() for part in rest)


class MissionAPI:
    """Each function in both spellings; a message names the API in the spelling the
    mission used (`executeBehavior` is told to use `activateBehavior`)."""

    def __init__(self, executive: Executive, max_wait_s: float = DEFAULT_WAIT_S) -> None:
        self.executive = executive
        self.max_wait_s = max_wait_s
        self._last_error = ""
        self._ended: dict[int, BehaviorEvent] = {}
        executive.add_event_listener(self._on_event)

    def _on_event(self, event: BehaviorEvent) -> None:
        self._ended[event.uid] = event

    def _command(self, command: str, **fields: Any) -> None:
        # A safe point too: a mission polling beliefs in a loop never steps the clock.
        check_interrupts()
        line = _mission_line()
        where = {"line": line} if line else {}
        self.executive.bus.publish("mission/command", {"command": command, **fields, **where})

    # -- behaviors -----------------------------------------------------------------------
    def execute_behavior(self, name: str, **arguments: Any) -> str:
        return self._execute(name, arguments, _snake)

    def executeBehavior(self, name: str, **arguments: Any) -> str:
        return self._execute(name, arguments, _camel)

    def _execute(self, name: str, arguments: dict[str, Any], spell: Spelling) -> str:
        self._command("execute_behavior", behavior=name, arguments=arguments)
        descriptor = self.executive.catalog.behaviors.get(name)
        if descriptor is not None and descriptor.recurrent:
            raise MissionError(
                f"{spell('execute_behavior')}('{name}'): {name} is recurrent and would never "
                f"return; use {spell('activate_behavior')} and {spell('inhibit_behavior')}"
            )
        result = self.executive.activate_behavior(name, arguments)
        if not result.ok:
            self._last_error = result.error
            return REFUSED
        uid = result.payload["uid"]
        timeout = descriptor.timeout if descriptor and descriptor.timeout else self.max_wait_s
        # The behavior's own timeout ends it first; the margin only guards against a
        # behavior that ignores it.
        finished = self.executive.run_until(lambda: uid in self._ended, timeout + 1.0)
        if not finished:
            raise MissionError(
                f"{spell('execute_behavior')}('{name}'): no event after {timeout + 1.0:g} s "
                f"(clock at {self.executive.clock.now_ns() / NS_PER_S:.1f} s)"
            )
        self._last_error = ""
        return self._ended.pop(uid).code.value

    def activate_behavior(self, name: str, **arguments: Any) -> bool:
        self._command("activate_behavior", behavior=name, arguments=arguments)
        result = self.executive.activate_behavior(name, arguments)
        self._last_error = result.error
        return result.ok

    def inhibit_behavior(self, name: str) -> bool:
        self._command("inhibit_behavior", behavior=name)
        result = self.executive.inhibit_behavior(name)
        self._last_error = result.error
        return result.ok

    def last_error(self) -> str:
        """Why the last behavior command was refused ('' when it was not)."""
        return self._last_error

    # -- beliefs -------------------------------------------------------------------------
    def consult_belief(self, query: str) -> tuple[bool, dict[str, Any]]:
        return self._consult(query, "consult_belief")

    def consultBelief(self, query: str) -> tuple[bool, dict[str, Any]]:
        return self._consult(query, "consultBelief")

    def true_belief(self, query: str) -> bool:
        return self._consult(query, "true_belief")[0]

    def trueBelief(self, query: str) -> bool:
        return self._consult(query, "trueBelief")[0]

    def _consult(self, query: str, called: str) -> tuple[bool, dict[str, Any]]:
        self._command("consult_belief", query=query)
        try:
            return self.executive.beliefs.query(query)
        except BeliefSyntaxError as exc:
            raise MissionError(f"{called}: {exc.message}") from None

    def add_belief(self, belief: str) -> bool:
        return self._add(belief, "add_belief")

    def addBelief(self, belief: str) -> bool:
        return self._add(belief, "addBelief")

    def _add(self, belief: str, called: str) -> bool:
        self._command("add_belief", belief=belief)
        try:
            return self.executive.beliefs.add(belief)
        except BeliefSyntaxError as exc:
            raise MissionError(f"{called}: {exc.message}") from None

    def remove_belief(self, belief: str) -> bool:
        return self._remove(belief, "remove_belief")

    def removeBelief(self, belief: str) -> bool:
        return self._remove(belief, "removeBelief")

    def _remove(self, belief: str, called: str) -> bool:
        self._command("remove_belief", belief=belief)
        try:
            return self.executive.beliefs.remove(belief)
        except BeliefSyntaxError as exc:
            raise MissionError(f"{called}: {exc.message}") from None

    # The thesis' spelling of the rest (their messages name no other function).
    activateBehavior = activate_behavior
    inhibitBehavior = inhibit_behavior
    lastError = last_error

    def as_module(self) -> types.ModuleType:
        """A module object a script can `import executive_engine_api as api`."""
        module = types.ModuleType(MODULE_NAME, "aeroexec mission API bound to one executive")
        for name in dir(self):
            if not name.startswith("_") and name not in ("executive", "max_wait_s", "as_module"):
                setattr(module, name, getattr(self, name))
        return module
