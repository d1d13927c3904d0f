"""`SimVehicle`: a deterministic kinematic quadrotor.

It is a point mass with a heading, driven by a position/velocity controller that
respects the world's speed, acceleration and yaw-rate limits. It is not a flight
dynamics model: it exists so missions, behaviors and recordings can be exercised
reproducibly. Determinism: time is an integer count of nanoseconds advanced only by
`step`, every `step` is split into equal fixed sub-steps, the arithmetic is plain
floats in a fixed order, and randomness comes only from `random.Random(seed)`.
"""

from __future__ import annotations

import dataclasses
import math
import random
from typing import Literal

from aeroexec.vehicles.base import (
    FLIP_DIRECTIONS,
    Vec3,
    VehicleCommandError,
    VehicleState,
)
from aeroexec.vehicles.world import RandomFailure, ScheduledFailure, World, default_world

NS_PER_S = 1_000_000_000
#: Longest integration sub-step; a 0.1 s executive tick is integrated in 5 of them so the
#: acceleration limit and the braking curve are followed closely.
MAX_SUBSTEP = 0.02
#: Fraction of the acceleration limit the position controller plans to brake with; the
#: margin keeps the proportional tail's deceleration (2 * this * limit) under the limit.
BRAKING_SHARE = 0.4
#: Proportional gain (1/s) of the final approach to a setpoint.
APPROACH_GAIN = 1.5
#: Within this distance (m) and below this speed (m/s) the vehicle is "at" its setpoint.
SETTLE_DISTANCE = 0.002
SETTLE_SPEED = 0.01
LANDING_SPEED = 0.5  # m/s, descent rate of `land()`
FLIP_DURATION = 1.0  # s
MIN_FLIP_ALTITUDE = 0.5  # m: below this the vehicle refuses to flip at all

Mode = Literal["idle", "position", "velocity", "brake", "land", "flip"]


def _wrap(angle: float) -> float:
    """Angle in radians into (-pi, pi]."""
    wrapped = math.fmod(angle + math.pi, 2.0 * math.pi)
    if wrapped <= 0.0:
        wrapped += 2.0 * math.pi
    return wrapped - math.pi


