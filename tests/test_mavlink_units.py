"""The MAVLink bridge's parts: frames, endpoints, decoding, real logs, acks, link health.

Real sockets on loopback; the peers are in-process threads here (a scripted fake
autopilot, or `MavSim`); `test_mavlink_flight.py` flies whole missions against the
`aeroexec mavsim` process.
"""

from __future__ import annotations

import base64
import hashlib
import json
import math
import random
import socket
import struct
import threading
import time
from collections import Counter
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from aeroexec.mavlink.sim_peer import MavSim, MavSimConfig
from aeroexec.mavlink.tlog import read_tlog
from aeroexec.vehicles.base import Vehicle, VehicleCommandError
from aeroexec.vehicles.mavlink import MavlinkConfig, MavlinkVehicle
from aeroexec.vehicles.mavlink.codec import (
    Decoder,
    command_number,
    json_safe,
    new_codec,
    packet_record,
    signing_key,
)
from aeroexec.vehicles.mavlink.convert import (
    COPTER_MODES,
    enu_to_ned,
    heading_degrees,
    ned_to_enu,
    yaw_enu_to_ned,
    yaw_ned_to_enu,
)
from aeroexec.vehicles.mavlink.endpoint import MavlinkError, parse_endpoint
from aeroexec.vehicles.mavlink.link import Link
from aeroexec.vehicles.mavlink.telemetry import Telemetry

FIXTURES = Path(__file__).parent / "fixtures" / "mavlink"
TLOG = FIXTURES / "arducopter_flight_window.tlog"


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _packet(msg: Any, system: int = 1, component: int = 1, key: bytes | None = None) -> bytes:
    return bytes(msg.pack(new_codec(system, component, key)))


def _heartbeat(mode: int = 4, armed: bool = False) -> Any:
    base = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    if armed:
        base |= mavlink.MAV_MODE_FLAG_SAFETY_ARMED
    return mavlink.MAVLink_heartbeat_message(
        mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, base, mode, 4, 3
    )


# -- frames ---------------------------------------------------------------------------------


def test_enu_and_ned_swap_the_horizontal_axes_and_flip_the_vertical() -> None:
    # 1 m east, 2 m north, 3 m up is 2 m north, 1 m east, 3 m *down* negative.
    assert enu_to_ned((1.0, 2.0, 3.0)) == (2.0, 1.0, -3.0)
    assert ned_to_enu((2.0, 1.0, -3.0)) == (1.0, 2.0, 3.0)
    # A vehicle 5 m north of home (NED x = 5) is at ENU y = 5.
    assert ned_to_enu((5.0, 0.0, 0.0)) == (0.0, 5.0, 0.0)
    rng = random.Random(7)
    for _ in range(200):
        v = (rng.uniform(-50, 50), rng.uniform(-50, 50), rng.uniform(-50, 50))
        assert ned_to_enu(enu_to_ned(v)) == v


@pytest.mark.parametrize(
    ("enu_yaw_deg", "ned_yaw_deg", "heading"),
    [
        (0.0, 90.0, 90.0),  # facing east
        (90.0, 0.0, 0.0),  # facing north
        (-90.0, 180.0, 180.0),  # facing south (the Appendix C ROTATE)
        (180.0, -90.0, 270.0),  # facing west
        (45.0, 45.0, 45.0),  # north-east is the same either way
        (135.0, -45.0, 315.0),  # north-west
    ],
)
def test_yaw_is_ccw_from_east_in_enu_and_cw_from_north_in_ned(
    enu_yaw_deg: float, ned_yaw_deg: float, heading: float
) -> None:
    enu = math.radians(enu_yaw_deg)
    ned = yaw_enu_to_ned(enu)
    assert math.isclose(math.degrees(ned), ned_yaw_deg, abs_tol=1e-9) or (
        abs(ned_yaw_deg) == 180.0 and math.isclose(abs(math.degrees(ned)), 180.0)
    )
    assert math.isclose(heading_degrees(enu), heading, abs_tol=1e-9)
    back = yaw_ned_to_enu(ned)
    assert math.isclose(math.cos(back), math.cos(enu), abs_tol=1e-12)
    assert math.isclose(math.sin(back), math.sin(enu), abs_tol=1e-12)


