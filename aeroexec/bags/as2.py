"""Aerostack2's behavior topics, turned into what `reconstruct.Reconstructor` reads.

An Aerostack2 behavior is a ROS 2 action server (`as2_behavior::BehaviorServer`) that
also publishes `<ns>/<Behavior>/_behavior/behavior_status` (as2_msgs/BehaviorStatus:
IDLE=0, RUNNING=1, PAUSED=2) every 100 ms, IDLE included. From a bag (see
docs/bags.md):

* the behaviors whose status is RUNNING or PAUSED make the **active list** (in the order
  they became active), given to the reconstructor on every change: a behavior
  appearing is an activation (reconstructed: goals are service calls), one leaving is
  an end;
* the **outcome** of an activation comes from its action: the first terminal status of
  each goal on `_action/status` (action_msgs/GoalStatusArray; a server repeats terminal
  goals in later arrays, so each goal counts once) or the `get_result` response, where
  the bag recorded action services: SUCCEEDED (with the result's `*_success` true) =
  GOAL_ACHIEVED, SUCCEEDED with `*_success` false or ABORTED = WRONG_PROGRESS,
  CANCELED = INTERRUPTED. A behavior stopped through `_behavior/stop` or a cancel ends
  without a terminal status (the BehaviorServer does not set one): only its status
  going IDLE shows it, and the reconstructor calls that an inhibition;
* the **arguments** of an activation are its goal (the `send_goal` request, where
  recorded), in the shape a catalog can check (`goal_arguments`): headers dropped (frame
  and stamp are transport), a stamped value as its value, a point, vector or pose as its
  `[x, y, z]` position, other nested fields as `<field>_<sub>`; the whole goal stays in
  the raw `send_goal` channel and its service call.
"""

from __future__ import annotations

import json
from typing import Any

from aeroexec.bags.extract import ActiveList, Event, plain
from aeroexec.executive.messages import EventCode

IDLE, RUNNING, PAUSED = 0, 1, 2
#: action_msgs/GoalStatus terminal values.
SUCCEEDED, CANCELED, ABORTED = 4, 5, 6
_TERMINAL = {SUCCEEDED: "SUCCEEDED", CANCELED: "CANCELED", ABORTED: "ABORTED"}


def _uuid(goal_id: object) -> bytes:
    value = getattr(goal_id, "uuid", goal_id)
    return bytes(plain(value)) if value is not None else b""


def _success(result: object) -> bool | None:
    """The `<x>_success` flag of an Aerostack2 action result (None when it has none)."""
    for name, value in (plain(result) or {}).items():
        if name.endswith("_success") and isinstance(value, bool):
            return value
    return None


_XYZ = ("x", "y", "z")


def _vector(value: dict[str, Any]) -> list[float] | None:
    if set(value) >= set(_XYZ) and set(value) <= {*_XYZ, "w"} and "w" not in value:
        numbers = [value[a] for a in _XYZ]
        if all(isinstance(n, (int, float)) and not isinstance(n, bool) for n in numbers):
            return [float(n) for n in numbers]
    return None


def _argument(value: Any) -> Any:
    """One goal field as an argument value (see the module docstring)."""
    if isinstance(value, list):
        return [_argument(v) for v in value]
    if not isinstance(value, dict):
        return value
    value = {k: v for k, v in value.items() if k != "header"}
    vector = _vector(value)
    if vector is not None:
        return vector
    for inner in ("point", "vector", "position", "pose"):  # Stamped, Pose, PoseWithID...
        if inner in value and isinstance(value[inner], dict):
            return _argument(value[inner])
    return {k: _argument(v) for k, v in value.items()}


def goal_arguments(goal: dict[str, Any]) -> dict[str, Any]:
    """A goal (plain fields) as flat activation arguments."""
    out: dict[str, Any] = {}
    for key, value in goal.items():
        if key == "header":
            continue
        argument = _argument(value)
        if isinstance(argument, dict):
            for sub, inner in goal_arguments(argument).items():
                out[f"{key}_{sub}"] = inner
        else:
            out[key] = argument
    return out


def outcome(status: int, result: object | None = None) -> tuple[EventCode, str] | None:
    """(code, detail) of a terminal goal status (and its result, when known)."""
    if status == SUCCEEDED:
        if result is not None and _success(result) is False:
            return EventCode.WRONG_PROGRESS, "succeeded with a false *_success result"
        return EventCode.GOAL_ACHIEVED, ""
    if status == ABORTED:
        return EventCode.WRONG_PROGRESS, "aborted"
    if status == CANCELED:
        return EventCode.INTERRUPTED, "canceled"
    return None


class BehaviorTimeline:
    """Per-behavior status, goals and outcomes of one Aerostack2 bag."""

    def __init__(self) -> None:
        self._status: dict[str, int] = {}
        self._active: dict[str, None] = {}  # in activation order
        self._arguments: dict[str, str] = {}
        self._finished: set[tuple[str, bytes]] = set()

    def status(self, behavior: str, message: object) -> ActiveList | None:
        """A behavior_status message: the new active list when it changed."""
        value = getattr(message, "status", None)
        if isinstance(value, bool) or not isinstance(value, int):
            return None
        previous = self._status.get(behavior, IDLE)
        self._status[behavior] = value
        was = previous in (RUNNING, PAUSED)
        now = value in (RUNNING, PAUSED)
        if was == now:
            return None
        if now:
            self._active[behavior] = None
        else:
            self._active.pop(behavior, None)
        names = tuple(self._active)
        return ActiveList(names, {n: self._arguments[n] for n in names if n in self._arguments})

    def goal(self, behavior: str, request: object) -> None:
        """A send_goal request: the arguments of the behavior's next activation."""
        goal = plain(getattr(request, "goal", None))
        if isinstance(goal, dict):
            self._arguments[behavior] = json.dumps(goal_arguments(goal), sort_keys=True)

    def goal_status(self, behavior: str, message: object) -> list[Event]:
        """A GoalStatusArray: an end event for each goal seen terminal the first time."""
        events = []
        for entry in getattr(message, "status_list", None) or ():
            status = getattr(entry, "status", None)
            if status not in _TERMINAL:
                continue
            goal = _uuid(getattr(getattr(entry, "goal_info", None), "goal_id", None))
            event = self._finish(behavior, goal, status, None)
            if event is not None:
                events.append(event)
        return events

    def result(self, behavior: str, request: object, response: object) -> Event | None:
        """A get_result response (with its request's goal id)."""
        status = getattr(response, "status", None)
        if status not in _TERMINAL:
            return None
        goal = _uuid(getattr(request, "goal_id", None)) if request is not None else b""
        return self._finish(behavior, goal, status, getattr(response, "result", None))

    def _finish(self, behavior: str, goal: bytes, status: int, result: Any) -> Event | None:
        key = (behavior, goal)
        if goal and key in self._finished:
            return None
        self._finished.add(key)
        found = outcome(status, result)
        if found is None:
            return None
        code, detail = found
        return Event(behavior, code, _TERMINAL[status], detail, None)
