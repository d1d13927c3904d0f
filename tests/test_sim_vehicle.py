"""The simulated quadrotor: limits, convergence, ground contact, battery, failures,
determinism."""

from __future__ import annotations

import dataclasses
import math
import random

import pytest

from aeroexec.vehicles import SimVehicle, Vehicle, VehicleCommandError, VehicleState
from aeroexec.vehicles.world import (
    BatteryModel,
    Limits,
    Marker,
    MovingObject,
    RandomFailure,
    ScheduledFailure,
    World,
    default_world,
)

DT = 0.1
EPS = 1e-9


def run(vehicle: SimVehicle, seconds: float, dt: float = DT) -> list[VehicleState]:
    states = []
    for _ in range(round(seconds / dt)):
        vehicle.step(dt)
        states.append(vehicle.state())
    return states


def airborne(world: World | None = None, altitude: float = 1.0) -> SimVehicle:
    vehicle = SimVehicle(world or World())
    vehicle.take_off(altitude)
    run(vehicle, 5.0)
    return vehicle


def test_implements_the_vehicle_protocol() -> None:
    vehicle = SimVehicle()
    assert isinstance(vehicle, Vehicle)
    assert vehicle.kind == "sim"


def test_take_off_arms_climbs_and_holds_the_altitude() -> None:
    vehicle = SimVehicle(World())
    start = vehicle.state()
    assert (start.flying, start.armed, start.position) == (False, False, (0.0, 0.0, 0.0))
    vehicle.take_off(1.2)
    assert vehicle.state().armed and not vehicle.state().flying  # armed, not yet off the ground
    states = run(vehicle, 5.0)
    assert states[0].flying
    assert states[-1].position == (0.0, 0.0, 1.2)
    assert states[-1].velocity == (0.0, 0.0, 0.0)
    # Climbing at 1 m/s at most, 1.2 m cannot be done in less than 1.2 s.
    assert states[10].altitude < 1.2


def limits_hold(states: list[VehicleState], limits: Limits, dt: float) -> None:
    previous = None
    for state in states:
        vx, vy, vz = state.velocity
        assert math.hypot(vx, vy) <= limits.horizontal_speed + EPS
        assert abs(vz) <= limits.vertical_speed + EPS
        assert state.altitude >= 0.0
        if previous is not None:
            dv = math.dist(state.velocity, previous.velocity)
            assert dv <= limits.acceleration * dt + EPS
            turn = abs(math.remainder(state.yaw - previous.yaw, 2 * math.pi))
            assert turn <= math.radians(limits.yaw_rate) * dt + EPS
        previous = state


@pytest.mark.parametrize("limits", [Limits(), Limits(1.0, 0.5, 1.0, 45.0)])
def test_limits_are_respected_at_every_step(limits: Limits) -> None:
    vehicle = SimVehicle(World(limits=limits))
    states = [vehicle.state()]
    vehicle.take_off(2.0)
    states += run(vehicle, 3.0)
    vehicle.go_to(20.0, -15.0, 6.0)
    vehicle.set_yaw(math.radians(170))
    states += run(vehicle, 4.0)
    vehicle.go_to(-5.0, 5.0, 1.0)  # reverse while fast: the hardest case for the limits
    vehicle.set_yaw(math.radians(-170))
    states += run(vehicle, 6.0)
    vehicle.set_velocity(limits.horizontal_speed, 0.0, -limits.vertical_speed)
    states += run(vehicle, 2.0)
    vehicle.hover()
    states += run(vehicle, 4.0)
    limits_hold(states, limits, DT)
    # The run must actually have pushed against the limits, or the test proves nothing.
    assert max(math.hypot(s.velocity[0], s.velocity[1]) for s in states) == pytest.approx(
        limits.horizontal_speed
    )
    assert max(abs(s.velocity[2]) for s in states) == pytest.approx(limits.vertical_speed)


