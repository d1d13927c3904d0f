"""`ReplayVehicle`: the recorded vehicle, played back (open-loop replay).

It implements the `Vehicle` protocol; `state()` is the latest recorded `vehicle/state`
at or before the executive's current time, read lazily from a streaming iterator, so
memory does not grow with the recording. Commands are accepted and ignored: in open
loop the aircraft did what the recording says it did, except the commands the recorded
vehicle refused (`Refusal`, derived from the recording by
`aeroexec.replay.refusals`): those it refuses again, with the same words, when asked
between the same two recorded ticks.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

from aeroexec.executive.clock import Clock
from aeroexec.replay.source import SourceMessage
from aeroexec.vehicles.base import Vec3, VehicleCommandError, VehicleState
from aeroexec.vehicles.null import NullVehicle

GROUNDED = VehicleState((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0, 1.0, False, False)


def _vec3(value: object) -> Vec3 | None:
    if not isinstance(value, list) or len(value) != 3:
        return None
    try:
        x, y, z = (float(v) for v in value)
    except (TypeError, ValueError):
        return None
    return (x, y, z)


def decode_state(data: bytes) -> VehicleState | None:
    """A `vehicle/state` message as a `VehicleState` (None if it is not one)."""
    try:
        message = json.loads(data)
    except ValueError:
        return None
    if not isinstance(message, dict):
        return None
    position = _vec3(message.get("position"))
    if position is None:
        return None
    velocity = _vec3(message.get("velocity")) or (0.0, 0.0, 0.0)
    try:
        yaw = float(message.get("yaw") or 0.0)
        battery = float(message.get("battery") if message.get("battery") is not None else 1.0)
    except (TypeError, ValueError):
        return None
    return VehicleState(
        position,
        velocity,
        yaw,
        battery,
        bool(message.get("flying")),
        bool(message.get("armed", message.get("flying"))),
        str(message.get("fault") or ""),
    )


@dataclass(frozen=True, slots=True)
class Refusal:
    """A vehicle command the recorded vehicle refused: when (the log time of the
    behavior's PROCESS_FAILURE, the recording's own time base), which behavior asked,
    and the refusal's words (`VehicleCommandError`'s message)."""

    time_ns: int
    behavior: str
    message: str


class ReplayVehicle(NullVehicle):
    """Shows the recorded vehicle state at the clock's time; commands change nothing
    (the recorded flight already happened)."""

    kind = "replay"

    def __init__(
        self,
        states: Iterator[SourceMessage],
        clock: Clock,
        offset_ns: int = 0,
        refusals: Sequence[Refusal] = (),
        upcoming: Callable[[], int] | None = None,
        heartbeat_timeout: str | None = None,
    ) -> None:
        """`states`: the recording's `vehicle/state` messages in order; `offset_ns`: the
        recorded time of the clock's zero; `refusals`: the commands to refuse again, in
        time order; `upcoming()`: the clock time of the next step (default: a tick on);
        `heartbeat_timeout` (a MAVLink flight's, as recorded): while the recorded state
        says `link_lost`, every command is refused as the flight's vehicle refused it
        then, the refusals no behavior event shows included (a hover when a behavior
        stops)."""
        self._states = states
        self._clock = clock
        self._offset = offset_ns
        self._refusals = list(refusals)
        self._heartbeat_timeout = heartbeat_timeout
        self._upcoming = upcoming or (lambda: clock.now_ns() + clock.tick_ns)
        self._next: tuple[int, VehicleState] | None = None
        self._current = GROUNDED
        self._pull()
        if self._next is not None:  # before the first record: the first recorded state
            self._current = self._next[1]

    def _pull(self) -> None:
        self._next = None
        for message in self._states:
            state = decode_state(message.data)
            if state is not None:
                self._next = (message.log_time_ns, state)
                return

    def state(self) -> VehicleState:
        now = self._clock.now_ns() + self._offset
        while self._next is not None and self._next[0] <= now:
            self._current = self._next[1]
            self._pull()
        return self._current

    # -- commands: accepted and ignored, unless the recorded vehicle refused them ---------
    def _answer(self, method: str) -> None:
        """Refuse `method` as the recorded vehicle did, if it did: the recorded refusal
        of a command asked after the last recorded tick (`now`) and refused before the
        next (the flight stepped no tick while it waited for the answer); else, while
        the recorded link was lost, the flight's link-lost refusal."""
        now = self._clock.now_ns() + self._offset
        upcoming = self._upcoming() + self._offset
        while self._refusals and self._refusals[0].time_ns < now:
            self._refusals.pop(0)  # its moment passed without the command: not ours
        if (
            self._refusals
            and self._refusals[0].time_ns <= upcoming
            and refused_by(method, self._refusals[0].message)
        ):
            raise VehicleCommandError(self._refusals.pop(0).message)
        if self._heartbeat_timeout is not None and self.state().fault == "link_lost":
            raise VehicleCommandError(
                f"{method}: refused, link lost (no heartbeat for {self._heartbeat_timeout} s)"
            )

    def take_off(self, altitude: float) -> None:
        self._answer("take_off")

    def land(self) -> None:
        self._answer("land")

    def go_to(self, x: float, y: float, z: float) -> None:
        self._answer("go_to")

    def set_velocity(self, vx: float, vy: float, vz: float) -> None:
        self._answer("set_velocity")

    def set_yaw(self, yaw: float) -> None:
        self._answer("set_yaw")

    def hover(self) -> None:
        self._answer("hover")

    def flip(self, direction: str) -> None:
        self._answer("flip")


#: The `Vehicle` commands, as a refusal names the one refused ("go_to: refused, ...").
COMMANDS = ("take_off", "land", "go_to", "set_velocity", "set_yaw", "hover", "flip")


def refused_by(method: str, words: str) -> bool:
    """Could a refusal in these words be `method`'s? A refusal names its command
    ("set_yaw: refused, link lost ...") or the MAVLink message the command sent
    ("MAV_CMD_NAV_TAKEOFF refused: FAILED"); a hover sends no COMMAND_LONG."""
    named = words.split(":", 1)[0]
    if named in COMMANDS:
        return named == method
    return method != "hover" or named.startswith("SET_POSITION_TARGET")
