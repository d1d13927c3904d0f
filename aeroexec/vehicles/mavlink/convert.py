"""Frames, headings and ArduCopter modes: the arithmetic between aeroexec and MAVLink.

aeroexec's `Vehicle` protocol is local ENU (x east, y north, z up; yaw counter-clockwise
from +x, radians). MAVLink's `MAV_FRAME_LOCAL_NED` is x north, y east, z down, and its
yaw/heading is clockwise from north. Both frames share the origin (the EKF origin, which
ArduPilot puts at home), so converting is a swap of the horizontal axes and a sign flip
of the vertical one; a heading `h` (NED) and a yaw `psi` (ENU) satisfy `h = pi/2 - psi`.
"""

from __future__ import annotations

import math

Vec3 = tuple[float, float, float]

#: ArduCopter `custom_mode` numbers (ArduPilot's `Mode::Number`; mavutil.mode_mapping_acm).
COPTER_MODES: dict[int, str] = {
    0: "STABILIZE",
    1: "ACRO",
    2: "ALT_HOLD",
    3: "AUTO",
    4: "GUIDED",
    5: "LOITER",
    6: "RTL",
    7: "CIRCLE",
    9: "LAND",
    11: "DRIFT",
    13: "SPORT",
    14: "FLIP",
    15: "AUTOTUNE",
    16: "POSHOLD",
    17: "BRAKE",
    18: "THROW",
    20: "GUIDED_NOGPS",
    21: "SMART_RTL",
}
GUIDED = 4
RTL = 6
LAND = 9
BRAKE = 17
STABILIZE = 0


def mode_name(custom_mode: int) -> str:
    return COPTER_MODES.get(custom_mode, f"MODE_{custom_mode}")


def wrap_pi(angle: float) -> float:
    """Angle in radians into (-pi, pi]."""
    wrapped = math.fmod(angle + math.pi, 2.0 * math.pi)
    if wrapped <= 0.0:
        wrapped += 2.0 * math.pi
    return wrapped - math.pi


def enu_to_ned(v: Vec3) -> Vec3:
    """A position or velocity from ENU (east, north, up) to NED (north, east, down)."""
    east, north, up = v
    return (north, east, -up if up != 0.0 else 0.0)


def ned_to_enu(v: Vec3) -> Vec3:
    """A position or velocity from NED (north, east, down) to ENU (east, north, up)."""
    north, east, down = v
    return (east, north, -down if down != 0.0 else 0.0)


def yaw_enu_to_ned(yaw: float) -> float:
    """ENU yaw (CCW from east, rad) -> NED yaw (CW from north, rad), in (-pi, pi]."""
    return wrap_pi(math.pi / 2.0 - yaw)


def yaw_ned_to_enu(yaw: float) -> float:
    """NED yaw (CW from north, rad) -> ENU yaw (CCW from east, rad), in (-pi, pi]."""
    return wrap_pi(math.pi / 2.0 - yaw)


def heading_degrees(yaw_enu: float) -> float:
    """ENU yaw (rad) -> compass heading in degrees [0, 360), as MAV_CMD_CONDITION_YAW takes."""
    heading = math.degrees(math.pi / 2.0 - yaw_enu) % 360.0
    return 0.0 if heading >= 360.0 else heading
