"""Keep the vehicle's beliefs in step with its state, touching as little as possible.

The executive calls `update_beliefs` after every vehicle step. Each change to the belief
store is published (and recorded), so a belief is only replaced when its *text* changes:
positions are rounded to centimetres and angles to degrees, which keeps a hovering
vehicle from producing a stream of identical-looking updates.

Beliefs maintained (Aerostack's always-present ones plus a few aeroexec adds):
`flight_state(self, FLYING|LANDED)`, `flying(self)` (only while flying),
`position(self, (X, Y, Z))`, `battery_level(self, HIGH|LOW)`, `battery_charge(self, P)`
(integer percent) and `yaw(self, DEG)` (integer degrees, counter-clockwise from +x).
Visual markers are not fed here: PAY_ATTENTION_TO_VISUAL_MARKERS adds those.
"""

from __future__ import annotations

import math

from aeroexec.executive.beliefs import Beliefs, Compound, Var
from aeroexec.vehicles.base import VehicleState

#: The vehicle fault of a lost position estimate (aeroexec/vehicles/faults.py).
POSITION_LOST = "position_lost"
#: Below this charge (percent) `battery_level(self, LOW)`.
LOW_BATTERY_PERCENT = 20

_FLYING = Compound("flying", ("self",))
_ANY_POSITION = Compound("position", ("self", Var("")))
_FLIGHT_STATES = {
    True: Compound("flight_state", ("self", "FLYING")),
    False: Compound("flight_state", ("self", "LANDED")),
}
_LEVELS = {
    True: Compound("battery_level", ("self", "LOW")),
    False: Compound("battery_level", ("self", "HIGH")),
}


def _cm(value: float) -> float:
    # `+ 0.0` turns -0.0 into 0.0, so a vehicle on the ground does not flip between the two.
    return round(value, 2) + 0.0


def battery_percent(charge: float) -> int:
    """Whole percent, rounded down (19.99 % is 19 %, consistent with LOW below 20 %)."""
    return max(0, min(100, math.floor(charge * 100.0 + 1e-9)))


def heading_degrees(yaw: float) -> int:
    """Yaw (radians) as integer degrees in (-180, 180]."""
    degrees = round(math.degrees(yaw))
    degrees = (degrees + 180) % 360 - 180
    return 180 if degrees == -180 else degrees


def update_beliefs(beliefs: Beliefs, state: VehicleState) -> int:
    """Bring the vehicle beliefs up to date; returns how many beliefs changed.

    Marker beliefs are not fed here: seeing markers is PAY_ATTENTION_TO_VISUAL_MARKERS'
    job (a mission that does not pay attention must not learn of them).
    """
    changes = 0
    changes += beliefs.add(_FLIGHT_STATES[state.flying])
    if state.flying:
        changes += beliefs.add(_FLYING)
    elif any(fact == _FLYING for fact in beliefs):
        changes += beliefs.remove(_FLYING)
    # A value that is not a number (a vehicle's bad estimate) leaves its belief as it was:
    # believing "nan" would be wrong, and rounding it would raise.
    x, y, z = state.position
    if state.fault == POSITION_LOST:
        # No estimate, no belief: a mission that asks where it is learns that it does not
        # know (Appendix C's "Position unknown, landing..." path), not a stale answer.
        changes += beliefs.remove(_ANY_POSITION)
    elif math.isfinite(x) and math.isfinite(y) and math.isfinite(z):
        changes += beliefs.add(Compound("position", ("self", (_cm(x), _cm(y), _cm(z)))))
    if math.isfinite(state.battery):
        percent = battery_percent(state.battery)
        changes += beliefs.add(_LEVELS[percent < LOW_BATTERY_PERCENT])
        changes += beliefs.add(Compound("battery_charge", ("self", percent)))
    if math.isfinite(state.yaw):
        changes += beliefs.add(Compound("yaw", ("self", heading_degrees(state.yaw))))
    return changes
