"""What the autopilot tells us, folded into aeroexec's `VehicleState`.

`Telemetry.apply(msg)` is the only place a received message changes what the executive
believes about the vehicle (and so its beliefs: `flying(self)`, `position(self, ...)`,
`battery_level(self, ...)`): HEARTBEAT (armed, mode), LOCAL_POSITION_NED (position and
velocity), ATTITUDE (yaw), SYS_STATUS (battery), EXTENDED_SYS_STATE (landed state).
Frames are converted here, once (see `aeroexec.vehicles.mavlink.convert`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from aeroexec.vehicles.base import VehicleState
from aeroexec.vehicles.mavlink.codec import MAVLinkMessage
from aeroexec.vehicles.mavlink.convert import Vec3, mode_name, ned_to_enu, yaw_ned_to_enu

#: Without EXTENDED_SYS_STATE, an armed vehicle above this height (m) counts as flying.
FLYING_ALTITUDE = 0.3
_AIRBORNE_STATES = (
    mavlink.MAV_LANDED_STATE_IN_AIR,
    mavlink.MAV_LANDED_STATE_TAKEOFF,
    mavlink.MAV_LANDED_STATE_LANDING,
)
#: EXTENDED_SYS_STATE's landed states, as an ending says what the autopilot said.
_LANDED_STATE_NAMES = {
    mavlink.MAV_LANDED_STATE_UNDEFINED: "no landed state",
    mavlink.MAV_LANDED_STATE_ON_GROUND: "on the ground",
    mavlink.MAV_LANDED_STATE_IN_AIR: "in the air",
    mavlink.MAV_LANDED_STATE_TAKEOFF: "taking off",
    mavlink.MAV_LANDED_STATE_LANDING: "landing",
}


#: The messages `Telemetry.apply` folds into the state.
USED = frozenset(
    {"HEARTBEAT", "LOCAL_POSITION_NED", "ATTITUDE", "SYS_STATUS", "EXTENDED_SYS_STATE"}
)


def unbelievable(msg: MAVLinkMessage) -> tuple[str, str] | None:
    """("non_finite", "LOCAL_POSITION_NED: x=nan") when a message that would feed the
    state carries a NaN or an infinity in any field, else None. Other messages may carry
    NaN on purpose (MAVLink's "no value"), so they are not judged."""
    kind = msg.get_type()
    if kind not in USED:
        return None
    bad = [
        f"{name}={value}"
        for name in msg.get_fieldnames()
        if isinstance(value := getattr(msg, name), float) and not math.isfinite(value)
    ]
    return ("non_finite", f"{kind}: {', '.join(bad)}") if bad else None


def is_autopilot_heartbeat(msg: MAVLinkMessage) -> bool:
    """A HEARTBEAT from a flight controller (not a GCS, gimbal, camera or radio)."""
    return (
        msg.get_type() == "HEARTBEAT"
        and msg.autopilot != mavlink.MAV_AUTOPILOT_INVALID
        and msg.type != mavlink.MAV_TYPE_GCS
    )


@dataclass
class Telemetry:
    """The latest values, in MAVLink's own frame (NED), plus what was heard at all."""

    position_ned: Vec3 = (0.0, 0.0, 0.0)
    velocity_ned: Vec3 = (0.0, 0.0, 0.0)
    yaw_ned: float = 0.0
    battery: float = 1.0
    armed: bool = False
    custom_mode: int = -1
    system_status: int = 0
    landed_state: int = mavlink.MAV_LANDED_STATE_UNDEFINED
    heartbeats: int = 0
    positions: int = 0
    #: As the autopilot's last HEARTBEAT said (never assumed from a command we sent):
    #: what an ending is confirmed by.
    heard_armed: bool = False
    heard_mode: int = -1
    #: SYS_STATUS's sensor bit fields (MAV_SYS_STATUS_SENSOR), and how many were heard.
    sensors_present: int = 0
    sensors_enabled: int = 0
    sensors_health: int = 0
    sys_statuses: int = 0

    @property
    def mode(self) -> str:
        return "UNKNOWN" if self.custom_mode < 0 else mode_name(self.custom_mode)

    @property
    def flying(self) -> bool:
        if self.landed_state in _AIRBORNE_STATES:
            return True
        if self.landed_state == mavlink.MAV_LANDED_STATE_ON_GROUND:
            return False
        return self.armed and -self.position_ned[2] > FLYING_ALTITUDE

    def apply(self, msg: MAVLinkMessage) -> bool:
        """Fold one message in; True if it changed what telemetry holds."""
        kind = msg.get_type()
        if kind == "HEARTBEAT":
            if not is_autopilot_heartbeat(msg):
                return False
            self.heartbeats += 1
            self.armed = bool(msg.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED)
            self.heard_armed = self.armed
            if msg.base_mode & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
                self.custom_mode = int(msg.custom_mode)
                self.heard_mode = self.custom_mode
            self.system_status = int(msg.system_status)
            return True
        if kind == "LOCAL_POSITION_NED":
            self.positions += 1
            self.position_ned = (float(msg.x), float(msg.y), float(msg.z))
            self.velocity_ned = (float(msg.vx), float(msg.vy), float(msg.vz))
            return True
        if kind == "ATTITUDE":
            self.yaw_ned = float(msg.yaw)
            return True
        if kind == "SYS_STATUS":
            self.sys_statuses += 1
            self.sensors_present = int(msg.onboard_control_sensors_present)
            self.sensors_enabled = int(msg.onboard_control_sensors_enabled)
            self.sensors_health = int(msg.onboard_control_sensors_health)
            if msg.battery_remaining >= 0:  # -1: the autopilot does not know
                self.battery = min(1.0, msg.battery_remaining / 100.0)
            return True
        if kind == "EXTENDED_SYS_STATE":
            self.landed_state = int(msg.landed_state)
            return True
        return False

    @property
    def heard_mode_name(self) -> str:
        return "no mode" if self.heard_mode < 0 else mode_name(self.heard_mode)

    @property
    def landed_state_name(self) -> str:
        """EXTENDED_SYS_STATE's landed state as the autopilot last said it: "landing"."""
        return _LANDED_STATE_NAMES.get(self.landed_state, f"landed state {self.landed_state}")

    @property
    def speed(self) -> float:
        """m/s, from the last LOCAL_POSITION_NED."""
        return math.hypot(*self.velocity_ned)

    def unhealthy_sensors(self) -> int:
        """SYS_STATUS bits present and enabled but not healthy (0 before a SYS_STATUS)."""
        return self.sensors_present & self.sensors_enabled & ~self.sensors_health

    def vehicle_state(self, fault: str = "") -> VehicleState:
        return VehicleState(
            position=ned_to_enu(self.position_ned),
            velocity=ned_to_enu(self.velocity_ned),
            yaw=yaw_ned_to_enu(self.yaw_ned),
            battery=self.battery,
            flying=self.flying,
            armed=self.armed,
            fault=fault,
        )
