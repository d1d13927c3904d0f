"""`MavSim`: the simulated vehicle (`SimVehicle`) behind an ArduCopter-like MAVLink face.

It speaks the part of ArduCopter's protocol that aeroexec's GUIDED-mode backend uses, over
any link aeroexec speaks (UDP, TCP either side, a serial port), in real time: HEARTBEAT
at 1 Hz, LOCAL_POSITION_NED and ATTITUDE at 10 Hz, SYS_STATUS and EXTENDED_SYS_STATE at
2 Hz (EXTENDED_SYS_STATE also when the landed state changes), a COMMAND_ACK for every
COMMAND_LONG and SET_MODE.

Where it matters for tests it behaves as ArduCopter 4.5 SITL was measured to:

* the EKF is not ready for `ekf_delay` vehicle seconds after start (SITL: ~40 s): no
  LOCAL_POSITION_NED yet, and arming is refused (FAILED, with an "Arm:" STATUSTEXT);
* the answers: FAILED for take-off while disarmed, not in GUIDED, already flying or to
  a non-positive altitude, for arming in flight and disarming in the air, for unknown
  modes; DENIED for a message interval of an unknown message; UNSUPPORTED for unknown
  commands; CONDITION_YAW is ACCEPTED in any mode, on the ground too (and does nothing
  there);
* a position setpoint overshoots: the vehicle passes the goal, stops `overshoot` metres
  beyond it and creeps back at `creep_speed` (SITL: 10-20 cm past after a few metres at
  ~3 m/s, back at 3-8 cm/s);
* RTL climbs to `rtl_altitude` (ArduCopter's RTL_ALT, 15 m), flies home (where it armed)
  and lands.

Setpoints (SET_POSITION_TARGET_LOCAL_NED) are obeyed only in GUIDED while flying, as
ArduCopter does; a velocity setpoint lapses after 3 s without a new one.

Parameters: PARAM_REQUEST_READ (by name or index) and PARAM_SET are answered with
PARAM_VALUE, as ArduCopter does, for the few parameters mavsim acts on or reports
(`PARAMETERS`: the GCS and battery failsafes, `BATT_ARM_VOLT`); a name it does not
have gets no answer (ArduCopter's silence), a PARAM_SET to it is ignored. One
difference: `FS_GCS_ENABLE` defaults to 1 here (ArduCopter: 0), so a plain mavsim
passes `aeroexec fly`'s failsafe preflight; `--param FS_GCS_ENABLE=0` is ArduCopter's
default. `BATT_ARM_VOLT` above the battery's voltage (12.6 V full, 10.5 V empty)
refuses arming as ArduCopter does: FAILED, after the STATUSTEXT
"Arm: Battery 1 below minimum arming voltage".

Fault injection for tests: heartbeats dropped for a while after take-off, commands
refused by name (TEMPORARILY_REJECTED), every Nth outgoing packet corrupted; and a
`speed_factor` that runs the vehicle model faster than the wall clock (positions,
velocities and rates reported are then those of the sped-up vehicle, so the ground
station sees a consistent, just faster, aircraft).
"""

from __future__ import annotations

import contextlib
import json
import math
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from aeroexec.vehicles.base import Vec3, VehicleCommandError
from aeroexec.vehicles.mavlink.codec import (
    MAVLinkMessage,
    command_name,
    command_number,
    result_name,
)
from aeroexec.vehicles.mavlink.convert import (
    COPTER_MODES,
    GUIDED,
    LAND,
    RTL,
    STABILIZE,
    enu_to_ned,
    ned_to_enu,
    wrap_pi,
    yaw_enu_to_ned,
    yaw_ned_to_enu,
)
from aeroexec.vehicles.mavlink.endpoint import DEFAULT_BAUD, DEFAULT_VEHICLE_URL, parse_endpoint
from aeroexec.vehicles.mavlink.link import Link