class SimVehicle:
    """The built-in simulated vehicle (implements `aeroexec.vehicles.base.Vehicle`)."""

    kind = "sim"

    def __init__(self, world: World | None = None, *, seed: int | None = None) -> None:
        self.world = world if world is not None else default_world()
        limits = self.world.limits
        self._vh = limits.horizontal_speed
        self._vz = limits.vertical_speed
        self._acc = limits.acceleration
        self._yaw_rate = math.radians(limits.yaw_rate)
        self._t_ns = 0
        self._p = list(self.world.start)
        self._v = [0.0, 0.0, 0.0]
        self._yaw = _wrap(math.radians(self.world.start_yaw))
        self._yaw_sp = self._yaw
        self._battery = self.world.battery.initial
        self._armed = False
        self._mode: Mode = "idle"
        self._sp: Vec3 = self.world.start
        self._v_sp: Vec3 = (0.0, 0.0, 0.0)
        self._flip_left = 0.0
        self._fault = ""
        self._pending: list[ScheduledFailure] = list(self.world.failures)
        self._random: RandomFailure | None = self.world.random_failure
        # An explicit vehicle seed (the CLI's --seed) wins over the one in the world file.
        rng_seed = seed
        if rng_seed is None and self._random is not None:
            rng_seed = self._random.seed
        self._rng = random.Random(self.world.seed if rng_seed is None else rng_seed)
        self._injected: list[tuple[float, str]] = []
        # Faults that last (aeroexec/vehicles/faults.py): when each ends (ns), and what
        # the executive was told when the link went (its view stays there until it is back).
        self._link_until_ns: int | None = None
        self._stale: VehicleState | None = None
        self._position_until_ns: int | None = None
        self._estimate: tuple[float, float] = (0.0, 0.0)
        self._gust_until_ns: int | None = None
        self._wind: Vec3 = (0.0, 0.0, 0.0)

    # -- observation ---------------------------------------------------------------------
    @property
    def time(self) -> float:
        """Simulated seconds since the vehicle was created."""
        return self._t_ns / NS_PER_S

    @property
    def failures_injected(self) -> tuple[tuple[float, str], ...]:
        """(simulated time s, kind) of every failure injected so far, in order."""
        return tuple(self._injected)

    @property
    def airborne(self) -> bool:
        return self._p[2] > 0.0

    @property
    def link_lost(self) -> bool:
        return self._link_until_ns is not None

    @property
    def position_lost(self) -> bool:
        return self._position_until_ns is not None

    def state(self) -> VehicleState:
        if self._stale is not None:
            return self._stale
        return self._true_state()

    def _true_state(self) -> VehicleState:
        # The wind moves only a vehicle that flies (the ground holds the others).
        pushed = self._mode != "idle" and self._fault != "stuck_motor"
        wx, wy, wz = self._wind if pushed else (0.0, 0.0, 0.0)
        position = (self._p[0], self._p[1], self._p[2])
        fault = self._fault
        if self._position_until_ns is not None:
            # The altitude stays known (a barometer); the horizontal estimate is frozen.
            position = (self._estimate[0], self._estimate[1], self._p[2])
            fault = fault or "position_lost"
        return VehicleState(
            position=position,
            velocity=(self._v[0] + wx, self._v[1] + wy, self._v[2] + wz),
            yaw=self._yaw,
            battery=self._battery,
            flying=self._armed and self.airborne,
            armed=self._armed,
            fault=fault,
            maneuver="flip" if self._mode == "flip" else "",
        )

    def _sees(self, point: Vec3) -> bool:
        dx = point[0] - self._p[0]
        dy = point[1] - self._p[1]
        return dx * dx + dy * dy <= self.world.camera_range * self.world.camera_range

    def visible_markers(self) -> tuple[int, ...]:
        if self.link_lost:
            return ()  # the camera's images come over the link too
        return tuple(m.id for m in self.world.markers if self._sees(m.position))

    def visible_object(self) -> Vec3 | None:
        obj = self.world.object
        if obj is None or self.link_lost:
            return None
        where = obj.at(self.time)
        return where if self._sees(where) else None

    # -- commands ------------------------------------------------------------------------
    def _refuse_if_unable(
        self, command: str, *, in_air: bool = True, needs_position: bool = True
    ) -> None:
        if self.link_lost:
            raise VehicleCommandError(f"{command}: refused, the link is lost")
        if needs_position and self.position_lost:
            raise VehicleCommandError(f"{command}: refused, no position estimate")
        if self._fault == "stuck_motor":
            raise VehicleCommandError(f"{command}: refused, a motor is stuck")
        if self._mode == "flip":
            raise VehicleCommandError(f"{command}: refused, a flip is in progress")
        if in_air and not self.airborne:
            raise VehicleCommandError(f"{command}: refused, the vehicle is on the ground")

    def take_off(self, altitude: float) -> None:
        self._refuse_if_unable("take_off", in_air=False)
        if self.airborne:
            raise VehicleCommandError("take_off: refused, already flying")
        if self._battery <= 0.0:
            raise VehicleCommandError("take_off: refused, the battery is empty")
        if not (math.isfinite(altitude) and altitude > 0.0):
            raise VehicleCommandError(f"take_off: altitude must be positive, got {altitude}")
        self._armed = True
        self._position_mode((self._p[0], self._p[1], altitude))

    def land(self) -> None:
        self._refuse_if_unable("land", needs_position=False)
        self._mode = "land"
        self._sp = (self._p[0], self._p[1], 0.0)

    def go_to(self, x: float, y: float, z: float) -> None:
        self._refuse_if_unable("go_to")
        self._refuse_if_depleted("go_to")
        if not all(math.isfinite(c) for c in (x, y, z)):
            raise VehicleCommandError(f"go_to: not a position: ({x}, {y}, {z})")
        if z < 0.0:
            raise VehicleCommandError(f"go_to: z = {z:g} m is below the ground")
        self._position_mode((float(x), float(y), float(z)))

    def set_velocity(self, vx: float, vy: float, vz: float) -> None:
        self._refuse_if_unable("set_velocity")
        self._refuse_if_depleted("set_velocity")
        if not all(math.isfinite(c) for c in (vx, vy, vz)):
            raise VehicleCommandError(f"set_velocity: not a velocity: ({vx}, {vy}, {vz})")
        # Refuse rather than clamp: a behavior that waits for its speed would wait forever.
        horizontal = math.hypot(vx, vy)
        if horizontal > self._vh + 1e-9:
            raise VehicleCommandError(
                f"set_velocity: {horizontal:g} m/s exceeds the horizontal limit {self._vh:g} m/s"
            )
        if abs(vz) > self._vz + 1e-9:
            raise VehicleCommandError(
                f"set_velocity: {abs(vz):g} m/s exceeds the vertical limit {self._vz:g} m/s"
            )
        self._mode = "velocity"
        self._v_sp = (float(vx), float(vy), float(vz))

    def set_yaw(self, yaw: float) -> None:
        self._refuse_if_unable("set_yaw", needs_position=False)
        if not math.isfinite(yaw):
            raise VehicleCommandError(f"set_yaw: not an angle: {yaw}")
        self._yaw_sp = _wrap(float(yaw))

    def hover(self) -> None:
        if self.link_lost:
            raise VehicleCommandError("hover: refused, the link is lost")
        # Holding still is what a stuck or flipping vehicle does anyway: not an error.
        if self._fault == "stuck_motor" or self._mode == "flip":
            return
        if self.position_lost:
            raise VehicleCommandError("hover: refused, no position estimate (landing)")
        # Braking to a hover would stop the forced landing of an empty battery.
        self._refuse_if_depleted("hover")
        if not self.airborne:
            raise VehicleCommandError("hover: refused, the vehicle is on the ground")
        self._mode = "brake"
        self._yaw_sp = self._yaw

    def flip(self, direction: str) -> None:
        self._refuse_if_unable("flip")
        self._refuse_if_depleted("flip")
        if direction not in FLIP_DIRECTIONS:
            raise VehicleCommandError(
                f"flip: direction must be one of {', '.join(FLIP_DIRECTIONS)}, got {direction!r}"
            )
        if self._p[2] < MIN_FLIP_ALTITUDE:
            raise VehicleCommandError(
                f"flip: refused at {self._p[2]:.2f} m (needs {MIN_FLIP_ALTITUDE:g} m)"
            )
        # The flip is a scripted maneuver: the vehicle brakes, tumbles in place for
        # FLIP_DURATION, and comes out holding the position it started from.
        self._mode = "flip"
        self._flip_left = FLIP_DURATION
        self._sp = (self._p[0], self._p[1], self._p[2])
        self._yaw_sp = self._yaw

    def _refuse_if_depleted(self, command: str) -> None:
        if self._fault == "battery_empty":
            raise VehicleCommandError(f"{command}: refused, the battery is empty (landing)")

    def _position_mode(self, setpoint: Vec3) -> None:
        self._mode = "position"
        self._sp = setpoint

    # -- simulation ----------------------------------------------------------------------
    def step(self, dt: float) -> None:
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"step: dt must be a positive number of seconds, got {dt}")
        substeps = max(1, math.ceil(dt / MAX_SUBSTEP - 1e-9))
        h = dt / substeps
        for _ in range(substeps):
            self._integrate(h)
        self._drain(dt)
        self._t_ns += round(dt * NS_PER_S)
        self._expire()
        self._inject_failures(dt)
        if self._link_until_ns is not None and self._stale is None:
            # What the executive last heard, said with the fault from now on.
            self._stale = dataclasses.replace(self._true_state(), fault="link_lost")

    def _integrate(self, h: float) -> None:
        if self._fault == "stuck_motor" or self._mode == "idle":
            # A seized motor: the simulated aircraft stays exactly where it is.
            self._v = [0.0, 0.0, 0.0]
            return
        if self._mode == "flip":
            self._flip_left -= h
            target = self._velocity_toward(self._sp)
            if self._flip_left <= 1e-9:
                self._mode = "position"
        elif self._mode == "position":
            target = self._velocity_toward(self._sp)
        elif self._mode == "velocity":
            target = self._v_sp
        elif self._mode == "brake":
            target = (0.0, 0.0, 0.0)
        else:  # land: hold x, y and sink at the landing rate
            toward = self._velocity_toward((self._sp[0], self._sp[1], self._p[2]))
            target = (toward[0], toward[1], -min(LANDING_SPEED, self._vz))
        self._accelerate(target, h)
        wind = self._wind
        for i in range(3):
            self._p[i] += (self._v[i] + wind[i]) * h
        self._turn(h)
        self._settle()
        self._ground_contact()

    def _velocity_toward(self, setpoint: Vec3) -> Vec3:
        """The velocity that brings the vehicle to `setpoint` within the limits.

        Speed is the least of: the speed limit along the direction to go, the speed from
        which it can still brake at BRAKING_SHARE of the acceleration limit, and a
        proportional term that makes the final approach smooth instead of bang-bang.
        """
        ex = setpoint[0] - self._p[0]
        ey = setpoint[1] - self._p[1]
        ez = setpoint[2] - self._p[2]
        distance = math.sqrt(ex * ex + ey * ey + ez * ez)
        if distance < 1e-12:
            return (0.0, 0.0, 0.0)
        ux, uy, uz = ex / distance, ey / distance, ez / distance
        cap = math.inf
        horizontal = math.hypot(ux, uy)
        if horizontal > 0.0:
            cap = self._vh / horizontal
        if uz != 0.0:
            cap = min(cap, self._vz / abs(uz))
        speed = min(
            cap,
            math.sqrt(2.0 * BRAKING_SHARE * self._acc * distance),
            APPROACH_GAIN * distance,
        )
        return (ux * speed, uy * speed, uz * speed)

    def _accelerate(self, target: Vec3, h: float) -> None:
        # Moving straight toward the target velocity keeps every intermediate velocity
        # on the segment between two admissible ones, so the speed limits hold too.
        dx = target[0] - self._v[0]
        dy = target[1] - self._v[1]
        dz = target[2] - self._v[2]
        change = math.sqrt(dx * dx + dy * dy + dz * dz)
        allowed = self._acc * h
        if change > allowed:
            scale = allowed / change
            dx, dy, dz = dx * scale, dy * scale, dz * scale
        self._v = [self._v[0] + dx, self._v[1] + dy, self._v[2] + dz]

    def _turn(self, h: float) -> None:
        error = _wrap(self._yaw_sp - self._yaw)
        limit = self._yaw_rate * h
        if abs(error) <= limit:
            self._yaw = self._yaw_sp
        else:
            self._yaw = _wrap(self._yaw + math.copysign(limit, error))

    def _settle(self) -> None:
        """Snap onto a reached setpoint so 'stopped' means exactly zero velocity."""
        speed = math.sqrt(sum(v * v for v in self._v))
        if self._mode == "position":
            gap = math.dist(self._p, self._sp)
            if gap < SETTLE_DISTANCE and speed < SETTLE_SPEED:
                self._p = list(self._sp)
                self._v = [0.0, 0.0, 0.0]
        elif self._mode == "brake" and speed < 1e-9:
            self._v = [0.0, 0.0, 0.0]
            self._position_mode((self._p[0], self._p[1], self._p[2]))

    def _ground_contact(self) -> None:
        if self._p[2] > 0.0:
            return
        self._p[2] = 0.0
        if self._v[2] <= 0.0:
            # Touchdown (a landing, or flown into the ground): on the ground nothing moves,
            # and like real autopilots the vehicle disarms once it is down.
            self._v = [0.0, 0.0, 0.0]
            self._armed = False
            self._mode = "idle"

    def _drain(self, dt: float) -> None:
        model = self.world.battery
        endurance = model.flight_endurance if self._armed else model.idle_endurance
        self._battery = max(0.0, self._battery - dt / endurance)
        if self._battery == 0.0 and not self._fault:
            # An empty battery forces a landing; nothing else is accepted any more.
            self._fault = "battery_empty"
            if self.airborne:
                self._mode = "land"
                self._sp = (self._p[0], self._p[1], 0.0)

    def _expire(self) -> None:
        """End the faults whose time is up (a fault lasts until the step that reaches
        its end)."""
        now = self._t_ns
        if self._link_until_ns is not None and now >= self._link_until_ns:
            self._link_until_ns = None
            self._stale = None
        if self._position_until_ns is not None and now >= self._position_until_ns:
            self._position_until_ns = None
        if self._gust_until_ns is not None and now >= self._gust_until_ns:
            self._gust_until_ns = None
            self._wind = (0.0, 0.0, 0.0)

    def _inject_failures(self, dt: float) -> None:
        while self._pending and round(self._pending[0].at * NS_PER_S) <= self._t_ns:
            self._fail(self._pending.pop(0))
        spec = self._random
        if spec is None or spec.rate <= 0.0:
            return
        # One draw per step until it strikes, so the failure time depends only on the
        # seed and the step sizes, never on what the vehicle was doing.
        if self._rng.random() < 1.0 - math.exp(-spec.rate * dt):
            self._random = None
            self._fail(spec)

    def _until(self, failure: ScheduledFailure | RandomFailure) -> int:
        return self._t_ns + round(failure.value("duration") * NS_PER_S)

    def _fail(self, failure: ScheduledFailure | RandomFailure) -> None:
        kind = failure.kind
        self._injected.append((self.time, kind))
        if kind == "low_battery":
            self._battery = min(self._battery, failure.value("level"))
        elif kind == "stuck_motor":
            self._fault = "stuck_motor"
            self._v = [0.0, 0.0, 0.0]
        elif kind == "lost_link":
            self._link_until_ns = max(self._link_until_ns or 0, self._until(failure))
        elif kind == "lost_position":
            if self._position_until_ns is None:
                self._estimate = (self._p[0], self._p[1])
            self._position_until_ns = max(self._position_until_ns or 0, self._until(failure))
            if self.airborne and not self._fault and self._mode != "land":
                # The autopilot's failsafe: without a position it can only come down.
                self._mode = "land"
                self._sp = (self._p[0], self._p[1], 0.0)
        elif kind == "wind_gust":
            speed = failure.value("speed")
            toward = math.radians(failure.value("direction"))
            self._wind = (speed * math.cos(toward), speed * math.sin(toward), 0.0)
            self._gust_until_ns = self._until(failure)