def test_copter_mode_numbers_are_pymavlinks() -> None:
    for number, name in COPTER_MODES.items():
        assert mavutil.mode_mapping_acm[number] == name
    assert COPTER_MODES[4] == "GUIDED" and COPTER_MODES[9] == "LAND"


# -- endpoints --------------------------------------------------------------------------------


def test_endpoints_parse_like_mavutil_and_stay_on_loopback() -> None:
    e = parse_endpoint("udpin:127.0.0.1:14550")
    assert (e.kind, e.host, e.port, e.stream) == ("udpin", "127.0.0.1", 14550, False)
    assert parse_endpoint("udp:localhost:9000").kind == "udpin"
    assert parse_endpoint("udp:localhost:9000").host == "127.0.0.1"
    assert parse_endpoint("udpout:127.0.0.2:9000").kind == "udpout"
    assert parse_endpoint("udpin:0.0.0.0:9000", allow_remote=True).host == "0.0.0.0"
    tcp = parse_endpoint("tcp:localhost:5760")
    assert (tcp.kind, tcp.host, tcp.port, tcp.stream, tcp.loopback) == (
        "tcp",
        "127.0.0.1",
        5760,
        True,
        True,
    )
    assert parse_endpoint("tcpin:127.0.0.1:5762").kind == "tcpin"
    assert parse_endpoint("tcpin:0.0.0.0:5762", allow_remote=True).loopback is False
    # A serial device is local: no --allow-remote needed. pymavlink's DEVICE,BAUD
    # spelling; without a baud rate the caller's default applies.
    radio = parse_endpoint("/dev/ttyUSB0,57600")
    assert (radio.kind, radio.device, radio.baud, radio.stream, radio.loopback) == (
        "serial",
        "/dev/ttyUSB0",
        57600,
        True,
        True,
    )
    usb = parse_endpoint("/dev/serial/by-id/usb-ArduPilot_fmuv3-if00", baud=921600)
    assert (usb.device, usb.baud) == ("/dev/serial/by-id/usb-ArduPilot_fmuv3-if00", 921600)


@pytest.mark.parametrize(
    ("url", "message"),
    [
        ("tcpx:127.0.0.1:5760", "unsupported connection 'tcpx:127.0.0.1:5760'"),
        ("ttyUSB0", "unsupported connection 'ttyUSB0' (use udpin:HOST:PORT"),
        ("tcp:10.0.0.2:5760", "not a loopback address; pass --allow-remote"),
        ("tcpin:0.0.0.0:5760", "not a loopback address; pass --allow-remote"),
        ("tcp:[::1]:5760", "TCP over IPv6 is not supported"),
        ("/dev/ttyUSB0,fast", "baud rate 'fast' is not a number"),
        ("/dev/ttyUSB0,0", "baud rate must be positive"),
        ("udpin:127.0.0.1", "needs HOST:PORT"),
        ("udpin:127.0.0.1:port", "port 'port' is not a number"),
        ("udpin:127.0.0.1:70000", "out of range"),
        ("udpin:0.0.0.0:14550", "not a loopback address; pass --allow-remote"),
        ("udpout:192.168.1.10:14550", "not a loopback address; pass --allow-remote"),
        ("udpout:drone.example:14550", "is not a loopback address"),
    ],
)
def test_bad_or_remote_endpoints_are_refused_with_the_reason(url: str, message: str) -> None:
    with pytest.raises(MavlinkError, match=message.replace("(", r"\(").replace("'", "'")):
        parse_endpoint(url)


