"""Whole missions over MAVLink: `aeroexec mavsim` in a subprocess as the autopilot,
`aeroexec fly` (a subprocess, or `fly()` in-process) as the ground station, real UDP on
loopback, ports chosen free per test. Every process is bounded (`--duration`,
timeouts) and killed at teardown if still alive.
"""

from __future__ import annotations

import json
import random
import socket
import threading
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from live_helpers import AeroexecProcess as Proc
from live_helpers import free_udp_port, write_mission
from pymavlink.dialects.v20 import ardupilotmega as mavlink
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.executive.bus import MemoryObserver
from aeroexec.executive.messages import TopicRecord
from aeroexec.mavlink.sim_peer import MavSim, MavSimConfig
from aeroexec.mission.live import FlightConfig, fly
from aeroexec.mission.paths import APPENDIX_C
from aeroexec.properties.check import SERVICES, TOPICS, VIOLATED, evaluate
from aeroexec.properties.signals import PERIOD_NS, SignalBuilder
from aeroexec.properties.spec import parse_properties
from aeroexec.recording import open_recording
from aeroexec.recording.reader import RecordedTopic
from aeroexec.replay.engine import Mode, ReplayOptions, replay_recording
from aeroexec.vehicles.mavlink.codec import new_codec
from aeroexec.vehicles.mavlink.vehicle import STILL_SPEED

SPEED = "5"  # mavsim runs the vehicle 5x faster than the wall clock ...
HEARTBEAT_HZ = "4"  # ... and beats 4 times a second, so arming and modes show sooner


@pytest.fixture
def procs() -> Iterator[list[Proc]]:
    started: list[Proc] = []
    yield started
    for proc in started:
        proc.kill()


def start_mavsim(procs: list[Proc], port: int, stats: Path, *extra: str) -> Proc:
    proc = Proc(
        [
            "mavsim",
            "--connect",
            f"udpout:127.0.0.1:{port}",
            "--speed-factor",
            SPEED,
            "--heartbeat-hz",
            HEARTBEAT_HZ,
            "--duration",
            "45",
            "--stats",
            str(stats),
            "--stats-tail",
            *extra,
        ]
    )
    procs.append(proc)
    proc.wait_for("mavsim: ArduCopter")
    return proc


def stop_mavsim(proc: Proc, stats: Path) -> dict[str, Any]:
    proc.stop()
    assert proc.popen.returncode == 0
    return json.loads(stats.read_text())


# -- the thesis' mission, end to end, recorded ---------------------------------------------------