def test_go_to_converges_and_stops_without_overshoot() -> None:
    vehicle = airborne(World())
    start = vehicle.state().position
    goal = (3.0, 5.5, 1.3)
    length = math.dist(start, goal)
    direction = [(g - s) / length for g, s in zip(goal, start, strict=True)]
    vehicle.go_to(*goal)
    states = run(vehicle, 20.0)
    along = [
        sum((p - s) * u for p, s, u in zip(st.position, start, direction, strict=True))
        for st in states
    ]
    assert max(along) - length < 0.03
    assert states[-1].position == goal
    assert states[-1].velocity == (0.0, 0.0, 0.0)
    # At cruise it really flies at the horizontal limit, so arrival takes a few seconds.
    arrival = next(i for i, st in enumerate(states) if math.dist(st.position, goal) < 0.05)
    assert 3.0 < arrival * DT < 10.0


def test_commands_refused_where_a_drone_would_refuse_them() -> None:
    grounded = SimVehicle(World())
    for command in (
        lambda: grounded.go_to(1.0, 1.0, 1.0),
        lambda: grounded.set_velocity(1.0, 0.0, 0.0),
        lambda: grounded.set_yaw(1.0),
        grounded.land,
        grounded.hover,
        lambda: grounded.flip("FRONT"),
    ):
        with pytest.raises(VehicleCommandError, match="on the ground"):
            command()
    with pytest.raises(VehicleCommandError, match="altitude must be positive"):
        grounded.take_off(0.0)

    flying = airborne(World())
    with pytest.raises(VehicleCommandError, match="already flying"):
        flying.take_off(1.0)
    with pytest.raises(VehicleCommandError, match="horizontal limit 2 m/s"):
        flying.set_velocity(3.0, 0.0, 0.0)
    with pytest.raises(VehicleCommandError, match="vertical limit 1 m/s"):
        flying.set_velocity(0.0, 0.0, -1.5)
    with pytest.raises(VehicleCommandError, match="below the ground"):
        flying.go_to(0.0, 0.0, -1.0)
    with pytest.raises(VehicleCommandError, match="direction"):
        flying.flip("SIDEWAYS")
    low = airborne(World(), altitude=0.3)
    with pytest.raises(VehicleCommandError, match=r"refused at 0\.30 m"):
        low.flip("FRONT")


def test_land_descends_and_disarms_on_touchdown() -> None:
    vehicle = airborne(World(), altitude=2.0)
    vehicle.land()
    states = run(vehicle, 6.0)
    touchdown = next(i for i, st in enumerate(states) if not st.armed)
    # 2 m at 0.5 m/s: about four seconds, not a drop.
    assert 3.8 <= touchdown * DT <= 4.8
    after = states[touchdown:]
    assert all(st.position[2] == 0.0 and st.velocity == (0.0, 0.0, 0.0) for st in after)
    assert not any(st.flying for st in after)
    assert all(st.flying for st in states[: touchdown - 1])


def test_flying_down_into_the_ground_stops_on_it() -> None:
    vehicle = airborne(World(), altitude=0.5)
    vehicle.set_velocity(1.0, 0.0, -1.0)
    states = run(vehicle, 3.0)
    assert min(st.altitude for st in states) == 0.0  # never below
    final = states[-1]
    assert final.velocity == (0.0, 0.0, 0.0) and not final.flying and not final.armed
    x = final.position[0]
    run(vehicle, 1.0)
    assert vehicle.state().position[0] == x  # on the ground nothing slides


def test_hover_brakes_then_holds_where_it_stopped() -> None:
    vehicle = airborne(World())
    vehicle.set_velocity(2.0, 0.0, 0.0)
    run(vehicle, 3.0)
    x0 = vehicle.state().position[0]
    vehicle.hover()
    states = run(vehicle, 4.0)
    # Braking from 2 m/s at 2 m/s² takes 1 m; it must neither stop dead nor drift on.
    assert states[-1].position[0] - x0 == pytest.approx(1.0, abs=0.1)
    assert states[-1].velocity == (0.0, 0.0, 0.0)
    assert states[-1].position == states[-10].position