def test_signing_key_is_hex_or_a_hashed_passphrase() -> None:
    hex_key = "00112233445566778899aabbccddeeff" * 2
    assert signing_key(hex_key) == bytes.fromhex(hex_key)
    assert signing_key("correct horse") == hashlib.sha256(b"correct horse").digest()
    assert len(signing_key("x")) == 32
    with pytest.raises(ValueError, match="empty"):
        signing_key("  ")


# -- decoding -------------------------------------------------------------------------------


def test_a_datagram_with_two_packets_gives_two_messages() -> None:
    decoder = Decoder(new_codec(255, 190))
    data = _packet(_heartbeat()) + _packet(
        mavlink.MAVLink_attitude_message(10, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
    )
    messages, rejected = decoder.feed(data)
    assert [m.get_type() for m in messages] == ["HEARTBEAT", "ATTITUDE"]
    assert rejected == []


def test_garbage_truncation_and_bad_crc_are_rejected_without_losing_the_next_packet() -> None:
    decoder = Decoder(new_codec(255, 190))
    good = _packet(_heartbeat())
    messages, rejected = decoder.feed(b"\x00\x01hello world")
    assert messages == [] and [r.reason for r in rejected] == ["bad_prefix"]
    # A packet header announcing more bytes than the datagram holds: the fragment is
    # dropped at the datagram's end instead of swallowing the next datagram's packet.
    messages, rejected = decoder.feed(good[:7])
    assert messages == [] and [r.reason for r in rejected] == ["truncated"]
    messages, rejected = decoder.feed(good)
    assert [m.get_type() for m in messages] == ["HEARTBEAT"] and rejected == []
    corrupt = bytearray(good)
    corrupt[-1] ^= 0xFF
    messages, rejected = decoder.feed(bytes(corrupt))
    assert messages == [] and [r.reason for r in rejected] == ["bad_crc"]
    rng = random.Random(1)
    for _ in range(300):  # random bytes never raise
        blob = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 300)))
        decoder.feed(blob)
    assert [m.get_type() for m in decoder.feed(good)[0]] == ["HEARTBEAT"]


def test_a_signed_codec_accepts_its_key_only() -> None:
    key, other = signing_key("secret"), signing_key("other")
    receiver = Decoder(new_codec(255, 190, key))
    signed = _packet(_heartbeat(), key=key)
    assert signed[2] & mavlink.MAVLINK_IFLAG_SIGNED
    assert [m.get_type() for m in receiver.feed(signed)[0]] == ["HEARTBEAT"]
    for bad in (_packet(_heartbeat()), _packet(_heartbeat(), key=other)):
        messages, rejected = receiver.feed(bad)
        assert messages == [] and [r.reason for r in rejected] == ["bad_signature"]


def test_packet_records_are_json_and_keep_the_exact_bytes() -> None:
    codec = new_codec(255, 190)
    msg = mavlink.MAVLink_command_long_message(1, 1, 22, 0, 0, 0, 0, math.nan, 0, 0, 2.5)
    raw = bytes(msg.pack(codec))
    record = packet_record(msg)
    assert base64.b64decode(record["raw"]) == raw
    assert record["type"] == "COMMAND_LONG" and record["system"] == 255
    assert record["fields"]["param4"] == "NaN" and record["fields"]["param7"] == 2.5
    json.dumps(record, allow_nan=False)  # strict JSON
    assert json_safe([1.0, math.inf, b"\x01"]) == [1.0, "Infinity", "AQ=="]
    assert command_number("nav_takeoff") == command_number("MAV_CMD_NAV_TAKEOFF") == 22


# -- a real flight log -----------------------------------------------------------------------


def _pymavlink_messages(path: Path) -> tuple[list[Any], int]:
    log = mavutil.mavlink_connection(str(path))
    out, bad = [], 0
    while True:
        msg = log.recv_match()
        if msg is None:
            break
        if msg.get_type() == "BAD_DATA":
            bad += 1
        else:
            out.append(msg)
    return out, bad