def test_appendix_c_flies_on_mavsim_and_the_recording_holds_every_packet(
    tmp_path: Path, procs: list[Proc]
) -> None:
    port = free_udp_port()
    record = tmp_path / "flight.mcap"
    stats_path = tmp_path / "mavsim.json"
    flight = Proc(
        ["fly", str(APPENDIX_C), "--connect", f"udpin:127.0.0.1:{port}", "--output", str(record)]
    )
    procs.append(flight)
    flight.wait_for("waiting for a heartbeat")  # bound: nothing mavsim sends is lost
    # Every 97th packet mavsim sends has a broken CRC.
    mavsim = start_mavsim(procs, port, stats_path, "--corrupt-every", "97")
    flight.wait_for("mavlink: autopilot system 1")
    # Meanwhile a stranger sprays garbage at the ground station's port.
    stranger = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    rng = random.Random(9)
    for _ in range(25):
        stranger.sendto(
            bytes(rng.randrange(256) for _ in range(rng.randrange(1, 80))), ("127.0.0.1", port)
        )
    stranger.close()
    started = time.monotonic()
    flight.wait_for("7 activations:", timeout=30)  # the summary: fly closed its socket
    stats = stop_mavsim(mavsim, stats_path)
    code, out, err = flight.finish()
    took = time.monotonic() - started

    assert code == 0, err
    assert err == ""
    assert took < 20.0
    ends = [line for line in out.splitlines() if "] end " in line]
    assert len(ends) == 7
    for line in ends:
        if "PAY_ATTENTION_TO_VISUAL_MARKERS" in line:
            assert "INTERRUPTED" in line and "(inhibited)" in line  # the script inhibits it
        else:
            assert "GOAL_ACHIEVED" in line, line
    assert "7 activations: 6 GOAL_ACHIEVED, 0 rejected" in out
    assert stats["final"]["mode"] == "LAND" and not stats["final"]["armed"]
    assert stats["final"]["yaw_deg"] == pytest.approx(-90.0, abs=1.0)  # ROTATE angle=-90
    assert stats["rejected"] == {} and stats["ignored"] == {}

    recording = open_recording(record)
    assert recording.complete
    topics: dict[str, list[Any]] = {}
    first_command_ns = None
    for item in recording.records():
        if isinstance(item, RecordedTopic):
            topics.setdefault(item.name, []).append(item.data)
            if item.name == "mission/command" and first_command_ns is None:
                first_command_ns = item.log_time_ns
    tx, rx = topics["mavlink/tx"], topics["mavlink/rx"]
    rejected = Counter(r["reason"] for r in topics["mavlink/rejected"])
    # Ground station -> vehicle: everything fly sent is what mavsim received, by type.
    assert Counter(r["type"] for r in tx) == Counter(stats["received"])
    # Vehicle -> ground station: what mavsim sent = recorded + corrupted + in flight when
    # fly closed its socket (mavsim still sent until it was stopped), by type. The
    # in-flight packets are the ones after the last recorded packet's seq in mavsim's tail.
    last = (rx[-1]["seq"], rx[-1]["type"])
    tail = [tuple(entry) for entry in stats["tail"]]
    cut = max(i for i, entry in enumerate(tail) if entry[:2] == last)
    in_flight = tail[cut + 1 :]
    # Fewer than 256 in flight: no seq wrapped among them, so the cut is unambiguous.
    assert len(in_flight) < 256, len(in_flight)
    corrupted = Counter(stats["corrupted"])
    for kind, sent in stats["sent"].items():
        flying_ok = sum(1 for _, t, bad in in_flight if t == kind and not bad)
        flying_bad = sum(1 for _, t, bad in in_flight if t == kind and bad)
        recorded = sum(1 for r in rx if r["type"] == kind)
        assert recorded + flying_ok + (corrupted[kind] - flying_bad) == sent, kind
    assert sum(corrupted.values()) > 0
    assert rejected["bad_crc"] == sum(corrupted.values()) - sum(1 for e in in_flight if e[2])
    assert rejected["foreign_address"] == 25  # the stranger's datagrams, all of them
    assert all(not r.get("ignored") for r in rx)
    # The recording's own summary agrees, and the link events are there.
    (final_stats,) = topics["mavlink/stats"]
    assert final_stats["rejected"]["foreign_address"] == 25
    assert [e["event"] for e in topics["mavlink/link"]] == ["connected", "mission_end", "ending"]
    assert topics["mavlink/link"][1]["how"] == "returned"
    ending = topics["mavlink/link"][-1]
    assert ending["down"] and ending["actions"] == [] and ending["problem"] == ""
    assert ending["last_seen"].startswith("on the ground at (")
    events = [e["code"] for e in topics["behavior_event"]]
    assert events.count("GOAL_ACHIEVED") == 6
    # Time 0 is when the link came up: the mission's first command comes right away
    # (mavsim's EKF took 2 vehicle seconds, 0.4 s of wall clock at SPEED 5, before that;
    # a clock started before connecting would show at least that).
    assert first_command_ns is not None and first_command_ns < 300_000_000
    # The unchanged flight replays with no difference, open and closed loop (the
    # closed loop runs the recorded commands, or the recorded mission when trusted, with
    # the real behaviors against the recorded vehicle).
    for mode, trusted in ((Mode.open, False), (Mode.closed, False), (Mode.closed, True)):
        options = ReplayOptions(mode=mode, trust_recording=trusted)
        replayed = replay_recording(record, options)
        assert replayed.diff is not None and replayed.diff.compared == 9, mode
        assert replayed.equal, (mode, [d.message for d in replayed.diff.differences])
        if mode is Mode.closed:
            ran_script = not any("was not run" in note for note in replayed.notes)
            assert ran_script == trusted, replayed.notes


# -- link loss --------------------------------------------------------------------------------


