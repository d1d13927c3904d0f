"""How long a flight between two points takes at least, at a vehicle's limits.

The limits are the world's (`aeroexec.vehicles.world.Limits`: horizontal and vertical
speed, acceleration), the same the simulator enforces. The bound starts and ends at
rest: accelerate, cruise, brake — so a behavior whose timeout is below it cannot reach
its target in time, whatever the controller does.
"""

from __future__ import annotations

import math

from aeroexec.vehicles.base import Vec3
from aeroexec.vehicles.world import Limits


def _leg(distance: float, speed: float, acceleration: float) -> float:
    if distance <= 0:
        return 0.0
    if distance >= speed * speed / acceleration:
        return distance / speed + speed / acceleration
    return 2.0 * math.sqrt(distance / acceleration)


def travel_time(horizontal: float, vertical: float, limits: Limits) -> float:
    """Seconds at least to move `horizontal` and `vertical` metres, from rest to rest."""
    return max(
        _leg(horizontal, limits.horizontal_speed, limits.acceleration),
        _leg(vertical, limits.vertical_speed, limits.acceleration),
    )


def travel_between(start: Vec3, end: Vec3, limits: Limits) -> tuple[float, float, float]:
    """(horizontal metres, vertical metres, seconds at least) from `start` to `end`."""
    horizontal = math.hypot(end[0] - start[0], end[1] - start[1])
    vertical = abs(end[2] - start[2])
    return horizontal, vertical, travel_time(horizontal, vertical, limits)


def describe_limits(limits: Limits) -> str:
    return (
        f"{limits.horizontal_speed:g} m/s horizontal, {limits.vertical_speed:g} m/s "
        f"vertical, {limits.acceleration:g} m/s²"
    )