def test_the_real_tlog_decodes_as_pymavlink_decodes_it() -> None:
    theirs, their_bad = _pymavlink_messages(TLOG)
    records = list(read_tlog(TLOG))
    ours = [r.message for r in records if r.message is not None]
    our_bad = [r.rejected for r in records if r.rejected is not None]
    assert len(ours) == len(theirs) == 9096
    assert len(our_bad) == their_bad == 118
    assert {r.reason for r in our_bad} == {"bad_crc"}
    for mine, other in zip(ours, theirs, strict=True):
        assert mine.get_type() == other.get_type()
        assert (mine.get_srcSystem(), mine.get_seq()) == (other.get_srcSystem(), other.get_seq())
        assert bytes(mine.get_msgbuf()) == bytes(other.get_msgbuf())
        # pymavlink reads a .tlog with its MAVLink 1 dialect, which has no extension
        # fields; ours (MAVLink 2) adds them, zero as the packet does not carry them.
        recorded = packet_record(mine)["fields"]
        expected = json_safe(_fields(other))
        assert {k: recorded[k] for k in expected} == expected
        assert all(not v for k, v in recorded.items() if k not in expected)


def _fields(msg: Any) -> dict[str, Any]:
    d = msg.to_dict()
    d.pop("mavpackettype")
    return d


def test_the_real_tlog_folds_into_vehicle_states() -> None:
    telemetry = Telemetry()
    armed_changes, modes, flying_seen = 0, [], False
    last_position = None
    for record in read_tlog(TLOG):
        msg = record.message
        if msg is None or msg.get_srcSystem() != 1:
            continue
        was_armed = telemetry.armed
        telemetry.apply(msg)
        armed_changes += telemetry.armed != was_armed
        if not modes or modes[-1] != telemetry.mode:
            modes.append(telemetry.mode)
        flying_seen |= telemetry.vehicle_state().flying
        if msg.get_type() == "LOCAL_POSITION_NED":
            last_position = msg
    # What the log says happened: armed once and disarmed once, STABILIZE -> LOITER ->
    # STABILIZE, airborne in between.
    assert armed_changes == 2 and not telemetry.armed
    assert [m for m in modes if m != "UNKNOWN"] == ["STABILIZE", "LOITER", "STABILIZE"]
    assert flying_seen
    state = telemetry.vehicle_state()
    assert last_position is not None
    assert state.position == (last_position.y, last_position.x, -last_position.z)
    assert state.velocity == (last_position.vy, last_position.vx, -last_position.vz)
    assert 0.0 <= state.battery <= 1.0


def test_the_real_tlog_sent_over_udp_reaches_the_vehicle_state_and_the_tap() -> None:
    """The log's packets, one datagram each, into a live `MavlinkVehicle`."""
    port = free_udp_port()
    tapped: Counter[str] = Counter()
    vehicle = MavlinkVehicle(
        MavlinkConfig(url=f"udpin:127.0.0.1:{port}", heartbeat_timeout=30, request_streams=False),
        tap=lambda topic, payload: tapped.update([topic]),
    )
    assert isinstance(vehicle, Vehicle)
    records = list(read_tlog(TLOG))
    raw = TLOG.read_bytes()
    packets = _tlog_packets(raw)
    assert len(packets) == len(records)
    sender = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        for i in range(0, len(packets), 40):
            for packet in packets[i : i + 40]:
                sender.sendto(packet, ("127.0.0.1", port))
            vehicle.step(0.1)
        deadline = time.monotonic() + 2.0
        while sum(vehicle.stats.received.values()) < 9096 and time.monotonic() < deadline:
            vehicle.step(0.1)
    finally:
        sender.close()
        vehicle.close()
    stats = vehicle.stats
    assert sum(stats.received.values()) == 9096  # every good packet arrived and decoded
    assert stats.rejected["bad_crc"] == 118
    assert vehicle.target == (1, 1)
    # After the lock on system 1: the GCS (255) and the radio (51) are foreign.
    assert stats.ignored["foreign_system"] > 0 and set(stats.rejected) == {"bad_crc"}
    assert tapped["mavlink/rx"] == 9096 and tapped["mavlink/rejected"] == 118
    expected = Telemetry()
    for record in records:
        if record.message is not None and record.message.get_srcSystem() == 1:
            expected.apply(record.message)
    assert vehicle.state() == expected.vehicle_state()