def fly_through_a_link_loss(
    tmp_path: Path, procs: list[Proc], body: str, *, failsafe: str
) -> tuple[Any, MemoryObserver, dict[str, Any]]:
    """Fly `body` against mavsim, whose heartbeats stop 1.2 s after the take-off for 2 s.
    The take-off takes ~0.7 s of wall time, then GO_TO_POINT 40 m north ~4 s more; fly
    calls the link lost after 1 s without a heartbeat, so in the middle of GO_TO_POINT.
    The flight's result, what its bus carried, and mavsim's counts."""
    port = free_udp_port()
    stats_path = tmp_path / "mavsim.json"
    mavsim = start_mavsim(procs, port, stats_path, "--drop-heartbeats-at", "1.2", "--drop-for", "2")
    memory = MemoryObserver()
    result = fly(
        FlightConfig(
            mission=write_mission(tmp_path, body),
            connect=f"udpin:127.0.0.1:{port}",
            heartbeat_timeout=1.0,
            failsafe=failsafe,
        ),
        observers=[memory],
    )
    return result, memory, stop_mavsim(mavsim, stats_path)


def test_link_loss_mid_go_to_point_fails_it_and_the_failsafe_lands(
    tmp_path: Path, procs: list[Proc]
) -> None:
    result, memory, stats = fly_through_a_link_loss(
        tmp_path,
        procs,
        "    took_off = api.executeBehavior('TAKE_OFF')\n"
        "    went = api.executeBehavior('GO_TO_POINT', coordinates=[0, 40, 1])\n"
        "    turned = api.executeBehavior('ROTATE', angle=90)\n"
        "    for _ in range(8):  # until the failsafe has landed it\n"
        "        if not api.trueBelief('flying(self)'):\n"
        "            break\n"
        "        api.executeBehavior('WAIT', duration=1)\n"
        "    return took_off, went, turned, api.trueBelief('flying(self)')\n",
        failsafe="land",
    )

    assert result.outcome.returned
    assert result.outcome.value == ("GOAL_ACHIEVED", "PROCESS_FAILURE", "PROCESS_FAILURE", False)
    rows = {a.behavior: a for a in result.activations}
    assert rows["GO_TO_POINT"].detail == "vehicle fault: link_lost"
    # A command while the link is down is refused by the vehicle: a clean failure too.
    assert "set_yaw: refused, link lost (no heartbeat for 1 s)" in rows["ROTATE"].detail
    events = [e["event"] for e in memory.topics("mavlink/link")]
    assert events == [
        "connected",
        "lost",
        "restored",
        "failsafe",
        "failsafe_seen",  # the autopilot's HEARTBEAT said LAND: acknowledged is not done
        "mission_end",
        "ending",
    ]
    seen = next(e for e in memory.topics("mavlink/link") if e["event"] == "failsafe_seen")
    assert seen["mode"] == "LAND" and 0.0 < seen["after_s"] < 2.0
    assert memory.topics("mavlink/link")[3]["action"] == "land"
    _the_link_signal_follows_the_link(memory)
    # The vehicle ended down, but the flight lost its link: not a safe flight.
    assert result.ending is not None and result.ending.down
    assert result.link_losses == 1 and not result.safe
    assert result.problem().startswith("the link was lost 1 time during the flight; vehicle")
    assert stats["dropped_heartbeats"] >= 1
    # The failsafe's LAND reached the vehicle after the link came back, and it landed
    # short of the goal it was flying to.
    modes = [c for c in stats["commands"] if c["command"] == "MAV_CMD_DO_SET_MODE"]
    assert [c["result"] for c in modes] == ["ACCEPTED", "ACCEPTED"]  # GUIDED, then LAND
    assert stats["final"]["mode"] == "LAND" and not stats["final"]["flying"]
    assert stats["final"]["position"][1] < 39.0