def test_yaw_turns_the_short_way_at_the_rate_limit() -> None:
    vehicle = airborne(World())
    vehicle.set_yaw(math.radians(-90))
    run(vehicle, 0.5)
    assert math.degrees(vehicle.state().yaw) == pytest.approx(-45.0)
    run(vehicle, 0.6)
    assert math.degrees(vehicle.state().yaw) == pytest.approx(-90.0)
    vehicle.set_yaw(math.radians(170))  # from -90 the short way is through -180
    run(vehicle, 0.5)
    assert math.degrees(vehicle.state().yaw) == pytest.approx(-135.0)


def test_flip_is_a_one_second_maneuver_ending_where_it_started() -> None:
    vehicle = airborne(World(), altitude=1.5)
    start = vehicle.state().position
    vehicle.flip("LEFT")
    with pytest.raises(VehicleCommandError, match="flip is in progress"):
        vehicle.go_to(1.0, 1.0, 1.0)
    maneuvers = [st.maneuver for st in run(vehicle, 1.5)]
    assert maneuvers[:9] == ["flip"] * 9 and maneuvers[10:] == [""] * 5
    assert vehicle.state().position == start


def test_battery_drains_faster_in_flight() -> None:
    grounded = SimVehicle(World())
    run(grounded, 60.0)
    flying = airborne(World())
    before = flying.state().battery
    run(flying, 60.0)
    assert grounded.state().battery == pytest.approx(1.0 - 60.0 / 7200.0)
    assert before - flying.state().battery == pytest.approx(60.0 / 1200.0)


def test_empty_battery_forces_a_landing() -> None:
    world = World(battery=BatteryModel(initial=0.01, flight_endurance=1200.0))
    vehicle = airborne(world, altitude=1.0)
    states = run(vehicle, 12.0)
    assert vehicle.state().battery == 0.0
    assert vehicle.state().fault == "battery_empty"
    assert not vehicle.state().armed and vehicle.state().altitude == 0.0
    assert any(st.flying for st in states)  # it did fly until the charge ran out
    with pytest.raises(VehicleCommandError, match="battery is empty"):
        vehicle.take_off(1.0)


def test_an_empty_battery_landing_cannot_be_turned_into_a_hover() -> None:
    world = World(battery=BatteryModel(initial=0.01, flight_endurance=1200.0))
    vehicle = airborne(world, altitude=3.0)
    run(vehicle, 7.5)  # 12 s of charge in all: empty now, and landing
    assert vehicle.state().fault == "battery_empty" and vehicle.state().flying
    with pytest.raises(VehicleCommandError, match="battery is empty"):
        vehicle.hover()
    run(vehicle, 8.0)
    assert not vehicle.state().flying and vehicle.state().altitude == 0.0


def test_scheduled_failures_strike_at_their_time() -> None:
    world = World(
        failures=(ScheduledFailure("low_battery", 3.0), ScheduledFailure("stuck_motor", 5.0))
    )
    vehicle = SimVehicle(world)
    vehicle.take_off(1.0)
    states = run(vehicle, 4.0)
    assert states[28].battery > 0.9 and states[29].battery == pytest.approx(0.10)  # t = 3.0
    vehicle.go_to(10.0, 0.0, 1.0)
    states = run(vehicle, 2.0)
    assert states[8].fault == "" and states[9].fault == "stuck_motor"  # t = 5.0
    frozen = states[9].position
    assert states[8].speed > 0.5  # it was on its way when the motor seized
    assert states[-1].position == frozen and states[-1].velocity == (0.0, 0.0, 0.0)
    with pytest.raises(VehicleCommandError, match="motor is stuck"):
        vehicle.go_to(0.0, 0.0, 1.0)
    vehicle.hover()  # holding still is what it does anyway: accepted
    assert vehicle.failures_injected == ((3.0, "low_battery"), (5.0, "stuck_motor"))