def _tlog_packets(data: bytes) -> list[bytes]:
    out, i = [], 0
    while i + 10 <= len(data):
        length = data[i + 9] + 8  # MAVLink 1: header 6 + payload + CRC 2
        out.append(data[i + 8 : i + 8 + length])
        i += 8 + length
    return out


# -- commands against a scripted autopilot ------------------------------------------------------


class FakeAutopilot:
    """A thread answering as `answer(command_long) -> MAV_RESULT | None` (None: silence),
    sending heartbeats (while `beating`) and a position, and keeping what it received."""

    def __init__(self, port: int, answer: Callable[[Any], int | None]) -> None:
        self.link = Link(parse_endpoint(f"udpout:127.0.0.1:{port}"), system=1, component=1)
        self.answer = answer
        #: A STATUSTEXT sent just after a FAILED acknowledgement (None: none).
        self.reason_after_ack: str | None = None
        self.beating = True
        self.received: list[Any] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> FakeAutopilot:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(5)
        self.link.close()

    def _run(self) -> None:
        next_beat = 0.0
        while not self._stop.is_set():
            now = time.monotonic()
            if now >= next_beat:
                next_beat = now + 0.05
                if self.beating:
                    self.link.send(_heartbeat(mode=4, armed=True))
                self.link.send(
                    mavlink.MAVLink_local_position_ned_message(0, 1.0, 2.0, -3.0, 0, 0, 0)
                )
                self.link.send(mavlink.MAVLink_extended_sys_state_message(0, 2))
            for item in self.link.poll(0.01):
                self.received.append(item.msg)
                if item.msg.get_type() == "COMMAND_LONG":
                    result = self.answer(item.msg)
                    if result is not None:
                        self.link.send(
                            mavlink.MAVLink_command_ack_message(
                                item.msg.command, result, 0, 0, 255, 190
                            )
                        )
                    if result == mavlink.MAV_RESULT_FAILED and self.reason_after_ack:
                        # As ArduCopter does: the STATUSTEXT is queued, the ACK is not.
                        time.sleep(0.02)
                        self.link.send(
                            mavlink.MAVLink_statustext_message(
                                mavlink.MAV_SEVERITY_CRITICAL, self.reason_after_ack.encode()
                            )
                        )

    def commands(self, command: int) -> list[Any]:
        return [
            m
            for m in list(self.received)
            if m.get_type() == "COMMAND_LONG" and m.command == command
        ]


@pytest.fixture
def vehicle_port() -> Iterator[int]:
    yield free_udp_port()


def _vehicle(port: int, **overrides: Any) -> MavlinkVehicle:
    config = MavlinkConfig(
        url=f"udpin:127.0.0.1:{port}",
        ack_timeout=0.2,
        retries=2,
        connect_timeout=3.0,
        request_streams=False,
        **overrides,
    )
    return MavlinkVehicle(config)


def test_a_refused_arming_waits_for_the_reason_the_autopilot_sends_after_its_ack(
    vehicle_port: int,
) -> None:
    def refuse_arming(msg: Any) -> int:
        if msg.command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM:
            return mavlink.MAV_RESULT_FAILED
        return mavlink.MAV_RESULT_ACCEPTED

    vehicle = _vehicle(vehicle_port)
    with FakeAutopilot(vehicle_port, answer=refuse_arming) as autopilot:
        autopilot.reason_after_ack = "Arm: Battery 1 below minimum arming voltage"
        vehicle.connect()
        with pytest.raises(VehicleCommandError) as refused:
            vehicle._command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (1.0,))
    vehicle.close()
    assert str(refused.value) == (
        "MAV_CMD_COMPONENT_ARM_DISARM refused: FAILED "
        "(autopilot: Arm: Battery 1 below minimum arming voltage)"
    )