def _the_link_signal_follows_the_link(memory: MemoryObserver) -> None:
    """The properties' `link` signal (docs/properties.md) on the flight's messages: 0
    from the tick the link is called lost to the tick it is restored, and
    `fault_link_lost` from the loss on."""
    builder = SignalBuilder(None)
    when: dict[str, int] = {}
    for record in memory.records:
        if isinstance(record, TopicRecord):
            if record.topic == "mavlink/link":
                when.setdefault(record.data["event"], record.log_time_ns)
            if record.topic in TOPICS:
                builder.topic(record.topic, record.log_time_ns, record.data)
        elif record.service in SERVICES:
            builder.call(record.service, record.log_time_ns, record.request, record.response)
    props = parse_properties(
        "properties:\n"
        "  - {name: link_up, formula: 'always(link >= 1)'}\n"
        "  - {name: never_lost, formula: 'always(fault_link_lost <= 0)'}\n",
        "link.yaml",
    )
    link_up, never_lost = evaluate(props, builder.finish())
    assert link_up.status == never_lost.status == VIOLATED
    lost, restored = when["lost"] // PERIOD_NS, when["restored"] // PERIOD_NS
    # The vehicle state that says so is the next one published: within a tick.
    start, end = (round(t / (PERIOD_NS / 1e9)) for t in link_up.interval_s)
    assert lost <= start <= lost + 1 and restored - 1 <= end <= restored + 1
    assert never_lost.interval_s[0] == link_up.interval_s[0]
    assert never_lost.interval_s[1] > link_up.interval_s[1]  # seen, from then on


def test_a_failsafe_hold_is_reported_only_once_the_autopilot_shows_it_still(
    tmp_path: Path, procs: list[Proc]
) -> None:
    """`--failsafe hold` brakes with a zero-velocity setpoint: sent is not stopped, so
    `failsafe_seen` waits for the autopilot's own velocity below `STILL_SPEED`."""
    result, memory, _ = fly_through_a_link_loss(
        tmp_path,
        procs,
        "    took_off = api.executeBehavior('TAKE_OFF')\n"
        "    went = api.executeBehavior('GO_TO_POINT', coordinates=[0, 40, 1])\n"
        "    api.executeBehavior('WAIT', duration=2)\n"
        "    return took_off, went\n",
        failsafe="hold",
    )

    assert result.outcome.value == ("GOAL_ACHIEVED", "PROCESS_FAILURE")
    link = memory.topics("mavlink/link")
    events = [e["event"] for e in link]
    assert events[:5] == ["connected", "lost", "restored", "failsafe", "failsafe_seen"], events
    seen = link[4]
    assert seen["mode"] == "GUIDED" and seen["speed"] <= STILL_SPEED
    assert not [e for e in link if e["event"] == "failsafe_unconfirmed"]
    assert not result.final_state.flying


# -- refusals ---------------------------------------------------------------------------------


def test_a_refused_command_fails_its_behavior_and_the_mission_goes_on(
    tmp_path: Path, procs: list[Proc]
) -> None:
    port = free_udp_port()
    stats_path = tmp_path / "mavsim.json"
    mavsim = start_mavsim(procs, port, stats_path, "--refuse", "MAV_CMD_CONDITION_YAW")
    mission = write_mission(
        tmp_path,
        "    results = [api.executeBehavior('TAKE_OFF')]\n"
        "    results.append(api.executeBehavior('ROTATE', angle=90))\n"
        "    results.append(api.executeBehavior('GO_TO_POINT', relative_coordinates=[1, 0, 0]))\n"
        "    results.append(api.executeBehavior('LAND'))\n"
        "    return results\n",
    )
    result = fly(FlightConfig(mission=mission, connect=f"udpin:127.0.0.1:{port}"))
    stats = stop_mavsim(mavsim, stats_path)

    assert result.outcome.value == [
        "GOAL_ACHIEVED",
        "PROCESS_FAILURE",
        "GOAL_ACHIEVED",
        "GOAL_ACHIEVED",
    ]
    rotate = next(a for a in result.activations if a.behavior == "ROTATE")
    assert rotate.detail == (
        "on_start failed: VehicleCommandError: MAV_CMD_CONDITION_YAW refused: TEMPORARILY_REJECTED"
    )
    yaw_commands = [c for c in stats["commands"] if c["command"] == "MAV_CMD_CONDITION_YAW"]
    assert yaw_commands == [
        {
            "command": "MAV_CMD_CONDITION_YAW",
            "result": "TEMPORARILY_REJECTED",
            "t": yaw_commands[0]["t"],
        }
    ]  # refused once, not retried: a refusal is an answer
    assert stats["final"]["position"][0] == pytest.approx(1.0, abs=0.06)  # went 1 m east
    assert stats["final"]["yaw_deg"] == pytest.approx(0.0, abs=0.5)  # never turned