#: Modes mavsim can be put in; in the air all but LAND and RTL brake and hold.
SUPPORTED_MODES = (STABILIZE, GUIDED, 5, RTL, LAND, 16, 17)  # + LOITER, POSHOLD, BRAKE
VELOCITY_TIMEOUT = 3.0  # s: ArduCopter's GUIDED velocity-setpoint timeout
FORCE_DISARM = 21196.0  # param2 magic of MAV_CMD_COMPONENT_ARM_DISARM
#: Default telemetry rates (Hz) by message id.
DEFAULT_RATES: dict[int, float] = {
    mavlink.MAVLINK_MSG_ID_HEARTBEAT: 1.0,
    mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED: 10.0,
    mavlink.MAVLINK_MSG_ID_ATTITUDE: 10.0,
    mavlink.MAVLINK_MSG_ID_SYS_STATUS: 2.0,
    mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: 2.0,
}
LOOP_PERIOD = 0.005  # s: how often the loop wakes at most
#: Within this distance (m) of an overshoot point or an RTL stage's target, it counts as
#: reached.
REACHED = 0.02
#: Vehicle seconds between two reports of the failing pre-arm checks (ArduCopter: 30).
PREARM_REPORT_PERIOD = 30.0
#: SYS_STATUS sensor bits mavsim reports present, enabled and (but for PREARM_CHECK when
#: a pre-arm check fails) healthy.
SENSORS = (
    mavlink.MAV_SYS_STATUS_SENSOR_3D_GYRO
    | mavlink.MAV_SYS_STATUS_SENSOR_3D_ACCEL
    | mavlink.MAV_SYS_STATUS_SENSOR_GPS
    | mavlink.MAV_SYS_STATUS_SENSOR_BATTERY
    | mavlink.MAV_SYS_STATUS_PREARM_CHECK
)
#: The parameters mavsim answers for, with their defaults (ArduCopter 4.5's, except
#: FS_GCS_ENABLE: see the module docstring). MAV_PARAM_TYPE_REAL32 for all.
PARAMETERS: dict[str, float] = {
    "FS_GCS_ENABLE": 1.0,
    "FS_GCS_TIMEOUT": 5.0,
    "BATT_FS_LOW_ACT": 0.0,
    "BATT_FS_CRT_ACT": 0.0,
    "BATT_LOW_VOLT": 10.5,
    "BATT_CRT_VOLT": 0.0,
    "BATT_ARM_VOLT": 0.0,
}


@dataclass(frozen=True, slots=True)
class MavSimConfig:
    url: str = DEFAULT_VEHICLE_URL
    allow_remote: bool = False
    signing_key: bytes | None = None
    system: int = 1
    component: int = 1
    #: Vehicle seconds per wall-clock second.
    speed_factor: float = 1.0
    #: HEARTBEAT rate (ArduPilot: 1 Hz). Faster makes mode and arming changes visible
    #: sooner, which shortens tests.
    heartbeat_hz: float = 1.0
    #: Wall-clock seconds to run; None: until stopped.
    duration: float | None = None
    #: Heartbeats stop this many seconds after the first accepted take-off ...
    drop_heartbeats_at: float | None = None
    #: ... for this many seconds.
    drop_for: float = 5.0
    #: Commands answered TEMPORARILY_REJECTED (MAV_CMD numbers).
    refuse: tuple[int, ...] = ()
    #: Corrupt (flip a CRC byte of) every Nth packet sent; 0: never.
    corrupt_every: int = 0
    world: str | Path | None = None
    #: Vehicle seconds from start until the EKF has a position (SITL: ~40).
    ekf_delay: float = 2.0
    #: Metres a position setpoint is overshot before the vehicle creeps back (0: none).
    overshoot: float = 0.15
    #: m/s (vehicle time) of the creep back from an overshoot.
    creep_speed: float = 0.05
    #: RTL's return altitude (ArduCopter's RTL_ALT), metres.
    rtl_altitude: float = 15.0
    #: Serial devices given without `,BAUD`.
    baud: int = DEFAULT_BAUD
    #: Parameter values other than `PARAMETERS`' defaults: (name, value) pairs.
    params: tuple[tuple[str, float], ...] = ()

    def __post_init__(self) -> None:
        for name, value in self.params:
            if name not in PARAMETERS:
                raise ValueError(
                    f"--param {name}: not one of mavsim's parameters ({', '.join(PARAMETERS)})"
                )
            if not math.isfinite(value):
                raise ValueError(f"--param {name}: not a number: {value}")
        if not (math.isfinite(self.speed_factor) and self.speed_factor > 0):
            raise ValueError(f"speed factor must be positive, got {self.speed_factor}")
        if not (math.isfinite(self.heartbeat_hz) and self.heartbeat_hz > 0):
            raise ValueError(f"heartbeat rate must be positive, got {self.heartbeat_hz}")
        if self.duration is not None and not self.duration > 0:
            raise ValueError(f"duration must be positive, got {self.duration}")
        if self.corrupt_every < 0:
            raise ValueError(f"corrupt-every must be >= 0, got {self.corrupt_every}")
        if self.drop_for < 0:
            raise ValueError(f"drop-for must be >= 0, got {self.drop_for}")
        for name in ("ekf_delay", "overshoot", "rtl_altitude"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name.replace('_', '-')} must be >= 0, got {value}")
        if not (math.isfinite(self.creep_speed) and self.creep_speed > 0):
            raise ValueError(f"creep-speed must be positive, got {self.creep_speed}")


