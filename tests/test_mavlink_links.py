"""Every connection kind, against `MavSim` on the other end: TCP either side, a serial line
(two pseudo-terminals joined by a relay, pyserial on both ends), a dropped TCP connection
and its return, and telemetry that is not a number. Ports are chosen free per test;
every thread is stopped and every descriptor closed at teardown.
"""

from __future__ import annotations

import math
import os
import select
import threading
import time
import tty
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
from live_helpers import free_tcp_port, free_udp_port, mavsim_thread, write_mission
from pymavlink.dialects.v20 import ardupilotmega as mavlink
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.executive.beliefs import Beliefs
from aeroexec.executive.beliefs_feed import update_beliefs
from aeroexec.executive.bus import MemoryObserver
from aeroexec.mission.live import FlightConfig, fly
from aeroexec.vehicles.base import VehicleState
from aeroexec.vehicles.mavlink.codec import Decoder, new_codec
from aeroexec.vehicles.mavlink.endpoint import parse_endpoint
from aeroexec.vehicles.mavlink.link import Link
from aeroexec.vehicles.mavlink.vehicle import MavlinkConfig, MavlinkVehicle

SHORT_FLIGHT = (
    "    return [api.executeBehavior('TAKE_OFF'),\n"
    "            api.executeBehavior('GO_TO_POINT', relative_coordinates=[1, 0, 0]),\n"
    "            api.executeBehavior('LAND')]\n"
)


# -- TCP ----------------------------------------------------------------------------------------


@pytest.mark.parametrize(("ground", "vehicle"), [("tcp", "tcpin"), ("tcpin", "tcp")])
def test_a_flight_over_tcp_from_either_side(tmp_path: Path, ground: str, vehicle: str) -> None:
    port = free_tcp_port()
    mission = write_mission(tmp_path, SHORT_FLIGHT)
    traffic = MemoryObserver()
    with mavsim_thread(f"{vehicle}:127.0.0.1:{port}") as sim:
        result = fly(
            FlightConfig(mission=mission, connect=f"{ground}:127.0.0.1:{port}", connect_timeout=5),
            observers=[traffic],
        )
    assert result.outcome.value == ["GOAL_ACHIEVED"] * 3
    assert result.safe and result.link_losses == 0
    # One connection, opened once; everything sent arrived, by type.
    connections = [e for e in traffic.topics("mavlink/link") if e["event"] == "connection"]
    assert [e["state"] for e in connections] == ["open"]
    sent = {k: v for k, v in sim.link.stats.received.items()}
    assert sent == dict(result_counts(traffic, "mavlink/tx"))
    assert sim.stats()["final"]["position"][0] == pytest.approx(1.0, abs=0.06)


def result_counts(traffic: MemoryObserver, topic: str) -> dict[str, int]:
    counts: dict[str, int] = {}
    for record in traffic.topics(topic):
        counts[record["type"]] = counts.get(record["type"], 0) + 1
    return counts


def test_a_dropped_tcp_connection_is_a_loss_at_once_and_comes_back(tmp_path: Path) -> None:
    port = free_tcp_port()
    vehicle = MavlinkVehicle(
        MavlinkConfig(url=f"tcp:127.0.0.1:{port}", heartbeat_timeout=3.0, connect_timeout=5.0)
    )
    events: list[dict[str, Any]] = []
    vehicle.tap = lambda topic, data: events.append(data) if topic == "mavlink/link" else None
    try:
        with mavsim_thread(f"tcpin:127.0.0.1:{port}"):
            vehicle.connect()
            vehicle.step(0.1)
        # The autopilot's end closed: no need to wait 3 s for a missing heartbeat.
        closed_at = time.monotonic()
        while not vehicle.link_lost and time.monotonic() - closed_at < 2.0:
            vehicle.step(0.1)
            time.sleep(0.01)
        detected = time.monotonic() - closed_at
        assert vehicle.link_lost and vehicle.state().fault == "link_lost"
        assert detected < 1.0
        # It listens again (an autopilot rebooted): the link reconnects by itself.
        with mavsim_thread(f"tcpin:127.0.0.1:{port}"):
            deadline = time.monotonic() + 5.0
            while vehicle.link_lost and time.monotonic() < deadline:
                vehicle.step(0.1)
                time.sleep(0.01)
        assert not vehicle.link_lost
    finally:
        vehicle.close()
    kinds = [(e["event"], e.get("state", "")) for e in events]
    assert kinds[:3] == [("connection", "open"), ("connected", ""), ("connection", "closed")]
    assert ("lost", "") in kinds and kinds.index(("lost", "")) == 3
    assert events[3]["why"] == "closed by the peer"
    assert ("connection", "open") in kinds[4:] and kinds[-1] == ("failsafe", "")
    assert events[-1]["action"] == "none" and events[-1]["reason"] == "not flying"


def test_no_tcp_server_exits_2_naming_the_refusal(tmp_path: Path) -> None:
    port = free_tcp_port()
    mission = str(write_mission(tmp_path, SHORT_FLIGHT))
    url = f"tcp:127.0.0.1:{port}"
    result = CliRunner().invoke(app, ["fly", mission, "--connect", url, "--connect-timeout", "0.6"])
    assert result.exit_code == 2
    assert result.output.strip().splitlines()[-1] == (
        f"aeroexec fly: error: no connection to tcp:127.0.0.1:{port} within 0.6 s "
        f"(Connection refused)"
    )