def test_an_unanswered_command_is_retried_then_reported(vehicle_port: int) -> None:
    vehicle = _vehicle(vehicle_port)
    with FakeAutopilot(vehicle_port, answer=lambda msg: None) as autopilot:
        vehicle.connect()
        assert vehicle.state().flying and vehicle.state().position == (2.0, 1.0, 3.0)
        started = time.monotonic()
        with pytest.raises(VehicleCommandError) as info:
            vehicle.set_yaw(0.0)
        took = time.monotonic() - started
    vehicle.close()
    assert str(info.value) == "MAV_CMD_CONDITION_YAW: no COMMAND_ACK after 3 attempts (0.2 s each)"
    sent = autopilot.commands(mavlink.MAV_CMD_CONDITION_YAW)
    assert [m.confirmation for m in sent] == [0, 1, 2]  # retransmissions are marked
    assert sent[0].param1 == pytest.approx(90.0)  # ENU yaw 0 (east) is heading 90
    assert 0.55 < took < 1.5


def test_a_lost_ack_is_recovered_by_the_retry(vehicle_port: int) -> None:
    answers = iter([None, mavlink.MAV_RESULT_ACCEPTED])
    vehicle = _vehicle(vehicle_port)
    with FakeAutopilot(vehicle_port, answer=lambda msg: next(answers)) as autopilot:
        vehicle.connect()
        vehicle.set_yaw(math.pi / 2)  # no exception: the second attempt was acknowledged
    vehicle.close()
    sent = autopilot.commands(mavlink.MAV_CMD_CONDITION_YAW)
    assert [m.confirmation for m in sent] == [0, 1]
    assert sent[0].param1 == pytest.approx(0.0)  # ENU pi/2 (north) is heading 0


def test_a_refused_command_raises_with_the_command_and_result_names(vehicle_port: int) -> None:
    vehicle = _vehicle(vehicle_port)
    with FakeAutopilot(vehicle_port, answer=lambda msg: mavlink.MAV_RESULT_DENIED):
        vehicle.connect()
        with pytest.raises(VehicleCommandError, match=r"^MAV_CMD_CONDITION_YAW refused: DENIED$"):
            vehicle.set_yaw(1.0)
    vehicle.close()


def test_heartbeat_loss_is_a_fault_commands_refuse_and_the_failsafe_runs_on_return(
    vehicle_port: int,
) -> None:
    events: list[dict[str, Any]] = []

    def tap(topic: str, payload: Any) -> None:
        if topic == "mavlink/link":
            events.append(payload)

    vehicle = _vehicle(vehicle_port, heartbeat_timeout=0.3, failsafe="hold")
    vehicle.tap = tap
    with FakeAutopilot(vehicle_port, answer=lambda msg: mavlink.MAV_RESULT_ACCEPTED) as autopilot:
        vehicle.connect()
        assert vehicle.state().fault == ""
        autopilot.beating = False
        deadline = time.monotonic() + 2.0
        while vehicle.state().fault != "link_lost" and time.monotonic() < deadline:
            vehicle.step(0.05)
            time.sleep(0.02)
        assert vehicle.state().fault == "link_lost"
        # Telemetry still flows (only heartbeats stopped), yet nothing may be commanded.
        with pytest.raises(
            VehicleCommandError, match=r"go_to: refused, link lost \(no heartbeat for 0.3 s\)"
        ):
            vehicle.go_to(0.0, 0.0, 2.0)
        before = len(autopilot.received)
        autopilot.beating = True
        deadline = time.monotonic() + 2.0
        while not any(e["event"] == "failsafe" for e in events) and time.monotonic() < deadline:
            vehicle.step(0.05)
            time.sleep(0.02)
        time.sleep(0.1)
    vehicle.close()
    assert vehicle.state().fault == ""
    assert [e["event"] for e in events] == ["connected", "lost", "restored", "failsafe"]
    assert events[-1]["action"] == "hold"
    # The hold: a zero-velocity setpoint in MAV_FRAME_LOCAL_NED, sent after the return.
    setpoints = [
        m for m in autopilot.received[before:] if m.get_type() == "SET_POSITION_TARGET_LOCAL_NED"
    ]
    assert len(setpoints) == 1
    hold = setpoints[0]
    assert hold.coordinate_frame == mavlink.MAV_FRAME_LOCAL_NED
    assert hold.type_mask & 0b111 == 0b111 and hold.type_mask & 0b111000 == 0  # velocity only
    assert (hold.vx, hold.vy, hold.vz) == (0.0, 0.0, 0.0)