def command_sequence(vehicle: SimVehicle) -> list[VehicleState]:
    states: list[VehicleState] = []
    vehicle.take_off(1.0)
    for seconds, command in (
        (3.0, lambda: vehicle.go_to(4.0, -2.0, 2.0)),
        (2.0, lambda: vehicle.set_yaw(2.0)),
        (2.0, lambda: vehicle.set_velocity(0.5, 1.0, 0.2)),
        (20.0, vehicle.hover),
        (5.0, vehicle.land),
    ):
        states += run(vehicle, seconds)
        try:
            command()
        except VehicleCommandError:
            states.append(vehicle.state())
    return states + run(vehicle, 5.0)


def random_world(seed: int) -> World:
    return World(random_failure=RandomFailure("stuck_motor", rate=0.1, seed=seed))


def test_same_world_and_seed_give_identical_states() -> None:
    random.seed(1)
    first = SimVehicle(random_world(7))
    a = command_sequence(first)
    random.seed(2)  # the global generator must play no part
    second = SimVehicle(random_world(7))
    b = command_sequence(second)
    assert a == b
    assert first.failures_injected == second.failures_injected != ()


def test_another_random_failure_seed_changes_the_failure_time() -> None:
    times = set()
    for seed in (7, 8):
        vehicle = SimVehicle(random_world(seed))
        command_sequence(vehicle)
        times.add(vehicle.failures_injected[0][0])
    assert len(times) == 2


def test_vehicle_seed_overrides_the_world_seed() -> None:
    world = dataclasses.replace(random_world(7), random_failure=RandomFailure("low_battery", 0.1))
    injected = []
    for seed in (None, 3, 3):
        vehicle = SimVehicle(world, seed=seed)
        run(vehicle, 60.0)
        injected.append(vehicle.failures_injected)
    assert injected[1] == injected[2] != injected[0]


def test_camera_sees_markers_within_range_in_ascending_order() -> None:
    world = World(
        markers=(Marker(2, (0.0, 3.9, 5.0)), Marker(5, (1.0, 0.0, 0.0)), Marker(7, (4.1, 0, 1))),
        camera_range=4.0,
    )
    vehicle = SimVehicle(world)
    assert vehicle.visible_markers() == (2, 5)  # range is horizontal: height does not matter
    vehicle.take_off(1.0)
    run(vehicle, 3.0)
    vehicle.go_to(3.0, 0.0, 1.0)
    run(vehicle, 8.0)
    assert vehicle.visible_markers() == (5, 7)


def test_the_object_moves_linearly_and_is_seen_only_in_range() -> None:
    world = World(object=MovingObject((2.0, 0.0, 0.0), (1.0, 0.0, 0.0)), camera_range=4.0)
    vehicle = SimVehicle(world)
    assert vehicle.visible_object() == (2.0, 0.0, 0.0)
    run(vehicle, 1.5)
    assert vehicle.visible_object() == pytest.approx((3.5, 0.0, 0.0))
    run(vehicle, 1.0)
    assert vehicle.visible_object() is None  # 4.5 m away


def test_default_world_route_passes_the_markers() -> None:
    vehicle = SimVehicle(default_world())
    assert vehicle.visible_markers() == (1,)
    vehicle.take_off(1.5)
    run(vehicle, 4.0)
    vehicle.go_to(3.0, 5.5, 1.3)
    run(vehicle, 12.0)
    assert vehicle.visible_markers() == (2, 3, 4)


@pytest.mark.parametrize("dt", [0.0, -0.1, math.nan])
def test_step_refuses_a_bad_dt(dt: float) -> None:
    with pytest.raises(ValueError, match="dt"):
        SimVehicle(World()).step(dt)