# -- signing ----------------------------------------------------------------------------------


def test_a_signed_link_flies_and_an_unsigned_sender_is_rejected(
    tmp_path: Path, procs: list[Proc]
) -> None:
    port = free_udp_port()
    stats_path = tmp_path / "mavsim.json"
    mavsim = start_mavsim(procs, port, stats_path, "--signing-key", "pass phrase")
    mission = write_mission(
        tmp_path,
        "    return [api.executeBehavior('TAKE_OFF'), api.executeBehavior('LAND')]\n",
    )
    signed_traffic = MemoryObserver()
    signed = fly(
        FlightConfig(mission=mission, connect=f"udpin:127.0.0.1:{port}", signing_key="pass phrase"),
        observers=[signed_traffic],
    )
    # The same vehicle, now from a ground station without the key.
    unsigned_traffic = MemoryObserver()
    unsigned = fly(
        FlightConfig(
            mission=mission,
            connect=f"udpin:127.0.0.1:{port}",
            ack_timeout=0.2,
            retries=1,
            # Its parameter reads go unanswered too: without this, the preflight refuses.
            allow_no_gcs_failsafe=True,
        ),
        observers=[unsigned_traffic],
    )
    stats = stop_mavsim(mavsim, stats_path)

    assert signed.outcome.value == ["GOAL_ACHIEVED", "GOAL_ACHIEVED"]
    rx, tx = signed_traffic.topics("mavlink/rx"), signed_traffic.topics("mavlink/tx")
    assert rx and tx and all(r["signed"] for r in rx + tx)
    # Without the key, every command goes unanswered: TAKE_OFF fails, LAND is refused
    # (not flying). mavsim rejected exactly what the unsigned station sent.
    assert unsigned.outcome.value == ["PROCESS_FAILURE", "ERROR"]
    take_off = unsigned.activations[0]
    assert take_off.detail.endswith(
        "MAV_CMD_DO_SET_MODE: no COMMAND_ACK after 2 attempts (0.2 s each)"
    )
    unsigned_tx = unsigned_traffic.topics("mavlink/tx")
    assert unsigned_tx and not any(r["signed"] for r in unsigned_tx)
    assert stats["rejected"] == {"bad_signature": len(unsigned_tx)}
    assert Counter(stats["received"]) == Counter(r["type"] for r in tx)


# -- the command line's bad input ------------------------------------------------------------


def test_garbage_and_no_autopilot_exit_2_with_one_line(tmp_path: Path, procs: list[Proc]) -> None:
    port = free_udp_port()
    flight = Proc(
        ["fly", str(APPENDIX_C), "--connect", f"udpin:127.0.0.1:{port}", "--connect-timeout", "1"]
    )
    procs.append(flight)
    flight.wait_for("waiting for a heartbeat")
    sender = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    rng = random.Random(5)
    for _ in range(40):
        sender.sendto(
            bytes(rng.randrange(256) for _ in range(rng.randrange(1, 120))), ("127.0.0.1", port)
        )
    gcs = mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 4, 3).pack(new_codec(254, 1))
    sender.sendto(bytes(gcs), ("127.0.0.1", port))  # a GCS is no autopilot
    sender.sendto(bytes(gcs)[:9], ("127.0.0.1", port))  # a cut-off packet
    sender.close()
    code, _, err = flight.finish()
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(
        f"aeroexec fly: error: no heartbeat from udpin:127.0.0.1:{port} within 1 s ("
    )
    # 40 random datagrams (each one rejection at least), the cut-off packet, and the
    # GCS heartbeat (a good packet, but no autopilot's) are all accounted for.
    assert "bad_prefix" in lines[0] and " truncated" in lines[0]
    assert "1 before_heartbeat ignored)" in lines[0] and "Traceback" not in err