def test_setpoints_go_out_in_ned_with_the_held_heading(vehicle_port: int) -> None:
    vehicle = _vehicle(vehicle_port)
    with FakeAutopilot(vehicle_port, answer=lambda msg: mavlink.MAV_RESULT_ACCEPTED) as autopilot:
        vehicle.connect()
        vehicle.set_yaw(math.radians(-90))  # face south
        vehicle.go_to(3.0, 5.5, 1.3)  # 3 m east, 5.5 m north, 1.3 m up
        vehicle.set_velocity(1.0, 0.0, -0.5)  # east, descending
        time.sleep(0.1)
    vehicle.close()
    go, vel = [m for m in autopilot.received if m.get_type() == "SET_POSITION_TARGET_LOCAL_NED"][:2]
    assert (go.x, go.y, go.z) == pytest.approx((5.5, 3.0, -1.3))
    assert go.type_mask & 0b111 == 0 and go.type_mask & 0b111000 == 0b111000
    assert not go.type_mask & mavlink.POSITION_TARGET_TYPEMASK_YAW_IGNORE
    assert go.yaw == pytest.approx(math.pi)  # south is NED yaw pi
    assert (vel.vx, vel.vy, vel.vz) == pytest.approx((0.0, 1.0, 0.5))
    assert vel.type_mask & 0b111 == 0b111


def test_mavsim_refuses_what_arducopter_refuses() -> None:
    port = free_udp_port()
    vehicle = _vehicle(port)
    sim = MavSim(MavSimConfig(url=f"udpout:127.0.0.1:{port}", speed_factor=5.0))
    stop = threading.Event()
    thread = threading.Thread(target=sim.run, args=(stop.is_set,), daemon=True)
    thread.start()
    try:
        vehicle.connect()
        assert vehicle.telemetry.mode == "STABILIZE" and not vehicle.state().flying
        take_off = mavlink.MAV_CMD_NAV_TAKEOFF
        with pytest.raises(VehicleCommandError, match=r"^MAV_CMD_NAV_TAKEOFF refused: FAILED$"):
            vehicle._command(take_off, (0, 0, 0, 0, 0, 0, 1.0))  # not GUIDED, not armed
        with pytest.raises(
            VehicleCommandError, match="go_to: refused, the vehicle is on the ground"
        ):
            vehicle.go_to(0, 0, 1)
        with pytest.raises(
            VehicleCommandError,
            match=r"^MAV_CMD_DO_SET_MODE refused: FAILED \(autopilot: No such mode 99\)$",
        ):
            vehicle._set_mode(99)  # no such mode: the autopilot's STATUSTEXT says why
        vehicle.take_off(1.0)  # GUIDED, arm, take off: accepted
        with pytest.raises(VehicleCommandError, match=r"^MAV_CMD_NAV_TAKEOFF refused: FAILED$"):
            vehicle._command(take_off, (0, 0, 0, 0, 0, 0, 2.0))  # already flying
        deadline = time.monotonic() + 3.0
        while not vehicle.state().flying and time.monotonic() < deadline:
            vehicle.step(0.05)
            time.sleep(0.02)
        with pytest.raises(
            VehicleCommandError, match=r"^MAV_CMD_COMPONENT_ARM_DISARM refused: FAILED$"
        ):
            vehicle._command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (0.0,))  # disarm in the air
        with pytest.raises(
            VehicleCommandError, match=r"^MAV_CMD_DO_REPOSITION refused: UNSUPPORTED$"
        ):
            vehicle._command(mavlink.MAV_CMD_DO_REPOSITION, ())
    finally:
        stop.set()
        thread.join(5)
        sim.close()
        vehicle.close()
    assert sim.mode == 4 and sim.armed


