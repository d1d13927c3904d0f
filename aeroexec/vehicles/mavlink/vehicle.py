"""`MavlinkVehicle`: the `Vehicle` protocol over MAVLink, for ArduPilot Copter in GUIDED.

One thread. `step(dt)` polls the link without blocking, folds telemetry into the state,
sends the ground station's 1 Hz heartbeat and watches the autopilot's. Commands that
MAVLink acknowledges (mode changes, arming, take-off, yaw, landing) are sent as
COMMAND_LONG and wait for their COMMAND_ACK, polling the link meanwhile, with a timeout
and bounded retries (the `confirmation` field counts the retransmissions); a refusal
raises `VehicleCommandError("MAV_CMD_NAV_TAKEOFF refused: TEMPORARILY_REJECTED")`.
Setpoints (`go_to`, `set_velocity`, `hover`) are SET_POSITION_TARGET_LOCAL_NED, which
MAVLink never acknowledges: they are checked against the mode and state first.

Link health: when no autopilot heartbeat arrived for `heartbeat_timeout` seconds, or a
TCP or serial connection closed, the link is lost: `state().fault == "link_lost"`, every
command raises, and a `mavlink/link` event is published. When heartbeats come back, the
configured failsafe runs (`hold`: brake and hold where the vehicle is; `land`: switch to
LAND; `rtl`: switch to RTL). With `link_timeout`, a link lost for longer than that makes
`step()` raise `LinkTimeout`, which ends the flight (see `aeroexec.mission.ending`).
The ground station's own HEARTBEAT (every second, and once per autopilot heartbeat) is
what ArduPilot's GCS failsafe (`FS_GCS_ENABLE`) watches: when aeroexec dies, the
autopilot acts on its own.

Every packet in and out is handed to `tap(topic, payload)` (wired to the executive's
bus by `aeroexec.mission.live.fly`); until a tap is attached the vehicle keeps them and
hands them over on attachment, so the recording starts with the connection.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from aeroexec.interrupts import check as check_interrupts
from aeroexec.vehicles.base import VehicleCommandError, VehicleState
from aeroexec.vehicles.mavlink.codec import MAVLinkMessage, command_name, result_name
from aeroexec.vehicles.mavlink.convert import (
    GUIDED,
    LAND,
    RTL,
    enu_to_ned,
    heading_degrees,
    mode_name,
    yaw_enu_to_ned,
)
from aeroexec.vehicles.mavlink.endpoint import (
    DEFAULT_BAUD,
    DEFAULT_GCS_URL,
    MavlinkError,
    parse_endpoint,
)
from aeroexec.vehicles.mavlink.link import Link, LinkStats, Received
from aeroexec.vehicles.mavlink.telemetry import Telemetry, is_autopilot_heartbeat, unbelievable

Failsafe = Literal["land", "hold", "rtl"]
FAILSAFES: tuple[Failsafe, ...] = ("land", "hold", "rtl")
#: Modes in which the autopilot brings the vehicle down by itself.
DESCENDING_MODES = frozenset({LAND, RTL, 21})  # 21: SMART_RTL
Tap = Callable[[str, Any], None]

#: Messages (and rates, Hz) requested from the autopilot with MAV_CMD_SET_MESSAGE_INTERVAL.
STREAMS: tuple[tuple[int, float], ...] = (
    (mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED, 10.0),
    (mavlink.MAVLINK_MSG_ID_ATTITUDE, 10.0),
    (mavlink.MAVLINK_MSG_ID_SYS_STATUS, 2.0),
    (mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE, 2.0),
)
#: The ground station's HEARTBEAT: at least every `gcs_heartbeat_period`, and once per
#: autopilot heartbeat, but never more often than this (Hz).
GCS_HEARTBEAT_MAX_HZ = 20.0
#: Traffic kept while no tap is attached (beyond it, only counted).
MAX_BUFFERED = 100_000
#: A failsafe's mode must show in a HEARTBEAT within this (s) of its COMMAND_ACK.
FAILSAFE_BOUND_S = 5.0
#: A hold (the failsafe's, or an ending's brake) is seen when the vehicle is slower
#: than this (m/s), by the autopilot's own LOCAL_POSITION_NED.
STILL_SPEED = 0.3
#: How long a `--failsafe hold` may take to be seen still: braking in GUIDED from a
#: copter's cruise speed takes ArduCopter several seconds (docs/mavlink.md).
HOLD_BOUND_S = 15.0
#: How long a refused command waits for the autopilot's STATUSTEXT saying why (s).
REFUSAL_TEXT_WAIT_S = 0.5
#: STATUSTEXTs kept (the older half is dropped when full).
MAX_TEXTS = 200

_IGNORE_VELOCITY = (
    mavlink.POSITION_TARGET_TYPEMASK_VX_IGNORE
    | mavlink.POSITION_TARGET_TYPEMASK_VY_IGNORE
    | mavlink.POSITION_TARGET_TYPEMASK_VZ_IGNORE
)
_IGNORE_POSITION = (
    mavlink.POSITION_TARGET_TYPEMASK_X_IGNORE
    | mavlink.POSITION_TARGET_TYPEMASK_Y_IGNORE
    | mavlink.POSITION_TARGET_TYPEMASK_Z_IGNORE
)
_IGNORE_ACCELERATION = (
    mavlink.POSITION_TARGET_TYPEMASK_AX_IGNORE
    | mavlink.POSITION_TARGET_TYPEMASK_AY_IGNORE
    | mavlink.POSITION_TARGET_TYPEMASK_AZ_IGNORE
)
#: Position setpoint with a heading (yaw rate ignored).
POSITION_MASK = (
    _IGNORE_VELOCITY | _IGNORE_ACCELERATION | mavlink.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE
)
#: Velocity setpoint with a heading.
VELOCITY_MASK = (
    _IGNORE_POSITION | _IGNORE_ACCELERATION | mavlink.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE
)


class LinkTimeout(BaseException):
    """The link stayed lost longer than `link_timeout`: the flight cannot go on.

    A `BaseException`, like `KeyboardInterrupt`: a mission's `except Exception:` must not
    keep a flight running without a link."""

    def __init__(self, silent_s: float) -> None:
        self.silent_s = silent_s
        super().__init__(f"link lost for {silent_s:.1f} s")


@dataclass(frozen=True, slots=True)
class MavlinkConfig:
    url: str = DEFAULT_GCS_URL
    allow_remote: bool = False
    #: 32-byte MAVLink 2 signing key (see `codec.signing_key`), or None for no signing.
    signing_key: bytes | None = None
    heartbeat_timeout: float = 3.0
    failsafe: Failsafe = "land"
    #: A link lost this long (s) ends the flight (`LinkTimeout` from `step`); None: never.
    link_timeout: float | None = None
    #: Serial devices given without `,BAUD`.
    baud: int = DEFAULT_BAUD
    ack_timeout: float = 1.0
    retries: int = 2
    connect_timeout: float = 10.0
    #: Our own identity: a ground station (255) / onboard companion component.
    system: int = 255
    component: int = 190
    #: The autopilot's system id; None: the first autopilot heard.
    target_system: int | None = None
    gcs_heartbeat_period: float = 1.0
    #: ArduCopter drops a velocity setpoint after 3 s; it is re-sent this often.
    velocity_resend_period: float = 1.0
    request_streams: bool = True

    def __post_init__(self) -> None:
        if not (math.isfinite(self.heartbeat_timeout) and self.heartbeat_timeout > 0):
            raise ValueError(f"heartbeat timeout must be positive, got {self.heartbeat_timeout}")
        if self.failsafe not in FAILSAFES:
            raise ValueError(f"failsafe must be one of {', '.join(FAILSAFES)}")
        if self.link_timeout is not None and not (
            math.isfinite(self.link_timeout) and self.link_timeout >= 0
        ):
            raise ValueError(f"link timeout must be >= 0 seconds, got {self.link_timeout}")
        if self.baud <= 0:
            raise ValueError(f"baud rate must be positive, got {self.baud}")
        if not (math.isfinite(self.ack_timeout) and self.ack_timeout > 0):
            raise ValueError(f"ack timeout must be positive, got {self.ack_timeout}")
        if self.retries < 0:
            raise ValueError(f"retries must be >= 0, got {self.retries}")
        if not (math.isfinite(self.connect_timeout) and self.connect_timeout > 0):
            raise ValueError(f"connect timeout must be positive, got {self.connect_timeout}")


class MavlinkVehicle:
    """A live ArduCopter (or anything speaking its GUIDED-mode protocol, like `mavsim`)."""

    kind = "mavlink"

    def __init__(
        self,
        config: MavlinkConfig | None = None,
        *,
        tap: Tap | None = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.config = config if config is not None else MavlinkConfig()
        self.endpoint = parse_endpoint(
            self.config.url, allow_remote=self.config.allow_remote, baud=self.config.baud
        )
        self._clock = clock
        self._start = clock()
        self._tap: Tap | None = tap
        self._buffered: list[tuple[str, Any]] = []
        self.dropped_before_tap = 0
        self.link = Link(
            self.endpoint,
            system=self.config.system,
            component=self.config.component,
            key=self.config.signing_key,
            tap=self._emit,
            on_transport=self._transport_event,
            validate=unbelievable,
        )
        self.telemetry = Telemetry()
        #: (system, component) of the autopilot, once its first heartbeat arrived.
        self.target: tuple[int, int] | None = None
        self._last_heartbeat = -math.inf
        self.link_lost = False
        self.link_losses = 0
        #: When the current loss began (the last heartbeat before it), or None.
        self.lost_since: float | None = None
        self._failsafe_pending = False
        #: A failsafe not yet seen done: (mode, heartbeats before it, when it was
        #: acknowledged, deadline, whether it is a hold, to be seen still too).
        self._failsafe_watch: tuple[int, int, float, float, bool] | None = None
        #: Why the last failsafe was not confirmed ("" when it was, or none ran).
        self.failsafe_problem = ""
        self._acks: list[MAVLinkMessage] = []
        self._commanded_mode: int | None = None
        self._yaw_target_ned: float | None = None
        self._velocity_ned: tuple[float, float, float] | None = None
        self._next_gcs_heartbeat = -math.inf
        self._last_gcs_heartbeat = -math.inf
        self._next_velocity = math.inf
        self._streams_requested = False
        #: The autopilot's STATUSTEXTs: (our clock, severity, text), oldest first.
        self.texts: list[tuple[float, int, str]] = []
        #: Parameters read with `read_parameters` (PARAM_VALUE), by name.
        self.parameters: dict[str, float] = {}

    # -- the tap -------------------------------------------------------------------------
    @property
    def tap(self) -> Tap | None:
        return self._tap

    @tap.setter
    def tap(self, tap: Tap | None) -> None:
        """Attach (or detach) the traffic tap; what arrived before is handed over now."""
        self._tap = tap
        if tap is not None:
            buffered, self._buffered = self._buffered, []
            for topic, payload in buffered:
                tap(topic, payload)

    def _emit(self, topic: str, payload: Any) -> None:
        if self._tap is not None:
            self._tap(topic, payload)
        elif len(self._buffered) < MAX_BUFFERED:
            self._buffered.append((topic, payload))
        else:
            self.dropped_before_tap += 1

    def _event(self, event: str, **detail: Any) -> None:
        self._emit("mavlink/link", {"event": event, "url": self.endpoint.url, **detail})

    def _log(self, message: str, level: str = "WARNING") -> None:
        self._emit("log", {"level": level, "name": "mavlink", "message": message})

    # -- connection ----------------------------------------------------------------------
    @property
    def stats(self) -> LinkStats:
        return self.link.stats

    @property
    def connected(self) -> bool:
        return self.target is not None and not self.link_lost

    def connect(self, timeout: float | None = None) -> None:
        """Wait for the autopilot's heartbeat and a first position; request the streams.
        `MavlinkError` if it does not come within `timeout` (default: the config's)."""
        limit = self.config.connect_timeout if timeout is None else timeout
        deadline = self._clock() + limit
        while self.target is None or self.telemetry.positions == 0:
            check_interrupts()  # an operator may give up on a vehicle that never answers
            remaining = deadline - self._clock()
            if remaining <= 0:
                raise MavlinkError(self._no_connection_text(limit))
            self._process(self.link.poll(min(remaining, 0.05)))
            self._service()
            if self.target is not None and not self._streams_requested:
                self._streams_requested = True
                self._request_streams()
        self._event(
            "connected",
            system=self.target[0],
            component=self.target[1],
            mode=self.telemetry.mode,
            armed=self.telemetry.armed,
        )

    def _no_connection_text(self, limit: float) -> str:
        transport = self.link.transport
        if self.endpoint.stream and not transport.up and self.target is None:
            what = "client on" if self.endpoint.kind == "tcpin" else "connection to"
            text = f"no {what} {self.endpoint.url} within {limit:g} s"
            error = getattr(transport, "last_error", "")
            return f"{text} ({error})" if error else text
        if self.target is None:
            text = f"no heartbeat from {self.endpoint.url} within {limit:g} s"
        else:
            text = (
                f"heartbeat from {self.endpoint.url} but no LOCAL_POSITION_NED within "
                f"{limit:g} s (has the autopilot a position estimate?)"
            )
        reasons = self.link.stats.reasons()
        if reasons:
            text += f" (packets: {reasons})"
        return text

    def _request_streams(self) -> None:
        if not self.config.request_streams:
            return
        for message_id, rate in STREAMS:
            try:
                self._command(
                    mavlink.MAV_CMD_SET_MESSAGE_INTERVAL,
                    (float(message_id), 1e6 / rate),
                    retries=0,
                )
            except VehicleCommandError as exc:
                self._log(f"stream request not granted: {exc}")

    def read_parameters(
        self, names: tuple[str, ...], timeout: float = 2.0, min_sys_status: int = 0
    ) -> dict[str, float]:
        """Ask for `names` with PARAM_REQUEST_READ (again for the missing, every half
        `timeout`) and wait for their PARAM_VALUEs, at most `timeout` s; what arrived.
        Also waits (within `timeout`) for `min_sys_status` SYS_STATUS messages."""
        target = self._require_link("PARAM_REQUEST_READ")
        deadline = self._clock() + timeout
        resend = -math.inf
        while True:
            missing = [n for n in names if n not in self.parameters]
            if not missing and self.telemetry.sys_statuses >= min_sys_status:
                break
            now = self._clock()
            if now >= deadline:
                break
            if missing and now >= resend:
                resend = now + timeout / 2
                for name in missing:
                    self.link.send(
                        mavlink.MAVLink_param_request_read_message(
                            target[0], target[1], name.encode("ascii"), -1
                        )
                    )
            check_interrupts()
            self._process(self.link.poll(min(deadline - now, 0.05)))
            self._service()
        return {n: self.parameters[n] for n in names if n in self.parameters}

    def close(self) -> None:
        self.link.close()

    # -- the Vehicle protocol: observation -----------------------------------------------
    def state(self) -> VehicleState:
        return self.telemetry.vehicle_state(self._fault())

    def _fault(self) -> str:
        if self.link_lost:
            return "link_lost"
        if self.target is None:
            return "not_connected"
        if (
            self._commanded_mode is not None
            and self.telemetry.custom_mode != self._commanded_mode
            and self.telemetry.flying
        ):
            return f"mode_changed:{self.telemetry.mode}"
        return ""

    def visible_markers(self) -> tuple[int, ...]:
        return ()  # no marker detection over MAVLink

    def visible_object(self) -> tuple[float, float, float] | None:
        return None

    # -- the Vehicle protocol: time ------------------------------------------------------
    def step(self, dt: float) -> None:
        self._process(self.link.poll())
        self._acks.clear()  # nobody is waiting for one now
        self._service()
        if self._failsafe_pending and not self.link_lost:
            self._failsafe_pending = False
            self._run_failsafe()
        watch = self._failsafe_watch
        if watch is not None and watch[4]:
            self._see_failsafe(watch)
            watch = self._failsafe_watch
        if watch is not None and self._clock() > watch[3]:
            self._failsafe_watch = None
            if watch[4] and self.telemetry.heard_mode == watch[0]:
                self.failsafe_problem = (
                    f"failsafe hold not confirmed: still moving at {self.telemetry.speed:.1f} "
                    f"m/s {watch[3] - watch[2]:g} s after the brake"
                )
            else:
                self.failsafe_problem = (
                    f"failsafe {mode_name(watch[0])} not confirmed: the autopilot still says "
                    f"{self.telemetry.heard_mode_name} {watch[3] - watch[2]:g} s after "
                    "acknowledging it"
                )
            self._event("failsafe_unconfirmed", mode=mode_name(watch[0]))
            self._log(self.failsafe_problem, "ERROR")
        limit = self.config.link_timeout
        if limit is not None and self.lost_since is not None:
            silent = self._clock() - self.lost_since
            if silent > limit:
                raise LinkTimeout(silent)

    def _process(self, received: list[Received]) -> None:
        for item in received:
            msg = item.msg
            src = msg.get_srcSystem()
            if self.target is None:
                wanted = self.config.target_system
                if is_autopilot_heartbeat(msg) and (wanted is None or wanted == src):
                    self.target = (src, msg.get_srcComponent())
                    self.link.lock(item.address)
                else:
                    self.link.count_ignored("before_heartbeat")
                    self.link.record_rx(msg, "before the autopilot's first heartbeat")
                    continue
            elif src != self.target[0]:
                self.link.count_ignored("foreign_system")
                self.link.record_rx(msg, f"foreign system {src}")
                continue
            self.link.record_rx(msg)
            self._handle(msg, item)

    def _handle(self, msg: MAVLinkMessage, item: Received) -> None:
        # Only the autopilot's own component speaks for the vehicle (a gimbal on the same
        # system sends ATTITUDE and HEARTBEAT too).
        if self.target is None or msg.get_srcComponent() != self.target[1]:
            return
        kind = msg.get_type()
        if kind == "HEARTBEAT":
            self._heartbeat(item)
            return
        if kind == "COMMAND_ACK":
            mine = msg.target_system in (0, self.config.system)
            if mine:
                self._acks.append(msg)
            return
        if kind == "STATUSTEXT":
            text = msg.format_attr("text")
            if len(self.texts) >= MAX_TEXTS:
                del self.texts[: MAX_TEXTS // 2]
            self.texts.append((self._clock(), int(msg.severity), text))
            self._log(f"autopilot: {text}", _severity(msg.severity))
            return
        if kind == "PARAM_VALUE":
            name = msg.format_attr("param_id")
            if math.isfinite(msg.param_value):
                self.parameters[name] = float(msg.param_value)
            return
        self.telemetry.apply(msg)

    def _heartbeat(self, item: Received) -> None:
        self.telemetry.apply(item.msg)
        self._last_heartbeat = self._clock()
        if self._failsafe_watch is not None:
            self._see_failsafe(self._failsafe_watch)
        # Answer each autopilot heartbeat with ours (at most GCS_HEARTBEAT_MAX_HZ): an
        # autopilot that beats faster than 1 Hz runs faster than the wall clock (SITL
        # with a speed-up), and its GCS failsafe (FS_GCS_TIMEOUT) counts on its clock.
        if self._last_heartbeat - self._last_gcs_heartbeat >= 1.0 / GCS_HEARTBEAT_MAX_HZ:
            self._beat(self._last_heartbeat)
        if self.link_lost:
            silent = self._last_heartbeat - (self.lost_since or self._last_heartbeat)
            self.link_lost = False
            self.lost_since = None
            self.link.lock(item.address)
            self._failsafe_pending = True
            self._event("restored", failsafe=self.config.failsafe, silent_s=round(silent, 3))

    def _transport_event(self, event: str, detail: str) -> None:
        self._event("connection", state=event, detail=detail)
        if event == "closed" and self.target is not None and not self.link_lost:
            # A closed TCP connection or a vanished serial port is a loss at once: no
            # heartbeat can arrive until it is reopened.
            self._lose(detail)

    def _lose(self, why: str) -> None:
        now = self._clock()
        self.link_lost = True
        self.link_losses += 1
        self.lost_since = self._last_heartbeat if math.isfinite(self._last_heartbeat) else now
        self._velocity_ned = None  # the autopilot drops it too; never resumed
        self.link.unlock()
        self._event("lost", silent_s=round(now - self.lost_since, 3), why=why)

    def _beat(self, now: float) -> None:
        self.link.send(
            mavlink.MAVLink_heartbeat_message(
                mavlink.MAV_TYPE_GCS,
                mavlink.MAV_AUTOPILOT_INVALID,
                0,
                0,
                mavlink.MAV_STATE_ACTIVE,
                3,
            )
        )
        self._last_gcs_heartbeat = now
        self._next_gcs_heartbeat = now + self.config.gcs_heartbeat_period

    def _service(self) -> None:
        now = self._clock()
        if now >= self._next_gcs_heartbeat:
            self._beat(now)
        if (
            self.target is not None
            and not self.link_lost
            and now - self._last_heartbeat > self.config.heartbeat_timeout
        ):
            self._lose("no heartbeat")
        if self._velocity_ned is not None and now >= self._next_velocity and not self.link_lost:
            self._send_velocity(self._velocity_ned)

    def _see_failsafe(self, watch: tuple[int, int, float, float, bool]) -> None:
        """The failsafe is seen done: a HEARTBEAT after it in its mode and, for a hold,
        the vehicle slower than `STILL_SPEED`."""
        mode, beats, since, _, hold = watch
        if self.telemetry.heartbeats <= beats or self.telemetry.heard_mode != mode:
            return
        if hold and self.telemetry.speed > STILL_SPEED:
            return
        self._failsafe_watch = None
        seen: dict[str, Any] = {"mode": mode_name(mode)}
        if hold:
            seen["speed"] = round(self.telemetry.speed, 2)
        self._event("failsafe_seen", **seen, after_s=round(self._clock() - since, 3))

    def _run_failsafe(self) -> None:
        self._velocity_ned = None
        if not self.telemetry.flying:
            self._event("failsafe", action="none", reason="not flying")
            return
        self.failsafe_problem = ""
        try:
            beats = self.telemetry.heartbeats
            if self.config.failsafe == "land":
                self._set_mode(LAND)
            elif self.config.failsafe == "rtl":
                self._set_mode(RTL)
            elif self.telemetry.custom_mode == GUIDED:
                self._brake()
            if self.config.failsafe != "hold" or self.telemetry.custom_mode == GUIDED:
                # Acknowledged is not done: watch the HEARTBEATs for the mode, and for a
                # hold the autopilot's own velocity too (sent is not stopped).
                now = self._clock()
                mode = self.telemetry.custom_mode
                hold = self.config.failsafe == "hold"
                bound = HOLD_BOUND_S if hold else FAILSAFE_BOUND_S
                self._failsafe_watch = (mode, beats, now, now + bound, hold)
            # hold outside GUIDED: the autopilot's own failsafe (LAND, RTL) or a pilot
            # has the vehicle; a setpoint would be ignored, and taking over is not ours.
            self._event("failsafe", action=self.config.failsafe, mode=self.telemetry.mode)
        except VehicleCommandError as exc:
            self._event("failsafe", action=self.config.failsafe, error=str(exc))
            self._log(f"failsafe {self.config.failsafe} failed: {exc}", "ERROR")

    # -- commands ------------------------------------------------------------------------
    def _require_link(self, what: str) -> tuple[int, int]:
        if self.target is None:
            raise VehicleCommandError(f"{what}: refused, no autopilot connected")
        if self.link_lost:
            raise VehicleCommandError(
                f"{what}: refused, link lost (no heartbeat for {self.config.heartbeat_timeout:g} s)"
            )
        return self.target

    def _require_guided_flight(self, what: str) -> None:
        self._require_link(what)
        if not self.telemetry.flying:
            raise VehicleCommandError(f"{what}: refused, the vehicle is on the ground")
        if self.telemetry.custom_mode != GUIDED:
            raise VehicleCommandError(
                f"{what}: refused, the autopilot is in {self.telemetry.mode} mode, not GUIDED"
            )

    def _command(
        self, command: int, params: tuple[float, ...], *, retries: int | None = None
    ) -> MAVLinkMessage:
        """Send COMMAND_LONG and wait for its ACCEPTED ack; raise on refusal or silence."""
        target = self._require_link(command_name(command))
        name = command_name(command)
        p = (*params, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)[:7]
        attempts = 1 + (self.config.retries if retries is None else retries)
        self._acks.clear()
        texts_before = len(self.texts)
        for attempt in range(attempts):
            self.link.send(
                mavlink.MAVLink_command_long_message(
                    target[0], target[1], command, min(attempt, 255), *p
                )
            )
            deadline = self._clock() + self.config.ack_timeout
            while True:
                for ack in self._acks:
                    if ack.command != command:
                        continue
                    if ack.result == mavlink.MAV_RESULT_IN_PROGRESS:
                        deadline = self._clock() + self.config.ack_timeout
                        continue
                    self._acks.clear()
                    if ack.result == mavlink.MAV_RESULT_ACCEPTED:
                        return ack
                    if (
                        command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM
                        and ack.result == mavlink.MAV_RESULT_FAILED
                        and len(self.texts) == texts_before
                    ):
                        self._await_text(texts_before)
                    said = "; ".join(t for _, _, t in self.texts[texts_before:])
                    because = f" (autopilot: {said})" if said else ""
                    raise VehicleCommandError(f"{name} refused: {result_name(ack.result)}{because}")
                self._acks.clear()
                remaining = deadline - self._clock()
                if remaining <= 0:
                    break
                self._process(self.link.poll(min(remaining, 0.05)))
                self._service()
                if self.link_lost:
                    raise VehicleCommandError(
                        f"{name}: link lost while waiting for COMMAND_ACK (no heartbeat for "
                        f"{self.config.heartbeat_timeout:g} s)"
                    )
        raise VehicleCommandError(
            f"{name}: no COMMAND_ACK after {attempts} attempt{'s' if attempts > 1 else ''} "
            f"({self.config.ack_timeout:g} s each)"
        )

    def _await_text(self, count: int) -> None:
        """Wait, briefly, for the autopilot to say why it refused to arm: ArduCopter
        states every failed arming check in a STATUSTEXT ("Arm: Battery 1 below minimum
        arming voltage"), which it queues, while the COMMAND_ACK goes out at once: the
        reason may come just after the refusal."""
        deadline = self._clock() + REFUSAL_TEXT_WAIT_S
        while len(self.texts) == count and not self.link_lost:
            remaining = deadline - self._clock()
            if remaining <= 0:
                return
            self._process(self.link.poll(min(remaining, 0.05)))
            self._service()

    def _set_mode(self, mode: int) -> None:
        self._command(
            mavlink.MAV_CMD_DO_SET_MODE,
            (float(mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED), float(mode)),
        )
        self._commanded_mode = mode
        self.telemetry.custom_mode = mode  # the next heartbeat will say so too
        if mode != GUIDED:
            self._velocity_ned = None  # setpoints mean nothing outside GUIDED

    def _arm(self) -> None:
        self._command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (1.0,))
        self.telemetry.armed = True

    def take_off(self, altitude: float) -> None:
        self._require_link("take_off")
        if self.telemetry.flying:
            raise VehicleCommandError("take_off: refused, already flying")
        if not (math.isfinite(altitude) and altitude > 0.0):
            raise VehicleCommandError(f"take_off: altitude must be positive, got {altitude}")
        if self.telemetry.custom_mode != GUIDED:
            self._set_mode(GUIDED)
        self._commanded_mode = GUIDED
        if not self.telemetry.armed:
            self._arm()
        self._command(mavlink.MAV_CMD_NAV_TAKEOFF, (0.0, 0.0, 0.0, math.nan, 0.0, 0.0, altitude))
        self._yaw_target_ned = self.telemetry.yaw_ned
        self._velocity_ned = None

    def land(self) -> None:
        self._require_link("land")
        if not self.telemetry.flying:
            raise VehicleCommandError("land: refused, the vehicle is on the ground")
        self._velocity_ned = None
        self._set_mode(LAND)

    def go_to(self, x: float, y: float, z: float) -> None:
        self._require_guided_flight("go_to")
        if not all(math.isfinite(c) for c in (x, y, z)):
            raise VehicleCommandError(f"go_to: not a position: ({x}, {y}, {z})")
        if z < 0.0:
            raise VehicleCommandError(f"go_to: z = {z:g} m is below the ground")
        north, east, down = enu_to_ned((float(x), float(y), float(z)))
        self._velocity_ned = None
        self._send_target(POSITION_MASK, (north, east, down), (0.0, 0.0, 0.0))

    def set_velocity(self, vx: float, vy: float, vz: float) -> None:
        self._require_guided_flight("set_velocity")
        if not all(math.isfinite(c) for c in (vx, vy, vz)):
            raise VehicleCommandError(f"set_velocity: not a velocity: ({vx}, {vy}, {vz})")
        self._send_velocity(enu_to_ned((float(vx), float(vy), float(vz))))

    def set_yaw(self, yaw: float) -> None:
        self._require_guided_flight("set_yaw")
        if not math.isfinite(yaw):
            raise VehicleCommandError(f"set_yaw: not an angle: {yaw}")
        # param1 heading (deg, CW from north), param2 rate (0: default), param3 direction
        # (0: the shorter way), param4 0: absolute.
        self._command(mavlink.MAV_CMD_CONDITION_YAW, (heading_degrees(yaw), 0.0, 0.0, 0.0))
        self._yaw_target_ned = yaw_enu_to_ned(yaw)

    def hover(self) -> None:
        self._require_guided_flight("hover")
        self._brake()

    def flip(self, direction: str) -> None:
        raise VehicleCommandError(
            "flip: not supported over MAVLink (ArduCopter's FLIP mode needs a pilot's sticks)"
        )

    def _brake(self) -> None:
        """Zero velocity: the autopilot decelerates and holds where it stops."""
        self._velocity_ned = None
        self._send_target(VELOCITY_MASK, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))

    def _send_velocity(self, velocity_ned: tuple[float, float, float]) -> None:
        self._velocity_ned = velocity_ned
        self._next_velocity = self._clock() + self.config.velocity_resend_period
        self._send_target(VELOCITY_MASK, (0.0, 0.0, 0.0), velocity_ned)

    def _send_target(
        self,
        mask: int,
        position: tuple[float, float, float],
        velocity: tuple[float, float, float],
    ) -> None:
        target = self._require_link("SET_POSITION_TARGET_LOCAL_NED")
        yaw = self._yaw_target_ned if self._yaw_target_ned is not None else self.telemetry.yaw_ned
        boot_ms = int((self._clock() - self._start) * 1000) & 0xFFFFFFFF
        self.link.send(
            mavlink.MAVLink_set_position_target_local_ned_message(
                boot_ms,
                target[0],
                target[1],
                mavlink.MAV_FRAME_LOCAL_NED,
                mask,
                *position,
                *velocity,
                0.0,
                0.0,
                0.0,
                yaw,
                0.0,
            )
        )

    # -- endings (see aeroexec.mission.ending) -------------------------------------------
    @property
    def descending(self) -> bool:
        """The autopilot is bringing the vehicle down by itself (LAND, RTL, SMART_RTL)."""
        return self.telemetry.custom_mode in DESCENDING_MODES

    @property
    def in_commanded_mode(self) -> bool:
        """The autopilot is in the mode aeroexec last commanded (not a pilot's, nor one
        its own failsafe chose, nor the one it had when aeroexec connected)."""
        return self._commanded_mode is not None and (
            self.telemetry.custom_mode == self._commanded_mode
        )

    @property
    def down(self) -> bool:
        """Landed and disarmed, as the autopilot last said (EXTENDED_SYS_STATE and its
        HEARTBEAT: never assumed from a command sent). An arm acknowledged since that
        HEARTBEAT counts as armed: the HEARTBEAT is older than the arm."""
        t = self.telemetry
        return not t.flying and not t.heard_armed and not t.armed

    def bring_down(self) -> str:
        """LAND, unless the autopilot is already landing or returning; what was done."""
        if self.descending:
            return f"left it in {self.telemetry.mode}"
        self._velocity_ned = None
        self._require_link("land")
        self._set_mode(LAND)
        return "switched to LAND"

    def return_home(self) -> str:
        """RTL, unless the autopilot is already landing or returning; what was done."""
        if self.descending:
            return f"left it in {self.telemetry.mode}"
        self._velocity_ned = None
        self._require_link("return")
        self._set_mode(RTL)
        return "switched to RTL"

    def switch_mode(self, mode: int) -> None:
        """Switch to `mode` (acknowledged; the HEARTBEAT shows it later): for an ending
        (BRAKE before a landing)."""
        self._velocity_ned = None
        self._require_link(mode_name(mode))
        self._set_mode(mode)

    def hold_here(self) -> str:
        """Brake and hold in GUIDED; in any other mode the autopilot keeps what it does."""
        if self.telemetry.custom_mode != GUIDED:
            return f"left it in {self.telemetry.mode}"
        self._brake()
        return "braked to hold in GUIDED"

    def disarm(self) -> None:
        """Disarm on the ground (never forced: the autopilot refuses in the air)."""
        self._command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (0.0,))
        self.telemetry.armed = False

    def silent_for(self) -> float:
        """Seconds since the autopilot's last heartbeat (inf before the first)."""
        return self._clock() - self._last_heartbeat

    def last_seen(self) -> str:
        """The vehicle as last heard: "flying at (3.00, 5.50, 1.30) m in GUIDED, armed"
        (with "N s ago" when the link is lost)."""
        t = self.telemetry
        x, y, z = self.state().position
        where = f"at ({x:.2f}, {y:.2f}, {z:.2f}) m"
        what = "flying" if t.flying else "on the ground"
        text = f"{what} {where} in {t.mode}, {'armed' if t.armed else 'disarmed'}"
        if self.link_lost or self.target is None:
            text += f", {self.silent_for():.1f} s ago"
        return text

    # -- reporting -----------------------------------------------------------------------
    def describe(self) -> str:
        mode = mode_name(self.telemetry.custom_mode) if self.telemetry.custom_mode >= 0 else "?"
        return f"{self.endpoint.url} system {self.target} mode {mode}"


def _severity(severity: int) -> str:
    if severity <= mavlink.MAV_SEVERITY_ERROR:
        return "ERROR"
    if severity <= mavlink.MAV_SEVERITY_WARNING:
        return "WARNING"
    return "INFO"
