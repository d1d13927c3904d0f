"""`MavSim` behaves like ArduCopter 4.5 SITL where the fast tests depend on it: the EKF
is not ready at once (no position, arming refused), the answers SITL gave to the same
commands, the overshoot of a position setpoint and the creep back, RTL."""

from __future__ import annotations

import math
import socket
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from aeroexec.mavlink.sim_peer import MavSim, MavSimConfig
from aeroexec.vehicles.base import VehicleCommandError
from aeroexec.vehicles.mavlink.vehicle import MavlinkConfig, MavlinkVehicle


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@contextmanager
def linked(**sim: Any) -> Iterator[tuple[MavSim, MavlinkVehicle]]:
    """A MavSim (5x speed, 10 Hz heartbeats) and a vehicle talking to it over UDP."""
    port = free_udp_port()
    vehicle = MavlinkVehicle(
        MavlinkConfig(url=f"udpin:127.0.0.1:{port}", connect_timeout=5.0, ack_timeout=0.5)
    )
    settings: dict[str, Any] = {"speed_factor": 5.0, "heartbeat_hz": 10.0}
    settings.update(sim)
    peer = MavSim(MavSimConfig(url=f"udpout:127.0.0.1:{port}", **settings))
    stop = threading.Event()
    thread = threading.Thread(target=peer.run, args=(stop.is_set,), daemon=True)
    thread.start()
    try:
        yield peer, vehicle
    finally:
        stop.set()
        thread.join(5)
        peer.close()
        vehicle.close()


def step_until(vehicle: MavlinkVehicle, done: Any, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while not done():
        if time.monotonic() > deadline:
            return False
        vehicle.step(0.02)
        time.sleep(0.02)
    return True


def test_no_position_and_no_arming_until_the_ekf_is_ready() -> None:
    with linked(ekf_delay=2.0) as (_, vehicle):  # 2 vehicle seconds = 0.4 s at 5x
        started = time.monotonic()
        texts: list[str] = []
        vehicle.tap = lambda topic, data: texts.append(data["message"]) if topic == "log" else None
        assert step_until(vehicle, lambda: vehicle.target is not None, 3.0)
        with pytest.raises(VehicleCommandError, match="COMPONENT_ARM_DISARM refused: FAILED"):
            vehicle._arm()
        assert vehicle.telemetry.positions == 0
        vehicle.connect()  # waits for the first LOCAL_POSITION_NED
        ready = time.monotonic() - started
        vehicle._arm()
    assert 0.3 < ready < 2.0
    assert "autopilot: Arm: Need Position Estimate" in texts
    assert "autopilot: EKF3 IMU0 is using GPS" in texts


def test_the_answers_are_the_ones_sitl_gave() -> None:
    with linked(ekf_delay=0.0) as (sim, vehicle):
        vehicle.connect()
        # CONDITION_YAW is accepted on the ground, in any mode (it turns nothing there).
        vehicle._command(mavlink.MAV_CMD_CONDITION_YAW, (90.0, 0.0, 0.0, 0.0))
        # A message interval for a message id the autopilot does not know: DENIED.
        with pytest.raises(VehicleCommandError, match="SET_MESSAGE_INTERVAL refused: DENIED"):
            vehicle._command(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, (9999.0, 1e5))
        with pytest.raises(VehicleCommandError, match="NAV_TAKEOFF refused: FAILED"):
            vehicle._command(mavlink.MAV_CMD_NAV_TAKEOFF, (0, 0, 0, math.nan, 0, 0, 1.0))
        with pytest.raises(VehicleCommandError, match="DO_SET_MODE refused: FAILED"):
            vehicle._set_mode(99)
        vehicle._set_mode(4)
        vehicle._arm()
        with pytest.raises(VehicleCommandError, match="NAV_TAKEOFF refused: FAILED"):
            vehicle._command(mavlink.MAV_CMD_NAV_TAKEOFF, (0, 0, 0, math.nan, 0, 0, 0.0))
        vehicle._set_mode(6)  # RTL exists (on the ground it changes nothing)
    assert sim.mode == 6 and not sim.flying
    assert sim.sim.state().yaw == pytest.approx(0.0)  # the yaw command did not turn it


def test_a_position_setpoint_is_overshot_and_crept_back_to() -> None:
    with linked(ekf_delay=0.0, overshoot=0.15, creep_speed=0.05) as (sim, vehicle):
        vehicle.connect()
        vehicle.take_off(1.0)
        assert step_until(vehicle, lambda: abs(vehicle.state().altitude - 1.0) < 0.01, 5.0)
        vehicle.go_to(3.0, 0.0, 1.0)
        farthest = 0.0
        deadline = time.monotonic() + 8.0
        while time.monotonic() < deadline:
            vehicle.step(0.02)
            x = sim.sim.state().position[0]
            farthest = max(farthest, x)
            if farthest > 3.1 and abs(x - 3.0) < 0.005:
                break
            time.sleep(0.01)
        final = sim.sim.state().position[0]
    assert 3.12 < farthest <= 3.15  # it went (almost) 15 cm past the goal...
    assert final == pytest.approx(3.0, abs=0.005)  # ...and came back to it


def test_rtl_climbs_flies_home_and_lands() -> None:
    with linked(ekf_delay=0.0, rtl_altitude=3.0) as (sim, vehicle):
        vehicle.connect()
        vehicle.take_off(1.0)
        assert step_until(vehicle, lambda: vehicle.state().altitude > 0.95, 5.0)
        vehicle.go_to(0.0, 4.0, 1.0)
        assert step_until(vehicle, lambda: vehicle.state().position[1] > 3.9, 8.0)
        vehicle._set_mode(6)
        highest = 0.0

        def landed() -> bool:
            nonlocal highest
            highest = max(highest, sim.sim.state().position[2])
            return not sim.flying and not sim.armed

        assert step_until(vehicle, landed, 20.0)
        x, y, _ = sim.sim.state().position
    assert highest == pytest.approx(3.0, abs=0.05)
    assert math.hypot(x, y) < 0.05  # home: where it armed


def test_the_ground_station_beats_as_fast_as_the_autopilot() -> None:
    with linked(ekf_delay=0.0, heartbeat_hz=10.0) as (sim, vehicle):
        vehicle.connect()
        started = time.monotonic()
        before = sim.link.stats.received["HEARTBEAT"]
        assert step_until(vehicle, lambda: time.monotonic() - started > 1.0, 2.0)
        beats = sim.link.stats.received["HEARTBEAT"] - before
    # An autopilot beating at 10 Hz runs 10x faster than its 1 Hz: so does its
    # GCS-failsafe clock, and one GCS heartbeat a second would trip it.
    assert beats >= 6