def test_a_signed_ground_station_ignores_an_unsigned_vehicle(tmp_path: Path) -> None:
    port = free_udp_port()
    sim = MavSim(MavSimConfig(url=f"udpout:127.0.0.1:{port}"))
    stop = threading.Event()
    thread = threading.Thread(target=sim.run, args=(stop.is_set,), daemon=True)
    thread.start()
    try:
        result = CliRunner().invoke(
            app,
            [
                "fly",
                str(APPENDIX_C),
                "--connect",
                f"udpin:127.0.0.1:{port}",
                "--signing-key",
                "pass phrase",
                "--connect-timeout",
                "1",
            ],
        )
    finally:
        stop.set()
        thread.join(5)
        sim.close()
    assert result.exit_code == 2
    assert f"no heartbeat from udpin:127.0.0.1:{port} within 1 s (" in result.output
    assert " bad_signature rejected)" in result.output
    assert sim.link.stats.sent["HEARTBEAT"] >= 1  # it did speak, unsigned


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--connect", "tcp4:127.0.0.1:5760"], "unsupported connection 'tcp4:127.0.0.1:5760'"),
        (["--connect", "udpin:0.0.0.0:14550"], "is not a loopback address; pass --allow-remote"),
        (["--failsafe", "panic"], "invalid value for --failsafe: 'panic' is not one of"),
        (["--on-exit", "panic"], "invalid value for --on-exit: 'panic' is not one of"),
        (["--link-timeout", "-1"], "link timeout must be >= 0 seconds"),
        (["--heartbeat-timeout", "0"], "heartbeat timeout must be positive"),
        (["--signing-key", " "], "--signing-key: the signing key is empty"),
    ],
)
def test_bad_fly_options_exit_2_with_one_line(args: list[str], message: str) -> None:
    result = CliRunner().invoke(app, ["fly", str(APPENDIX_C), *args])
    assert result.exit_code == 2
    assert result.output.strip().splitlines() == [f"aeroexec fly: error: {message}"] or (
        message in result.output and len(result.output.strip().splitlines()) == 1
    )


def test_a_missing_mission_exits_2_before_any_link_opens(tmp_path: Path) -> None:
    missing = tmp_path / "nope.py"
    result = CliRunner().invoke(app, ["fly", str(missing)])
    assert result.exit_code == 2
    assert result.output.strip() == f"{missing}: error: no such file"


def test_a_port_already_taken_exits_2_instead_of_sharing_it() -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as other_station:
        other_station.bind(("127.0.0.1", 0))
        port = other_station.getsockname()[1]
        result = CliRunner().invoke(
            app, ["fly", str(APPENDIX_C), "--connect", f"udpin:127.0.0.1:{port}"]
        )
    assert result.exit_code == 2
    assert result.output.strip() == (
        f"aeroexec fly: error: cannot open udpin:127.0.0.1:{port}: Address already in use"
    )


def test_allow_remote_lets_a_non_loopback_endpoint_through(tmp_path: Path) -> None:
    port = free_udp_port()
    result = CliRunner().invoke(
        app,
        [
            "fly",
            str(APPENDIX_C),
            "--connect",
            f"udpin:0.0.0.0:{port}",
            "--allow-remote",
            "--connect-timeout",
            "0.3",
        ],
    )
    assert result.exit_code == 2
    assert f"no heartbeat from udpin:0.0.0.0:{port} within 0.3 s" in result.output


def test_fly_and_mavsim_defaults_are_loopback() -> None:
    fly_help = CliRunner().invoke(app, ["fly", "--help"]).output
    mavsim_help = CliRunner().invoke(app, ["mavsim", "--help"]).output
    assert "udpin:127.0.0.1:14550" in fly_help
    assert "udpout:127.0.0.1:14550" in mavsim_help


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["--refuse", "MAV_CMD_FLY_TO_THE_MOON"],
            "unknown MAVLink command 'MAV_CMD_FLY_TO_THE_MOON'",
        ),
        (["--speed-factor", "0"], "speed factor must be positive"),
        (["--connect", "udpout:10.0.0.1:14550"], "not a loopback address"),
        (["--stats", "/nonexistent/dir/s.json"], "cannot write --stats /nonexistent/dir/s.json"),
    ],
)
def test_bad_mavsim_options_exit_2_with_one_line(args: list[str], message: str) -> None:
    result = CliRunner().invoke(app, ["mavsim", "--duration", "0.1", *args])
    assert result.exit_code == 2
    assert message in result.output and len(result.output.strip().splitlines()) == 1
