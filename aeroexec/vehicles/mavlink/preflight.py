"""What fly checks on the autopilot before a mission may arm it.

aeroexec cannot protect a vehicle once it has exited (killed, a power cut, a link that
never came back within `--link-timeout`): then only the autopilot's own failsafes can.
So at connect `preflight` reads them with MAVLink's parameter protocol
(PARAM_REQUEST_READ, answered with PARAM_VALUE):

* `FS_GCS_ENABLE` (what ArduCopter does when the ground station's heartbeats stop; 0, its
  default, is nothing: a vehicle in GUIDED hovers until its battery is empty) and
  `FS_GCS_TIMEOUT` (after how many seconds);
* `BATT_FS_LOW_ACT`, `BATT_FS_CRT_ACT` (what it does on a low / critical battery).

A GCS failsafe that is off (or that the autopilot would not tell) is a `GcsFailsafeOff`
finding: `aeroexec fly` refuses to fly (before anything is armed) unless
`--allow-no-gcs-failsafe`. It also reports the pre-arm failures the autopilot states:
SYS_STATUS sensors present and enabled but not healthy (`PREARM_CHECK`: its pre-arm
checks fail), and the "PreArm:" STATUSTEXTs heard so far.
"""

from __future__ import annotations

from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from aeroexec.vehicles.mavlink.endpoint import MavlinkError
from aeroexec.vehicles.mavlink.vehicle import MavlinkVehicle

FAILSAFE_PARAMETERS = ("FS_GCS_ENABLE", "FS_GCS_TIMEOUT", "BATT_FS_LOW_ACT", "BATT_FS_CRT_ACT")
#: ArduCopter 4.5's FS_GCS_ENABLE values.
GCS_FAILSAFE_ACTIONS = {
    0: "off",
    1: "RTL",
    2: "continue an AUTO mission, else RTL",
    3: "SmartRTL or RTL",
    4: "SmartRTL or LAND",
    5: "LAND",
    6: "AUTO DO_LAND_START or RTL",
    7: "brake or LAND",
}
#: ArduCopter 4.5's BATT_FS_LOW_ACT / BATT_FS_CRT_ACT values.
BATTERY_FAILSAFE_ACTIONS = {
    0: "none",
    1: "LAND",
    2: "RTL",
    3: "SmartRTL or RTL",
    4: "SmartRTL or LAND",
    5: "terminate",
    6: "AUTO DO_LAND_START or RTL",
    7: "brake or LAND",
}
#: Seconds to wait for the parameters (and a first SYS_STATUS).
PARAMETER_TIMEOUT = 3.0


class GcsFailsafeOff(MavlinkError):
    """The autopilot would not act on its own when fly's heartbeats stop (exit 2)."""


@dataclass(frozen=True, slots=True)
class Preflight:
    #: The failsafe parameters as the autopilot gave them (missing: it did not answer).
    parameters: dict[str, float]
    #: Why the GCS failsafe cannot be counted on ("" when it is on).
    gcs_failsafe_off: str
    #: One line each: the failsafes, then each pre-arm failure the autopilot stated.
    lines: tuple[str, ...]
    #: The pre-arm failures alone (SYS_STATUS bits, "PreArm:" texts).
    prearm: tuple[str, ...]

    def metadata(self) -> str:
        """ "FS_GCS_ENABLE=5 FS_GCS_TIMEOUT=5 ..." (a recording's `failsafe_parameters`)."""
        return " ".join(f"{n}={v:g}" for n, v in self.parameters.items())


def _action(table: dict[int, str], value: float | None) -> str:
    if value is None:
        return "not reported"
    return table.get(int(value), f"action {value:g}")


def sensor_names(bits: int) -> list[str]:
    """MAV_SYS_STATUS_SENSOR bits as short names ("GPS", "PREARM_CHECK")."""
    names = []
    for value, entry in sorted(mavlink.enums["MAV_SYS_STATUS_SENSOR"].items()):
        if value & (value - 1) == 0 and bits & value:
            name = entry.name.removeprefix("MAV_SYS_STATUS_").removeprefix("SENSOR_")
            names.append(name)
    return names


def preflight(vehicle: MavlinkVehicle, timeout: float = PARAMETER_TIMEOUT) -> Preflight:
    """Read the failsafe parameters and the autopilot's health (see the module doc)."""
    params = vehicle.read_parameters(FAILSAFE_PARAMETERS, timeout, min_sys_status=1)
    gcs = params.get("FS_GCS_ENABLE")
    if gcs is None:
        off = (
            "the autopilot did not report FS_GCS_ENABLE (PARAM_REQUEST_READ unanswered "
            f"for {timeout:g} s): its GCS failsafe cannot be counted on"
        )
    elif int(gcs) == 0:
        off = (
            "the autopilot's GCS failsafe is off (FS_GCS_ENABLE=0): if fly stops or its "
            "link is lost for good, the vehicle hovers in GUIDED until its battery is "
            "empty; set FS_GCS_ENABLE=5 (land) or 1 (RTL) on the autopilot"
        )
    else:
        off = ""
    timeout_s = params.get("FS_GCS_TIMEOUT")
    after = f" after {timeout_s:g} s" if timeout_s is not None and gcs else ""
    lines = [
        f"preflight: GCS failsafe {_action(GCS_FAILSAFE_ACTIONS, gcs)}{after}; battery "
        f"failsafes low {_action(BATTERY_FAILSAFE_ACTIONS, params.get('BATT_FS_LOW_ACT'))}, "
        f"critical {_action(BATTERY_FAILSAFE_ACTIONS, params.get('BATT_FS_CRT_ACT'))}"
    ]
    prearm = []
    unhealthy = vehicle.telemetry.unhealthy_sensors()
    if unhealthy:
        prearm.append(f"SYS_STATUS unhealthy: {', '.join(sensor_names(unhealthy))}")
    seen: set[str] = set()
    for _, _, text in vehicle.texts:
        if text.startswith("PreArm:") and text not in seen:
            seen.add(text)
            prearm.append(f"autopilot: {text}")
    lines += [f"preflight: pre-arm failure: {p}" for p in prearm]
    return Preflight(params, off, tuple(lines), tuple(prearm))
