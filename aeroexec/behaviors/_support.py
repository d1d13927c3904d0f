"""What the standard behaviors share: belief checks, progress watching, hover-on-stop.

Situation checks read beliefs only (as Aerostack's did), through queries parsed once at
import: `check_situation` is on every activation's path.
"""

from __future__ import annotations

import math
from collections import deque

from aeroexec.executive.behavior import ALLOWED, Behavior, Finished, Situation
from aeroexec.executive.beliefs import Beliefs, Compound, parse_query
from aeroexec.executive.messages import EventCode
from aeroexec.vehicles.base import Vec3, VehicleCommandError

#: Vehicle faults that end a motion behavior with PROCESS_FAILURE: the link to the
#: autopilot is gone, or the pilot/autopilot took the vehicle out of the commanded mode.
LINK_FAULTS = ("link_lost", "mode_changed")
#: The battery is empty: the vehicle is landing by force and accepts no other command,
#: so no motion goal but landing can be reached any more.
POWER_FAULTS = ("battery_empty",)
#: A motor has seized: the vehicle cannot hold a hover (the simulator freezes it where it
#: is, which must not pass for hovering). Behaviors that move are caught by their
#: progress watch instead (WRONG_PROGRESS, with the fault in the event's detail).
MOTOR_FAULTS = ("stuck_motor",)
#: The position estimate is lost: no position goal can be flown to (the vehicle is
#: landing by its own failsafe). LAND does not list it: landing needs no position.
POSITION_FAULTS = ("position_lost",)
#: No progress for this long (s) is WRONG_PROGRESS, for every goal-seeking behavior.
PROGRESS_WINDOW = 5.0
#: A vehicle at or below this speed (m/s) counts as stopped.
STOPPED_SPEED = 0.1

_FLYING = parse_query("flying(self)")
_BATTERY_LOW = parse_query("battery_level(self, LOW)")
_BATTERY_CHARGE = parse_query("battery_charge(self, ?P)")
_POSITION = parse_query("position(self, (?X, ?Y, ?Z))")


def holds(beliefs: Beliefs, goals: tuple[Compound, ...]) -> bool:
    return next(beliefs.solve(goals), None) is not None


def is_flying(beliefs: Beliefs) -> bool:
    return holds(beliefs, _FLYING)


def altitude(beliefs: Beliefs) -> float | None:
    for bindings in beliefs.solve(_POSITION):
        z = bindings["Z"]
        return float(z) if isinstance(z, (int, float)) else None
    return None


def low_battery_reason(beliefs: Beliefs) -> str | None:
    """ "battery low (12 %)" when the battery belief says LOW, else None."""
    if not holds(beliefs, _BATTERY_LOW):
        return None
    for bindings in beliefs.solve(_BATTERY_CHARGE):
        return f"battery low ({bindings['P']} %)"
    return "battery low"


def must_be_flying(beliefs: Beliefs) -> Situation:
    return ALLOWED if is_flying(beliefs) else Situation(False, "not flying")


def visual_marker(marker: int) -> tuple[Compound, ...]:
    """The query `visual_marker(ID)`, ready for `holds`."""
    return (Compound("visual_marker", (marker,)),)


def fmt(point: Vec3) -> str:
    return "(" + ", ".join(f"{c:.2f}" for c in point) + ")"


def angle_error_degrees(target: float, actual: float) -> float:
    """Smallest absolute difference of two headings in radians, in degrees."""
    error = math.fmod(target - actual, 2.0 * math.pi)
    if error > math.pi:
        error -= 2.0 * math.pi
    elif error < -math.pi:
        error += 2.0 * math.pi
    return abs(math.degrees(error))


class ProgressWatch:
    """Tells when a remaining-distance measure has stopped shrinking.

    Progress means "closer than within the last window": `stalled` turns true once the
    measure has been watched for `window` seconds and is not at least `min_gain` below
    every value it had in the last `window` seconds (the one a window ago included).
    Comparing with the recent past, not with the best ever seen, is what lets a vehicle
    that overshot its goal make progress again: a real autopilot arriving at speed passes
    the goal, stops beyond it and creeps back, and creeping back is progress. A vehicle
    that is stuck, or swings back and forth without closing in (at the top of a swing it
    is no closer than a swing ago), is caught; so is creeping by less than `min_gain` per
    window, even if the estimate jitters.
    """

    __slots__ = ("_samples", "min_gain", "window")

    def __init__(self, min_gain: float, window: float = PROGRESS_WINDOW) -> None:
        self.min_gain = min_gain
        self.window = window
        self._samples: deque[tuple[float, float]] = deque()

    def stalled(self, now: float, remaining: float) -> bool:
        samples = self._samples
        samples.append((now, remaining))
        cutoff = now - self.window
        # Keep the newest sample at or before the cutoff: the value "a window ago".
        while len(samples) > 1 and samples[1][0] <= cutoff:
            samples.popleft()
        if samples[0][0] > cutoff:
            return False  # watched for less than a window yet
        return remaining > max(value for _, value in samples) - self.min_gain


class MotionBehavior(Behavior):
    """A behavior that commands motion: when it ends, the vehicle is left hovering.

    A behavior whose success leaves the vehicle doing exactly what was asked (holding the
    reached point, the new heading, the new velocity) returns `self.achieved(...)`, and
    then the command is left in place instead of being replaced by a hover.
    """

    _keep_command = False
    fails_on_faults = LINK_FAULTS + POWER_FAULTS + POSITION_FAULTS

    def achieved(self, detail: str = "") -> Finished:
        self._keep_command = True
        return Finished(EventCode.GOAL_ACHIEVED, detail)

    def on_stop(self) -> None:
        # The flag is per activation: clear it here, the one hook every activation reaches.
        keep, self._keep_command = self._keep_command, False
        if not keep:
            hover_if_flying(self)


def hover_if_flying(behavior: Behavior) -> None:
    if not behavior.vehicle.state().flying:
        return
    try:
        behavior.vehicle.hover()
    except VehicleCommandError as exc:
        # Reported, not raised: an on_stop error would replace the real outcome (say,
        # WRONG_PROGRESS from a stuck motor) with PROCESS_FAILURE.
        behavior.log(f"could not leave the vehicle hovering: {exc}", "WARN")