def test_garbage_from_a_stranger_is_counted_and_ignored(vehicle_port: int) -> None:
    vehicle = _vehicle(vehicle_port)
    stranger = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    rng = random.Random(3)
    with FakeAutopilot(vehicle_port, answer=lambda msg: mavlink.MAV_RESULT_ACCEPTED):
        vehicle.connect()
        state = vehicle.state()
        for _ in range(50):
            stranger.sendto(
                bytes(rng.randrange(256) for _ in range(40)), ("127.0.0.1", vehicle_port)
            )
        # A well-formed heartbeat from another address claiming to be the autopilot in
        # LAND mode, disarmed: ignored too (the link is locked on the real sender).
        stranger.sendto(_packet(_heartbeat(mode=9)), ("127.0.0.1", vehicle_port))
        time.sleep(0.1)
        vehicle.step(0.1)
    stranger.close()
    vehicle.close()
    assert vehicle.stats.rejected["foreign_address"] == 51
    assert vehicle.telemetry.mode == "GUIDED" and vehicle.state().armed == state.armed


def test_garbage_from_the_autopilots_own_address_is_parsed_counted_and_survived(
    vehicle_port: int,
) -> None:
    vehicle = _vehicle(vehicle_port)
    rng = random.Random(11)
    blobs = [bytes(rng.randrange(256) for _ in range(rng.randrange(1, 200))) for _ in range(200)]
    blobs += [b"\xfd\xff" + bytes(20), b"\xfe\x09", _packet(_heartbeat())[:-3]]  # cut short
    with FakeAutopilot(vehicle_port, answer=lambda msg: mavlink.MAV_RESULT_ACCEPTED) as autopilot:
        vehicle.connect()
        for blob in blobs:
            autopilot.link.transport.sock.sendto(blob, ("127.0.0.1", vehicle_port))
        time.sleep(0.1)
        vehicle.step(0.1)
        vehicle.set_yaw(0.5)  # still commanded and acknowledged after the garbage
    vehicle.close()
    rejected = vehicle.stats.rejected
    assert rejected["foreign_address"] == 0  # it came from the locked peer: parsed
    assert rejected["truncated"] >= 3 and sum(rejected.values()) >= len(blobs)
    assert rejected["unknown_message"] > 0  # what random bytes mostly "decode" to
    assert set(vehicle.stats.received) <= {
        "HEARTBEAT",
        "LOCAL_POSITION_NED",
        "EXTENDED_SYS_STATE",
        "COMMAND_ACK",
    }
    assert vehicle.state().position == (2.0, 1.0, 3.0) and vehicle.telemetry.mode == "GUIDED"


def test_struct_layout_of_tlog_records_is_what_read_tlog_assumes() -> None:
    data = TLOG.read_bytes()
    (first_us,) = struct.unpack_from(">Q", data, 0)
    assert data[8] == 0xFE  # MAVLink 1 packet right after the timestamp
    assert 1436056400 < first_us / 1e6 < 1436056500  # 2015-07-05
