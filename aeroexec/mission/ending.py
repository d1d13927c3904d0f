"""How a live flight ends: never by just closing the link under a flying vehicle.

Whatever ended the mission (it returned, it raised, a signal, a link lost too long),
`end_flight` runs the same policy, with the executive still stepping so every packet and
state keeps being recorded:

1. the behaviors still active are inhibited (through the mission API, so the recording
   shows the commands and a replay repeats them);
2. a lost link is waited for until `link_timeout` seconds after it went silent; when it
   comes back, the vehicle's failsafe (`--failsafe`) runs first;
3. `on_exit` is applied to a vehicle that is airborne (or armed): `land` brakes a
   vehicle moving in GUIDED first, in BRAKE (a LAND at speed touches down metres on,
   wherever its descent ends), switches to LAND (unless the autopilot is already
   landing or returning) and waits, bounded, for landed and disarmed, disarming a
   vehicle left armed on the ground (a link lost while braking: once it is back, and
   the failsafe has run, the landing starts over); `hold` brakes and holds in GUIDED
   and leaves it to the autopilot's own GCS failsafe; `none` leaves the vehicle as it
   is. A vehicle flying in a mode aeroexec did not command (a pilot took
   over with the sticks, or was flying it when aeroexec connected) is left to whoever
   has it: aeroexec never takes a vehicle away from a pilot.

Every step is confirmed from the autopilot's own telemetry before it is reported,
never assumed from what was sent: a brake by a HEARTBEAT in its mode and `STILL_FOR_S` of
LOCAL_POSITION_NED slower than `STILL_SPEED` (within `BRAKE_BOUND_S`); LAND by a
HEARTBEAT in LAND (within `MODE_BOUND_S`); landed and disarmed by EXTENDED_SYS_STATE
and a HEARTBEAT heard after the ending's last command (within the landing's bound, or
`LANDING_MARGIN_S` for a disarm on the ground). The actions say what was seen; a step not
seen within its bound is said so, and the ending has a `problem` (fly exits 1), even when
the vehicle came down after all (a brake never seen to stop: it landed wherever LAND
found it, not where it was braked).

A signal during the waits (a second Ctrl-C) stops waiting: the vehicle keeps doing what
it was told. The result says whether the vehicle ended landed and disarmed, and the one
line describing its last seen state.
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass
from typing import Literal

from aeroexec.executive.executive import Executive
from aeroexec.interrupts import Interrupted
from aeroexec.mission.api import MissionAPI
from aeroexec.vehicles.base import VehicleCommandError
from aeroexec.vehicles.mavlink.convert import BRAKE, GUIDED, LAND, mode_name
from aeroexec.vehicles.mavlink.vehicle import STILL_SPEED, LinkTimeout, MavlinkVehicle

OnExit = Literal["land", "hold", "none"]
ON_EXIT: tuple[OnExit, ...] = ("land", "hold", "none")
#: Wall seconds a landing may take beyond its descent at `LANDING_RATE` (touchdown,
#: the autopilot's land detector and disarm take a few seconds).
LANDING_MARGIN_S = 20.0
#: The slowest descent rate (m/s) a landing is expected to keep (ArduCopter: LAND_SPEED
#: 0.5 m/s near the ground).
LANDING_RATE = 0.25
#: An RTL first flies home (WPNAV_SPEED, 5 m/s by default): at least this speed (m/s).
RETURN_RATE = 1.0
#: Slower than `STILL_SPEED` for this long in a row (s): then a brake (a hold) is confirmed.
STILL_FOR_S = 1.0
#: A brake must be seen to stop within this (s), plus `BRAKE_PER_SPEED_S` per m/s.
BRAKE_BOUND_S = 8.0
BRAKE_PER_SPEED_S = 1.0
#: An unconfirmed brake is sent again this often (s): a setpoint is never acknowledged.
REBRAKE_S = 0.5
#: A mode change must be seen in the autopilot's HEARTBEAT within this (s).
MODE_BOUND_S = 5.0


@dataclass(frozen=True, slots=True)
class Ending:
    #: The vehicle was last seen landed and disarmed.
    down: bool
    #: "landed and disarmed at (0.01, 0.00, 0.00) m in LAND" / "flying at ... 31.0 s ago".
    last_seen: str
    #: What `end_flight` did, in order ("inhibited GO_TO_POINT", "switched to LAND", ...).
    actions: tuple[str, ...]
    #: Why the vehicle may not be down, or a step of the ending that was not seen: ""
    #: when the vehicle is down and every step was seen.
    problem: str = ""

    @property
    def confirmed(self) -> bool:
        """Seen landed and disarmed, every step of the ending seen as it was meant."""
        return self.down and not self.problem

    def line(self) -> str:
        """One line for the operator."""
        if self.confirmed:
            return f"vehicle {self.last_seen}"
        if self.down:
            return f"vehicle {self.last_seen}; {self.problem}"
        return f"vehicle not landed: {self.problem}; last seen {self.last_seen}"


def end_flight(
    executive: Executive,
    api: MissionAPI,
    vehicle: MavlinkVehicle,
    on_exit: OnExit,
    *,
    link_timeout: float,
) -> Ending:
    """Bring the flight to its documented end (see the module docstring)."""
    actions: list[str] = []
    stepper = _Stepper(executive)
    try:
        _inhibit_all(executive, api, actions)
        if vehicle.link_lost and not _wait_for_link(stepper, vehicle, link_timeout):
            return _ending(vehicle, actions, f"link lost, no heartbeat for {link_timeout:g} s")
        if not vehicle.connected:
            return _ending(vehicle, actions, "no autopilot connected")
        if on_exit == "land":
            return _land(stepper, vehicle, actions, link_timeout)
        if on_exit == "hold" and vehicle.telemetry.flying:
            if vehicle.telemetry.custom_mode != GUIDED:
                actions.append(f"left it in {vehicle.telemetry.mode}")
                return _ending(vehicle, actions, "--on-exit hold left it flying")
            unconfirmed = _brake(stepper, vehicle, actions)
            if unconfirmed:
                return _ending(vehicle, actions, f"hold not confirmed: {unconfirmed}", True)
            return _ending(vehicle, actions, "--on-exit hold left it flying")
        if on_exit == "none" and not vehicle.down:
            return _ending(vehicle, actions, "--on-exit none left it as it was")
        return _ending(vehicle, actions, "")
    except Interrupted as exc:
        actions.append(f"stopped waiting ({exc.name})")
        return _ending(vehicle, actions, f"stopped waiting ({exc.name})")


class _Stepper:
    """Steps the executive (recording everything) and tells how long that took."""

    def __init__(self, executive: Executive) -> None:
        self.executive = executive

    @property
    def now(self) -> float:
        return self.executive.now_s

    def step(self) -> None:
        with contextlib.suppress(LinkTimeout):  # the ending watches the link itself
            self.executive.step()


def _tell(command: object) -> str:
    try:
        return str(command())  # type: ignore[operator]
    except VehicleCommandError as exc:
        return f"failed: {exc}"


def _inhibit_all(executive: Executive, api: MissionAPI, actions: list[str]) -> None:
    for name in executive.active_behaviors:
        api.inhibit_behavior(name)
        actions.append(f"inhibited {name}")


def _wait_for_link(stepper: _Stepper, vehicle: MavlinkVehicle, link_timeout: float) -> bool:
    """Step until the link is back (True) or it was silent `link_timeout` s (False)."""
    while vehicle.link_lost:
        if vehicle.silent_for() > link_timeout:
            return False
        stepper.step()
    return True


def _land(
    stepper: _Stepper, vehicle: MavlinkVehicle, actions: list[str], link_timeout: float
) -> Ending:
    commanded = False
    deadline = bound = math.inf
    since = ""  # what the landing's bound counts from
    unbraked = ""  # why a brake before the landing was not seen to stop
    on_ground = False  # armed on the ground: the ending disarms it
    disarmed_at: float | None = None  # when that disarm was acknowledged
    # Heartbeats heard before the ending's last command: down must be said by a later one.
    before = -1
    while not (vehicle.down and vehicle.telemetry.heartbeats > before):
        if vehicle.link_lost:
            if not _wait_for_link(stepper, vehicle, link_timeout):
                return _ending(
                    vehicle,
                    actions,
                    f"link lost while landing, no heartbeat for {link_timeout:g} s",
                )
            continue
        if vehicle.telemetry.flying and not commanded:
            commanded = True
            if not (vehicle.descending or vehicle.in_commanded_mode):
                mode = vehicle.telemetry.mode
                return _ending(
                    vehicle,
                    actions,
                    f"{mode} was not commanded by aeroexec: a pilot or the autopilot has it",
                )
            moving = vehicle.telemetry.speed > STILL_SPEED
            if vehicle.telemetry.custom_mode in (GUIDED, BRAKE) and (moving or unbraked):
                # Brake first, in BRAKE (the hardest stop ArduCopter makes): a LAND at
                # speed is braked during the descent, and the vehicle touches down
                # metres on (SITL at 7.7 m/s: 11-19 m).
                # Not seen to stop, it is landed all the same (the safest thing left),
                # and the ending says so.
                unbraked = _brake(stepper, vehicle, actions, BRAKE)
                if vehicle.link_lost:
                    # Once the link is back (and --failsafe has run) the landing starts
                    # over from what the autopilot then says: left in BRAKE (failsafe
                    # hold), it would otherwise hold there, and fly wait, for ever.
                    commanded = False
                    continue
            beats = before = vehicle.telemetry.heartbeats
            action = _tell(vehicle.bring_down)
            mode = vehicle.telemetry.custom_mode
            if action.startswith("left it in ") and vehicle.telemetry.heard_mode != mode:
                # Already descending as far as we know (a failsafe's LAND or RTL, just
                # acknowledged): the autopilot's HEARTBEAT must say so too.
                if _see_mode(stepper, vehicle, mode, beats) is None:
                    actions.append(f"{action}: NOT seen in it within {MODE_BOUND_S:g} s")
                    return _ending(
                        vehicle,
                        actions,
                        f"{vehicle.telemetry.mode} not confirmed: the autopilot says "
                        f"{vehicle.telemetry.heard_mode_name}",
                        True,
                    )
                actions.append(action)
                since = f"{mode_name(mode)} was seen"
            elif action != "switched to LAND":
                # Left in a mode already heard (LAND, RTL), or LAND failed.
                actions.append(action)
                left = action.startswith("left it in ")
                since = f"{mode_name(mode)} was seen" if left else "LAND failed"
            else:
                seen = _see_mode(stepper, vehicle, LAND, beats)
                if seen is None:
                    actions.append(f"switched to LAND: NOT seen in LAND within {MODE_BOUND_S:g} s")
                    return _ending(
                        vehicle,
                        actions,
                        f"LAND not confirmed: the autopilot still says "
                        f"{vehicle.telemetry.heard_mode_name} {MODE_BOUND_S:g} s after it "
                        "acknowledged LAND",
                        True,
                    )
                actions.append(f"switched to LAND: seen in LAND {seen:.1f} s later")
                since = "LAND was seen"
            bound = _landing_bound(vehicle)
            deadline = stepper.now + bound
        elif not vehicle.telemetry.flying and vehicle.telemetry.armed and not commanded:
            # Armed on the ground (a take-off that failed after arming): disarm it. The
            # acknowledgement is not the disarm: the HEARTBEAT must say so.
            commanded = on_ground = True
            before = vehicle.telemetry.heartbeats
            try:
                vehicle.disarm()
                disarmed_at = stepper.now
                since = "it acknowledged the disarm"
            except VehicleCommandError as exc:
                actions.append(f"disarm failed: {exc}")
                since = "the disarm failed"
            bound = LANDING_MARGIN_S
            deadline = stepper.now + bound
        if stepper.now > deadline:
            said = _landed_as_said(vehicle)
            if on_ground:
                actions.append(f"NOT seen disarmed within {bound:.0f} s: {said}")
                return _ending(
                    vehicle,
                    actions,
                    f"disarm not confirmed: the autopilot still says {said} {bound:.0f} s "
                    f"after {since}",
                    True,
                )
            actions.append(f"NOT seen landed and disarmed within {bound:.0f} s: {said}")
            return _ending(
                vehicle,
                actions,
                f"landing not confirmed: the autopilot still says {said} {bound:.0f} s after "
                f"{since}",
                True,
            )
        stepper.step()
    if disarmed_at is not None:
        actions.append(f"disarmed: seen disarmed {stepper.now - disarmed_at:.1f} s later")
    if unbraked:
        return _ending(vehicle, actions, f"brake before landing not confirmed: {unbraked}", True)
    return _ending(vehicle, actions, "")


def _landed_as_said(vehicle: MavlinkVehicle) -> str:
    """What the autopilot last said of its landing: "landing, armed"."""
    t = vehicle.telemetry
    return f"{t.landed_state_name}, {'armed' if t.heard_armed else 'disarmed'}"


def _see_mode(stepper: _Stepper, vehicle: MavlinkVehicle, mode: int, beats: int) -> float | None:
    """Seconds until a HEARTBEAT after the `beats`-th said `mode`; None if none did
    within `MODE_BOUND_S` (or the link was lost)."""
    start = stepper.now
    while not vehicle.link_lost:
        t = vehicle.telemetry
        if t.heartbeats > beats and t.heard_mode == mode:
            return stepper.now - start
        if stepper.now - start > MODE_BOUND_S:
            return None
        stepper.step()
    return None


def _brake(
    stepper: _Stepper, vehicle: MavlinkVehicle, actions: list[str], mode: int = GUIDED
) -> str:
    """Brake and wait until the autopilot's own telemetry shows it holding: a HEARTBEAT
    in `mode` and `STILL_FOR_S` of LOCAL_POSITION_NED slower than `STILL_SPEED`, all
    after the brake. In GUIDED the brake is a zero-velocity setpoint (re-sent, as no
    setpoint is acknowledged), stopping at the autopilot's waypoint acceleration
    (WPNAV_ACCEL, 2.5 m/s2); in BRAKE, ArduCopter's own mode for stopping as fast as it
    can (7.5 m/s2). The action says what was seen; "" when the hold was confirmed, else
    why not."""
    name = mode_name(mode)
    if mode != GUIDED:
        try:
            vehicle.switch_mode(mode)
        except VehicleCommandError as exc:
            actions.append(f"braked: NOT seen holding: {exc}")
            return str(exc)
    t = vehicle.telemetry
    start = stepper.now
    bound = BRAKE_BOUND_S + BRAKE_PER_SPEED_S * t.speed
    beats, positions = t.heartbeats, t.positions
    still_since: float | None = None
    last_brake = -math.inf
    while True:
        if vehicle.link_lost:
            problem = "the link was lost while braking"
            break
        if t.heartbeats > beats and t.heard_mode != mode:
            problem = f"the autopilot switched to {t.heard_mode_name} while braking"
            break
        fresh = t.heartbeats > beats and t.positions > positions
        if fresh and t.speed <= STILL_SPEED:
            still_since = stepper.now if still_since is None else still_since
            if stepper.now - still_since >= STILL_FOR_S:
                x, y, z = vehicle.state().position
                actions.append(
                    f"braked: seen holding in {name} at ({x:.2f}, {y:.2f}, {z:.2f}) m, "
                    f"{t.speed:.2f} m/s, {stepper.now - start:.1f} s after the brake"
                )
                return ""
        else:
            still_since = None
        if stepper.now - start > bound:
            problem = (
                f"still {t.speed:.2f} m/s in {t.heard_mode_name} {bound:.0f} s after the brake"
            )
            break
        if mode == GUIDED and stepper.now - last_brake >= REBRAKE_S and t.speed > STILL_SPEED:
            last_brake = stepper.now
            try:
                vehicle.hold_here()
            except VehicleCommandError as exc:
                problem = f"the brake failed: {exc}"
                break
        stepper.step()
    actions.append(f"braked: NOT seen holding: {problem}")
    return problem


def _landing_bound(vehicle: MavlinkVehicle) -> float:
    x, y, z = vehicle.state().position
    return LANDING_MARGIN_S + max(z, 0.0) / LANDING_RATE + math.hypot(x, y) / RETURN_RATE


def _ending(
    vehicle: MavlinkVehicle, actions: list[str], problem: str, unconfirmed: bool = False
) -> Ending:
    """The ending as last seen; `unconfirmed`: `problem` is a step not seen, which stays
    a problem even if the vehicle is down."""
    down = vehicle.down and not vehicle.link_lost and vehicle.target is not None
    if down and not unconfirmed:
        problem = ""
    elif not problem:
        problem = "it was never seen landed and disarmed"
    return Ending(down=down, last_seen=vehicle.last_seen(), actions=tuple(actions), problem=problem)