def parse_params(texts: list[str] | tuple[str, ...]) -> tuple[tuple[str, float], ...]:
    """`--param NAME=VALUE` values -> (name, value) pairs; `ValueError` for a bad one."""
    out: list[tuple[str, float]] = []
    for text in texts:
        name, sep, value = text.partition("=")
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not sep or not name.strip() or not math.isfinite(number):
            raise ValueError(f"--param {text!r}: expected NAME=VALUE (FS_GCS_ENABLE=0)")
        out.append((name.strip().upper(), number))
    return tuple(out)


def refuse_numbers(names: list[str] | tuple[str, ...]) -> tuple[int, ...]:
    """`--refuse` values (MAV_CMD_NAV_TAKEOFF, nav_takeoff, 22) -> command numbers."""
    out: list[int] = []
    for name in names:
        out.append(int(name) if name.strip().isdigit() else command_number(name))
    return tuple(out)


@dataclass
class _Counters:
    dropped_heartbeats: int = 0
    ignored_setpoints: int = 0
    commands: list[dict[str, Any]] = field(default_factory=list)
    setpoints: Counter[str] = field(default_factory=Counter)


class MavSim:
    def __init__(
        self, config: MavSimConfig | None = None, *, clock: Callable[[], float] = time.monotonic
    ) -> None:
        from aeroexec.vehicles.sim import SimVehicle
        from aeroexec.vehicles.world import default_world, load_world

        self.config = config if config is not None else MavSimConfig()
        self.endpoint = parse_endpoint(
            self.config.url, allow_remote=self.config.allow_remote, baud=self.config.baud
        )
        world = load_world(self.config.world) if self.config.world else default_world()
        self.sim = SimVehicle(world)
        self.link = Link(
            self.endpoint,
            system=self.config.system,
            component=self.config.component,
            key=self.config.signing_key,
            corrupt_every=self.config.corrupt_every,
        )
        self._clock = clock
        self.started = clock()
        self._last_step = self.started
        self.mode = STABILIZE
        self.armed = False
        self.counters = _Counters()
        self._rates = dict(DEFAULT_RATES)
        self._rates[mavlink.MAVLINK_MSG_ID_HEARTBEAT] = self.config.heartbeat_hz
        self._next_due: dict[int, float] = dict.fromkeys(self._rates, self.started)
        self._landed_state = mavlink.MAV_LANDED_STATE_ON_GROUND
        self._take_off_at: float | None = None
        self._launched = False
        self._velocity_at: float | None = None
        self._last_result: tuple[int, int] | None = None  # (command, result)
        self.gcs: tuple[int, int] | None = None
        #: A position setpoint being overshot: (goal, overshoot point, creep start time
        #: in vehicle seconds or None while still flying out).
        self._overshoot: tuple[Vec3, Vec3, float | None] | None = None
        #: RTL: "climb", "return" or "land"; None outside RTL.
        self._rtl_stage: str | None = None
        self._home: Vec3 = self.sim.state().position
        self._ekf_announced = False
        self.params: dict[str, float] = {**PARAMETERS, **dict(self.config.params)}
        # The first report when the EKF is ready (mavsim's boot messages end there).
        self._next_prearm_report = self.config.ekf_delay

    # -- running -------------------------------------------------------------------------
    @property
    def elapsed(self) -> float:
        return self._clock() - self.started

    def run(self, should_stop: Callable[[], bool] = lambda: False) -> None:
        """Serve until `duration` passed or `should_stop()` is true."""
        while not should_stop():
            if self.config.duration is not None and self.elapsed >= self.config.duration:
                break
            self.tick(LOOP_PERIOD)
        self.tick(0.0)  # whatever arrived meanwhile is counted too

    def tick(self, wait: float) -> None:
        """Receive (waiting at most `wait` s), advance the model, send what is due."""
        for item in self.link.poll(wait):
            self._receive(item.msg, item.address)
        now = self._clock()
        dt = now - self._last_step
        if dt > 0:
            self._last_step = now
            self._advance(dt)
        self._telemetry(now)

    def close(self) -> None:
        self.link.close()

    # -- the model -----------------------------------------------------------------------
    @property
    def flying(self) -> bool:
        return self.sim.state().flying

    @property
    def in_flight(self) -> bool:
        """Flying, or launched and not yet back on the ground (ArduCopter's
        `!land_complete`): what take-off and disarming are refused in."""
        return self.flying or self._launched

    def _advance(self, dt: float) -> None:
        was_armed = self.sim.state().armed
        self.sim.step(dt * self.config.speed_factor)
        state = self.sim.state()
        if was_armed and not state.armed:
            self.armed = False  # touched down: ArduCopter disarms after landing
            self._launched = False
        if (
            self._velocity_at is not None
            and self._clock() - self._velocity_at > VELOCITY_TIMEOUT
            and self.flying
        ):
            self._velocity_at = None
            self.sim.hover()
        if self._overshoot is not None:
            self._follow_overshoot()
        if self._rtl_stage is not None:
            self._follow_rtl()
        if self.ekf_ready and not self._ekf_announced:
            self._ekf_announced = True
            self._statustext(mavlink.MAV_SEVERITY_INFO, "EKF3 IMU0 is using GPS")
        if not self.armed and self.sim.time >= self._next_prearm_report:
            # ArduCopter repeats its failing pre-arm checks every 30 s while disarmed.
            self._next_prearm_report = self.sim.time + PREARM_REPORT_PERIOD
            for failure in self._prearm_failures():
                self._statustext(mavlink.MAV_SEVERITY_CRITICAL, f"PreArm: {failure}")
        landed = self._landed()
        if landed != self._landed_state:
            self._landed_state = landed
            self._send_extended_sys_state()

    @property
    def ekf_ready(self) -> bool:
        """The EKF has a position (SITL: GPS in use, ~40 s after boot)."""
        return self.sim.time >= self.config.ekf_delay

    def _follow_overshoot(self) -> None:
        goal, beyond, creep_from = self._overshoot  # type: ignore[misc]
        now = self.sim.time
        if creep_from is None:
            if math.dist(self.sim.state().position, beyond) <= REACHED:
                self._overshoot = (goal, beyond, now)
            return
        gone = self.config.creep_speed * (now - creep_from)
        span = math.dist(goal, beyond)
        if gone >= span:
            self._overshoot = None
            self._sim_command(self.sim.go_to, *goal)
            return
        f = gone / span
        self._sim_command(
            self.sim.go_to, *(b + (g - b) * f for g, b in zip(goal, beyond, strict=True))
        )

    def _follow_rtl(self) -> None:
        x, y, z = self.sim.state().position
        hx, hy, _ = self._home
        if not self.flying:
            self._rtl_stage = None
            return
        if self._rtl_stage == "climb":
            target = max(z, self.config.rtl_altitude)
            if abs(z - target) <= REACHED:
                self._rtl_stage = "return"
                self._sim_command(self.sim.go_to, hx, hy, z)
            else:
                self._sim_command(self.sim.go_to, x, y, target)
        elif self._rtl_stage == "return" and math.hypot(x - hx, y - hy) <= REACHED:
            self._rtl_stage = "land"
            self._sim_command(self.sim.land)

    def _sim_command(self, command: Callable[..., None], *args: float) -> None:
        # The model may refuse (an empty battery): it then does what it must instead.
        with contextlib.suppress(VehicleCommandError):
            command(*args)

    def _landed(self) -> int:
        if not self.flying:
            return mavlink.MAV_LANDED_STATE_ON_GROUND
        if self.mode == LAND or self._rtl_stage == "land":
            return mavlink.MAV_LANDED_STATE_LANDING
        return mavlink.MAV_LANDED_STATE_IN_AIR

    # -- telemetry -----------------------------------------------------------------------
    def _telemetry(self, now: float) -> None:
        for message_id, rate in self._rates.items():
            if rate <= 0 or now < self._next_due[message_id]:
                continue
            self._next_due[message_id] = max(self._next_due[message_id] + 1.0 / rate, now)
            self._send_stream(message_id)

    def _send_stream(self, message_id: int) -> None:
        if message_id == mavlink.MAVLINK_MSG_ID_HEARTBEAT:
            self._send_heartbeat()
        elif message_id == mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED:
            if not self.ekf_ready:
                return  # no position estimate yet: ArduPilot sends none
            state = self.sim.state()
            k = self.config.speed_factor
            x, y, z = enu_to_ned(state.position)
            vx, vy, vz = enu_to_ned(state.velocity)
            self._send(
                mavlink.MAVLink_local_position_ned_message(
                    self._boot_ms(), x, y, z, vx * k, vy * k, vz * k
                )
            )
        elif message_id == mavlink.MAVLINK_MSG_ID_ATTITUDE:
            state = self.sim.state()
            self._send(
                mavlink.MAVLink_attitude_message(
                    self._boot_ms(), 0.0, 0.0, yaw_enu_to_ned(state.yaw), 0.0, 0.0, 0.0
                )
            )
        elif message_id == mavlink.MAVLINK_MSG_ID_SYS_STATUS:
            battery = self.sim.state().battery
            health = SENSORS
            if self._prearm_failures():
                health &= ~mavlink.MAV_SYS_STATUS_PREARM_CHECK
            self._send(
                mavlink.MAVLink_sys_status_message(
                    SENSORS,
                    SENSORS,
                    health,
                    0,
                    int(1000 * self.battery_voltage),
                    -1,
                    round(battery * 100),
                    0,
                    0,
                    0,
                    0,
                    0,
                    0,
                )
            )
        elif message_id == mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE:
            self._send_extended_sys_state()

    def _send_heartbeat(self) -> None:
        at = self.config.drop_heartbeats_at
        if at is not None and self._take_off_at is not None:
            since = self._clock() - self._take_off_at
            if at <= since < at + self.config.drop_for:
                self.counters.dropped_heartbeats += 1
                return
        base = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | mavlink.MAV_MODE_FLAG_STABILIZE_ENABLED
        if self.mode == GUIDED:
            base |= mavlink.MAV_MODE_FLAG_GUIDED_ENABLED
        if self.armed:
            base |= mavlink.MAV_MODE_FLAG_SAFETY_ARMED
        status = mavlink.MAV_STATE_ACTIVE if self.armed else mavlink.MAV_STATE_STANDBY
        self._send(
            mavlink.MAVLink_heartbeat_message(
                mavlink.MAV_TYPE_QUADROTOR,
                mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
                base,
                self.mode,
                status,
                3,
            )
        )

    def _send_extended_sys_state(self) -> None:
        self._send(
            mavlink.MAVLink_extended_sys_state_message(
                mavlink.MAV_VTOL_STATE_UNDEFINED, self._landed_state
            )
        )

    def _statustext(self, severity: int, text: str) -> None:
        self._send(mavlink.MAVLink_statustext_message(severity, text.encode("ascii")[:50]))

    def _send(self, msg: MAVLinkMessage) -> None:
        self.link.send(msg)

    def _boot_ms(self) -> int:
        return int(self.elapsed * 1000) & 0xFFFFFFFF

    # -- receiving -----------------------------------------------------------------------
    def _receive(self, msg: MAVLinkMessage, address: tuple[str, int]) -> None:
        kind = msg.get_type()
        if kind == "HEARTBEAT":
            if msg.type == mavlink.MAV_TYPE_GCS and self.gcs is None:
                self.gcs = (msg.get_srcSystem(), msg.get_srcComponent())
                self.link.lock(address)
            return
        if getattr(msg, "target_system", 0) not in (0, self.config.system):
            return  # for another vehicle
        if kind == "COMMAND_LONG":
            self._command_long(msg)
        elif kind == "SET_MODE":
            self._ack(msg, mavlink.MAVLINK_MSG_ID_SET_MODE, self._set_mode_message(msg))
        elif kind == "SET_POSITION_TARGET_LOCAL_NED":
            self._setpoint(msg)
        elif kind == "PARAM_REQUEST_READ":
            self._param_read(msg)
        elif kind == "PARAM_SET":
            self._param_set(msg)

    # -- parameters ----------------------------------------------------------------------
    def _param_read(self, msg: MAVLinkMessage) -> None:
        names = list(self.params)
        if msg.param_index >= 0:
            if msg.param_index < len(names):
                self._send_param(names[msg.param_index])
            return
        name = _param_name(msg.param_id)
        if name in self.params:
            self._send_param(name)

    def _param_set(self, msg: MAVLinkMessage) -> None:
        name = _param_name(msg.param_id)
        if name not in self.params or not math.isfinite(msg.param_value):
            return  # ArduCopter ignores a parameter it does not have
        self.params[name] = float(msg.param_value)
        self._send_param(name)

    def _send_param(self, name: str) -> None:
        names = list(self.params)
        self._send(
            mavlink.MAVLink_param_value_message(
                name.encode("ascii"),
                self.params[name],
                mavlink.MAV_PARAM_TYPE_REAL32,
                len(names),
                names.index(name),
            )
        )

    def _prearm_failures(self) -> list[str]:
        """ArduCopter's wording for each pre-arm check that fails now."""
        failures = []
        if not self.ekf_ready:
            failures.append("Need Position Estimate")
        if self.battery_voltage < self.params["BATT_ARM_VOLT"]:
            failures.append("Battery 1 below minimum arming voltage")
        return failures

    @property
    def battery_voltage(self) -> float:
        """Volts: 12.6 full, 10.5 empty (a 3S pack), as SYS_STATUS reports it."""
        return 10.5 + 2.1 * self.sim.state().battery

    def _ack(self, msg: MAVLinkMessage, command: int, result: int) -> None:
        self.counters.commands.append(
            {
                "t": round(self.elapsed, 3),
                "command": command_name(command),
                "result": result_name(result),
            }
        )
        self._send(
            mavlink.MAVLink_command_ack_message(
                command, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent()
            )
        )

    def _command_long(self, msg: MAVLinkMessage) -> None:
        command = int(msg.command)
        if (
            msg.confirmation > 0
            and self._last_result is not None
            and self._last_result[0] == command
        ):
            # A retransmission of what we just answered (our ack was lost): same answer,
            # without doing it twice.
            self._ack(msg, command, self._last_result[1])
            return
        if command in self.config.refuse:
            result = mavlink.MAV_RESULT_TEMPORARILY_REJECTED
        else:
            result = self._execute(command, msg)
        self._last_result = (command, result)
        self._ack(msg, command, result)

    def _execute(self, command: int, msg: MAVLinkMessage) -> int:
        ok, failed = mavlink.MAV_RESULT_ACCEPTED, mavlink.MAV_RESULT_FAILED
        if command == mavlink.MAV_CMD_DO_SET_MODE:
            if not int(msg.param1) & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
                return failed
            return self._enter_mode(int(msg.param2))
        if command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM:
            if msg.param1 >= 0.5:
                if self.armed:
                    return ok
                if not self.ekf_ready:
                    self._statustext(mavlink.MAV_SEVERITY_CRITICAL, "Arm: Need Position Estimate")
                    return failed
                if self.mode == LAND or self.in_flight or self.sim.state().battery <= 0.0:
                    return failed
                if self.battery_voltage < self.params["BATT_ARM_VOLT"]:
                    self._statustext(
                        mavlink.MAV_SEVERITY_CRITICAL,
                        "Arm: Battery 1 below minimum arming voltage",
                    )
                    return failed
                self.armed = True
                self._home = self.sim.state().position
                return ok
            if self.in_flight and msg.param2 != FORCE_DISARM:
                return failed
            self.armed = False
            return ok
        if command == mavlink.MAV_CMD_NAV_TAKEOFF:
            altitude = float(msg.param7)
            if self.mode != GUIDED or not self.armed or self.in_flight:
                return failed
            if not (math.isfinite(altitude) and altitude > 0):
                return failed
            try:
                self.sim.take_off(altitude)
            except VehicleCommandError:
                return failed
            self._launched = True
            if self._take_off_at is None:
                self._take_off_at = self._clock()
            return ok
        if command == mavlink.MAV_CMD_NAV_LAND:
            return self._enter_mode(LAND)
        if command == mavlink.MAV_CMD_CONDITION_YAW:
            if not (math.isfinite(msg.param1) and 0.0 <= msg.param1 <= 360.0):
                return failed
            if self.mode != GUIDED or not self.flying:
                return ok  # ArduCopter accepts it anywhere; it turns only in GUIDED flight
            heading = math.radians(msg.param1)
            if msg.param4 >= 0.5:  # relative: param3 gives the direction
                sign = -1.0 if msg.param3 < 0 else 1.0
                heading = yaw_enu_to_ned(self.sim.state().yaw) + sign * heading
            try:
                self.sim.set_yaw(yaw_ned_to_enu(heading))
            except VehicleCommandError:
                return failed
            return ok
        if command == mavlink.MAV_CMD_SET_MESSAGE_INTERVAL:
            message_id, interval = int(msg.param1), float(msg.param2)
            if message_id not in mavlink.mavlink_map:
                self._statustext(
                    mavlink.MAV_SEVERITY_INFO, f"No ap_message for mavlink id ({message_id})"
                )
                return mavlink.MAV_RESULT_DENIED
            if message_id not in DEFAULT_RATES or message_id == mavlink.MAVLINK_MSG_ID_HEARTBEAT:
                return ok
            if interval < 0:
                self._rates[message_id] = 0.0
            elif interval == 0:
                self._rates[message_id] = DEFAULT_RATES[message_id]
            else:
                self._rates[message_id] = 1e6 / interval
            return ok
        return mavlink.MAV_RESULT_UNSUPPORTED

    def _set_mode_message(self, msg: MAVLinkMessage) -> int:
        if not msg.base_mode & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
            return mavlink.MAV_RESULT_FAILED
        return self._enter_mode(int(msg.custom_mode))

    def _enter_mode(self, mode: int) -> int:
        if mode not in SUPPORTED_MODES:
            self._statustext(mavlink.MAV_SEVERITY_WARNING, f"No such mode {mode}")
            return mavlink.MAV_RESULT_FAILED
        self.mode = mode
        self._velocity_at = None
        self._overshoot = None
        self._rtl_stage = None
        if self.flying:
            try:
                if mode == LAND:
                    self.sim.land()
                elif mode == RTL:
                    self._rtl_stage = "climb"
                    self.sim.hover()
                else:
                    self.sim.hover()  # GUIDED, LOITER, BRAKE...: stop and hold
            except VehicleCommandError:
                return mavlink.MAV_RESULT_FAILED
        return mavlink.MAV_RESULT_ACCEPTED

    def _setpoint(self, msg: MAVLinkMessage) -> None:
        if (
            msg.coordinate_frame != mavlink.MAV_FRAME_LOCAL_NED
            or self.mode != GUIDED
            or not self.flying
        ):
            self.counters.ignored_setpoints += 1
            return
        mask = int(msg.type_mask)
        k = self.config.speed_factor
        try:
            if not mask & mavlink.POSITION_TARGET_TYPEMASK_YAW_IGNORE and math.isfinite(msg.yaw):
                self.sim.set_yaw(yaw_ned_to_enu(msg.yaw))
            if not mask & 0b111:  # position used
                self.counters.setpoints["position"] += 1
                self._velocity_at = None
                self._go_to(ned_to_enu((msg.x, msg.y, msg.z)))
            elif not mask & 0b111000:  # velocity used
                self.counters.setpoints["velocity"] += 1
                self._overshoot = None
                vx, vy, vz = ned_to_enu((msg.vx, msg.vy, msg.vz))
                if vx == 0.0 and vy == 0.0 and vz == 0.0:
                    self._velocity_at = None
                    self.sim.hover()
                else:
                    self._velocity_at = self._clock()
                    self.sim.set_velocity(*self._clamp(vx / k, vy / k, vz / k))
        except VehicleCommandError:
            self.counters.ignored_setpoints += 1

    def _go_to(self, goal: Vec3) -> None:
        """Fly to `goal`, overshooting it as ArduCopter does when it arrives at speed."""
        if self._overshoot is not None and self._overshoot[0] == goal:
            return  # the same setpoint again (a behavior re-aiming): the approach goes on
        here = self.sim.state().position
        distance = math.dist(here, goal)
        over = self.config.overshoot
        if goal[2] < 0.0 or over <= 0.0 or distance <= 2.0 * over:
            self._overshoot = None
            self.sim.go_to(*goal)
            return
        beyond = tuple(g + (g - h) / distance * over for g, h in zip(goal, here, strict=True))
        if beyond[2] < 0.0:  # never overshoot into the ground
            beyond = (beyond[0], beyond[1], goal[2])
        self.sim.go_to(*beyond)
        self._overshoot = (goal, (beyond[0], beyond[1], beyond[2]), None)

    def _clamp(self, vx: float, vy: float, vz: float) -> tuple[float, float, float]:
        limits = self.sim.world.limits
        horizontal = math.hypot(vx, vy)
        if horizontal > limits.horizontal_speed:
            scale = limits.horizontal_speed / horizontal
            vx, vy = vx * scale, vy * scale
        vz = max(-limits.vertical_speed, min(limits.vertical_speed, vz))
        return (vx, vy, vz)

    # -- reporting -----------------------------------------------------------------------
    def stats(self, tail: bool = False) -> dict[str, Any]:
        """Message counts by type and the final state; with `tail`, the last packets sent."""
        state = self.sim.state()
        counts = self.link.stats.as_dict()
        if not tail:
            del counts["tail"]
        return {
            **counts,
            "dropped_heartbeats": self.counters.dropped_heartbeats,
            "ignored_setpoints": self.counters.ignored_setpoints,
            "setpoints": dict(self.counters.setpoints),
            "commands": self.counters.commands,
            "final": {
                "mode": COPTER_MODES.get(self.mode, str(self.mode)),
                "armed": self.armed,
                "flying": state.flying,
                "position": [round(c, 4) for c in state.position],
                "yaw_deg": round(math.degrees(wrap_pi(state.yaw)), 3),
            },
            "elapsed_s": round(self.elapsed, 3),
        }

    def write_stats(self, path: str | Path, tail: bool = False) -> None:
        text = json.dumps(self.stats(tail), indent=2, sort_keys=True) + "\n"
        if str(path) == "-":
            print(text, end="")
        else:
            Path(path).write_text(text, encoding="utf-8")


def _param_name(param_id: str | bytes) -> str:
    """A PARAM_* message's 16-character id as a name (pymavlink gives str or bytes)."""
    if isinstance(param_id, bytes):
        param_id = param_id.decode("ascii", "replace")
    return param_id.split("\x00", 1)[0].strip()