# -- serial ---------------------------------------------------------------------------------------


@contextmanager
def null_modem() -> Iterator[tuple[str, str]]:
    """Two pseudo-terminals whose masters a thread joins: what is written to one slave is
    read from the other, like two serial ports and a cable."""
    masters, slaves = [], []
    for _ in range(2):
        master, slave = os.openpty()
        tty.setraw(slave)
        masters.append(master)
        slaves.append(slave)
    stop = threading.Event()

    def relay() -> None:
        while not stop.is_set():
            ready, _, _ = select.select(masters, [], [], 0.05)
            for fd in ready:
                try:
                    data = os.read(fd, 4096)
                except OSError:
                    continue
                os.write(masters[1 - masters.index(fd)], data)

    thread = threading.Thread(target=relay, daemon=True)
    thread.start()
    try:
        yield os.ttyname(slaves[0]), os.ttyname(slaves[1])
    finally:
        stop.set()
        thread.join(5)
        for fd in masters + slaves:
            os.close(fd)


def test_a_flight_over_a_serial_line(tmp_path: Path) -> None:
    mission = write_mission(tmp_path, SHORT_FLIGHT)
    with null_modem() as (ground, vehicle), mavsim_thread(f"{vehicle},57600"):
        # Without --allow-remote: a serial device is local.
        result = fly(FlightConfig(mission=mission, connect=ground, baud=57600, connect_timeout=5))
    assert result.outcome.value == ["GOAL_ACHIEVED"] * 3
    assert result.safe
    assert result.metadata["connect"] == ground


def test_a_missing_serial_device_exits_2_with_one_line(tmp_path: Path) -> None:
    device = tmp_path / "ttyNOPE"
    result = CliRunner().invoke(
        app, ["fly", str(write_mission(tmp_path, SHORT_FLIGHT)), "--connect", f"{device},57600"]
    )
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(
        f"aeroexec fly: error: cannot open {device},57600:"
    )
    assert "No such file or directory" in lines[0]


# -- streams in pieces ---------------------------------------------------------------------------


def test_a_stream_packet_in_pieces_is_one_message_and_garbage_does_not_swallow_the_next() -> None:
    packet = bytes(mavlink.MAVLink_heartbeat_message(2, 3, 81, 4, 4, 3).pack(new_codec(1, 1)))
    decoder = Decoder(new_codec(255, 190))
    got: list[Any] = []
    rejected: list[Any] = []
    for piece in (packet[:3], packet[3:10], packet[10:] + b"console text\n", packet):
        messages, bad = decoder.feed_stream(piece)
        got += messages
        rejected += bad
    assert [m.get_type() for m in got] == ["HEARTBEAT", "HEARTBEAT"]
    assert rejected and all(r.reason == "bad_prefix" for r in rejected)
    # Datagrams never carry a fragment over: the same pieces one by one are rejected.
    assert decoder.feed(packet[:3])[1][0].reason == "truncated"


# -- telemetry that is not a number ---------------------------------------------------------------


def test_non_finite_telemetry_is_rejected_and_counted_and_the_state_keeps_its_value() -> None:
    port = free_udp_port()
    vehicle = MavlinkVehicle(
        MavlinkConfig(url=f"udpin:127.0.0.1:{port}", request_streams=False, connect_timeout=3)
    )
    rejected: list[dict[str, Any]] = []
    vehicle.tap = lambda topic, data: rejected.append(data) if topic == "mavlink/rejected" else None
    autopilot = Link(parse_endpoint(f"udpout:127.0.0.1:{port}"), system=1, component=1)
    try:
        autopilot.send(mavlink.MAVLink_heartbeat_message(2, 3, 81, 4, 4, 3))
        autopilot.send(mavlink.MAVLink_local_position_ned_message(0, 1.0, 2.0, -3.0, 0, 0, 0))
        vehicle.connect()
        nan, inf = math.nan, math.inf
        autopilot.send(mavlink.MAVLink_local_position_ned_message(0, nan, 2.0, -3.0, 0, 0, 0))
        autopilot.send(mavlink.MAVLink_attitude_message(0, 0.0, 0.0, inf, 0.0, 0.0, 0.0))
        time.sleep(0.05)
        vehicle.step(0.1)
    finally:
        autopilot.close()
        vehicle.close()
    assert vehicle.stats.rejected["non_finite"] == 2
    assert vehicle.stats.received["LOCAL_POSITION_NED"] == 1  # the finite one only
    assert vehicle.state().position == (2.0, 1.0, 3.0) and vehicle.state().yaw == math.pi / 2
    details = sorted(r["detail"] for r in rejected)
    assert details == ["ATTITUDE: yaw=inf", "LOCAL_POSITION_NED: x=nan"]


def test_a_state_that_is_not_a_number_leaves_the_beliefs_as_they_were() -> None:
    beliefs = Beliefs()
    good = VehicleState((1.0, 2.0, 3.0), (0.0, 0.0, 0.0), 0.0, 0.5, True, True)
    update_beliefs(beliefs, good)
    before = sorted(str(b) for b in beliefs)
    bad = VehicleState((math.nan, 2.0, 3.0), (0.0, 0.0, 0.0), math.nan, math.nan, True, True)
    assert update_beliefs(beliefs, bad) == 0
    assert sorted(str(b) for b in beliefs) == before
