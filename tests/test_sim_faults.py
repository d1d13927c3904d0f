"""The fault kinds that last (issue 26): a lost link, a lost position estimate, a wind gust;
their registry, their parameters in world files, and what the simulated vehicle does."""

from __future__ import annotations

import dataclasses
import math

import pytest

from aeroexec.errors import InjectionError, WorldError
from aeroexec.executive.beliefs import Beliefs
from aeroexec.executive.beliefs_feed import update_beliefs
from aeroexec.vehicles import SimVehicle, VehicleCommandError, VehicleState
from aeroexec.vehicles.faults import FAULT_KINDS, KIND_NAMES, parse_fault
from aeroexec.vehicles.world import FAILURE_KINDS, ScheduledFailure, World, parse_world

DT = 0.1


def run(vehicle: SimVehicle, seconds: float) -> list[VehicleState]:
    states = []
    for _ in range(round(seconds / DT)):
        vehicle.step(DT)
        states.append(vehicle.state())
    return states


def flying_with(*failures: ScheduledFailure) -> SimVehicle:
    """Airborne at 1 m at t = 5 s, with `failures` scheduled."""
    vehicle = SimVehicle(World(failures=failures))
    vehicle.take_off(1.0)
    run(vehicle, 5.0)
    return vehicle


def test_the_registry_keeps_the_old_kinds_and_names_every_parameter_with_a_default() -> None:
    assert KIND_NAMES[:2] == ("low_battery", "stuck_motor")
    assert set(KIND_NAMES) >= {"lost_link", "lost_position", "wind_gust"}
    assert FAILURE_KINDS == KIND_NAMES  # the world files read the same registry
    for kind in FAULT_KINDS.values():
        for parameter in kind.parameters:
            assert parameter.minimum <= parameter.default <= parameter.maximum
            assert parameter.unit and parameter.meaning


def test_a_lost_link_refuses_commands_and_freezes_what_the_executive_sees() -> None:
    vehicle = flying_with(ScheduledFailure("lost_link", 5.5, duration=2.0))
    vehicle.go_to(5.0, 0.0, 1.0)
    states = run(vehicle, 0.5)
    lost = states[-1]
    assert lost.fault == "link_lost" and states[-2].fault == ""
    with pytest.raises(VehicleCommandError, match="link is lost"):
        vehicle.go_to(0.0, 0.0, 1.0)
    with pytest.raises(VehicleCommandError, match="link is lost"):
        vehicle.hover()
    assert vehicle.visible_markers() == ()
    during = run(vehicle, 1.9)
    # The executive hears nothing new while the vehicle keeps flying its last command.
    assert all(s == lost for s in during)
    after = run(vehicle, 0.1)[-1]
    assert after.fault == "" and after.position[0] > lost.position[0] + 2.0
    vehicle.go_to(0.0, 0.0, 1.0)  # accepted again


def test_a_lost_position_lands_the_vehicle_and_withdraws_the_position_belief() -> None:
    vehicle = flying_with(ScheduledFailure("lost_position", 5.5))  # default: 5 s
    vehicle.go_to(3.0, 0.0, 1.0)
    states = run(vehicle, 0.5)
    lost = states[-1]
    assert lost.fault == "position_lost"
    with pytest.raises(VehicleCommandError, match="no position estimate"):
        vehicle.go_to(0.0, 0.0, 1.0)
    beliefs = Beliefs()
    update_beliefs(beliefs, states[-2])
    assert beliefs.holds("position(self, (?X, ?Y, ?Z))")
    update_beliefs(beliefs, lost)
    assert not beliefs.holds("position(self, (?X, ?Y, ?Z))")
    later = run(vehicle, 3.0)
    # The horizontal estimate is frozen, the altitude is still measured: it comes down.
    assert later[-1].position[:2] == lost.position[:2]
    assert later[-1].altitude == 0.0 and not later[-1].armed
    assert run(vehicle, 2.0)[-1].fault == ""  # over after 5 s


def test_a_wind_gust_pushes_the_vehicle_toward_its_direction_then_it_comes_back() -> None:
    vehicle = flying_with(ScheduledFailure("wind_gust", 5.5, speed=4.0, direction=90.0))
    home = vehicle.state().position
    states = run(vehicle, 2.5)  # the default gust lasts 2 s
    pushed = max(s.position[1] - home[1] for s in states)
    assert pushed > 1.0  # north: 90 degrees counter-clockwise from east
    assert max(abs(s.position[0] - home[0]) for s in states) < 1e-9
    # Its ground velocity has the wind in it.
    assert states[3].speed == 0.0 and states[5].velocity[1] > 2.0
    back = run(vehicle, 10.0)[-1]
    assert math.dist(back.position, home) < 0.01


def test_a_gust_does_not_move_a_vehicle_on_the_ground() -> None:
    vehicle = SimVehicle(World(failures=(ScheduledFailure("wind_gust", 0.5, speed=10.0),)))
    states = run(vehicle, 2.0)
    assert all(s.position == (0.0, 0.0, 0.0) and s.speed == 0.0 for s in states)


def test_world_files_take_each_kinds_parameters_and_refuse_the_others_at_their_place() -> None:
    world = parse_world(
        "failures:\n"
        "  - {kind: lost_link, at: 3, duration: 1.5}\n"
        "  - {kind: wind_gust, at: 4, speed: 6, direction: 45}\n"
        "  - {kind: lost_position, at: 5}\n"
    )
    link, gust, position = world.failures
    assert link.value("duration") == 1.5
    assert (gust.value("speed"), gust.value("direction"), gust.value("duration")) == (6, 45, 2)
    assert position.value("duration") == 5.0  # the documented default
    with pytest.raises(WorldError) as caught:
        parse_world("failures:\n  - {kind: stuck_motor, at: 3, speed: 5}\n", "w.yaml")
    assert str(caught.value).startswith("w.yaml:2:39: error: ")
    assert "'speed' applies to wind_gust only" in str(caught.value)
    with pytest.raises(WorldError, match=r"w.yaml:2:40: .*duration \(s\) must be at least 0.1"):
        parse_world("failures:\n  - {kind: lost_link, at: 3, duration: 0}\n", "w.yaml")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("engine_fire", "unknown fault kind 'engine_fire' (known: low_battery, stuck_motor,"),
        ("stuck_motor:level=3", "stuck_motor has no parameter 'level' (its parameters: none)"),
        ("low_battery:lvl=3", "its parameters: level"),
        ("low_battery:level=300", "level must be at most 100, got 300"),
        ("wind_gust:speed=fast", "speed must be a number (m/s), got 'fast'"),
        ("lost_link:duration", "write duration=VALUE"),
    ],
)
def test_fault_specs_name_what_exists(text: str, message: str) -> None:
    with pytest.raises(InjectionError) as caught:
        parse_fault(text)
    assert message in str(caught.value)


def test_fault_specs_keep_what_was_given_and_default_the_rest() -> None:
    spec = parse_fault("wind_gust:direction=90,speed=5m/s")
    assert str(spec) == "wind_gust:direction=90,speed=5"
    assert spec.values() == {"speed": 5.0, "direction": 90.0, "duration": 2.0}
    assert parse_fault("low_battery").values() == {"level": 0.10}
    assert parse_fault("low_battery:level=15").values() == {"level": pytest.approx(0.15)}
    failure = ScheduledFailure("low_battery", 1.0, **parse_fault("low_battery:level=15").values())
    assert dataclasses.asdict(failure)["level"] == pytest.approx(0.15)
