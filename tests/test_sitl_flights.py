"""Live flights on the real autopilot: ArduCopter 4.5.6 SITL, one per test.

Each test starts its own SITL (its own `-I` instance, so its ports move by 10, and
`SITL_SPEEDUP`, 8 by default) and `aeroexec fly` as a subprocess, over a different
connection kind each: UDP, TCP (fly connects), TCP (SITL connects), a serial line (two
pseudo-terminals and a relay). Both processes are killed at teardown, pass or fail.
A second MAVLink connection to SITL's SERIAL1 (TCP 5762 + 10 x instance, system id 250,
never a heartbeat, so ArduPilot's GCS failsafe does not count it) is the test's own
view of the vehicle: what the autopilot itself says about mode, arming and landing.

The binary is found at `../shared/sitl/arducopter` (beside the repository) or at
`$AEROEXEC_SITL`, with `copter.parm` beside it; without it these tests are skipped.
Timeouts are wall-clock seconds with a wide margin: the machine may be busy.
"""

from __future__ import annotations

import itertools
import math
import os
import re
import select
import signal
import socket
import subprocess
import threading
import time
import tty
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from foxglove_client import FoxgloveClient
from live_helpers import AeroexecProcess, cpu_loaded, free_tcp_port, free_udp_port, write_mission
from test_live import assert_parity

from aeroexec.mission.paths import APPENDIX_C
from aeroexec.properties.check import check_recording
from aeroexec.properties.spec import load_properties
from aeroexec.recording import open_recording
from aeroexec.recording.reader import RecordedTopic
from aeroexec.replay.engine import Mode, ReplayOptions, replay_recording
from aeroexec.replay.inject import parse_injection

#: How far from the position at a SIGTERM at ~7.5 m/s the vehicle may touch down: what
#: ArduCopter needs to stop (measured on SITL: ~15 m in BRAKE), with a margin. See the
#: landing test; within 2 m is beyond its lean and jerk limits.
LANDING_BOUND_M = 20.0

REPO = Path(__file__).resolve().parents[1]
BINARY = Path(os.environ.get("AEROEXEC_SITL") or REPO.parent / "shared" / "sitl" / "arducopter")
PARM = BINARY.parent / "copter.parm"
SPEEDUP = float(os.environ.get("SITL_SPEEDUP", "8"))
#: SITL instances 30 and up (ports 6060+, away from a SITL someone runs by hand, 0..9).
INSTANCES = itertools.count(30 + 10 * (os.getpid() % 10))


def free_instance() -> int:
    """The next instance whose TCP ports (5760, 5762, 5763 + 10 x instance) can be bound
    now: a SITL that just stopped leaves its ports in TIME_WAIT for a minute, and SITL
    cannot bind them then ("bind failed on port 6062"); another worktree's tests may
    be flying SITLs too."""
    for instance in INSTANCES:
        try:
            for port in (5760, 5762, 5763):
                with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
                    s.bind(("0.0.0.0", port + 10 * instance))
        except OSError:
            continue
        return instance
    raise AssertionError("no free SITL instance")


pytestmark = pytest.mark.skipif(
    not (BINARY.is_file() and os.access(BINARY, os.X_OK) and PARM.is_file()),
    reason=f"ArduCopter SITL not found at {BINARY} (with copter.parm beside it); "
    "set AEROEXEC_SITL to the arducopter binary",
)

LAND_MODE, GUIDED_MODE = 9, 4
ON_GROUND = 1  # MAV_LANDED_STATE_ON_GROUND
#: A leg long enough (60 m at 3 m/s, ~2.5 s of wall time at 8x) to act in its middle.
FAR_LEG = "[0, 60, 2]"
SLOW = {"WPNAV_SPEED": 300.0}  # cm/s: GUIDED's horizontal speed


# -- the harness -------------------------------------------------------------------------------


class Sitl:
    """One ArduCopter SITL process (`start-sitl`'s arguments, minus the shell)."""

    def __init__(
        self,
        workdir: Path,
        *,
        serial0: str | None = None,
        params: dict[str, float] | None = None,
    ) -> None:
        self.instance = free_instance()
        self.workdir = workdir / f"sitl{self.instance}"
        self.workdir.mkdir()
        defaults = str(PARM)
        # copter.parm leaves ArduCopter's GCS failsafe off (FS_GCS_ENABLE 0), which fly's
        # preflight refuses: these flights have it on (land), as a real vehicle should.
        params = {"FS_GCS_ENABLE": 5.0, **(params or {})}
        if params:
            extra = self.workdir / "test.parm"
            extra.write_text("".join(f"{name} {value:g}\n" for name, value in params.items()))
            defaults += f",{extra}"
        args = [str(BINARY), "--model", "quad", "--speedup", f"{SPEEDUP:g}"]
        args += ["--defaults", defaults, "-I", str(self.instance)]
        if serial0 is not None:
            args += ["--serial0", serial0]
        self.log = (self.workdir / "sitl.log").open("wb")
        self.proc = subprocess.Popen(
            args, cwd=self.workdir, stdout=self.log, stderr=subprocess.STDOUT
        )

    @property
    def tcp_port(self) -> int:
        """SERIAL0's TCP server (when started without `serial0`)."""
        return 5760 + 10 * self.instance

    @property
    def monitor_port(self) -> int:
        return 5762 + 10 * self.instance

    def signal(self, signum: int) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signum)

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGCONT)  # a stopped process cannot act on TERM
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(5)
        self.log.close()


class Monitor:
    """The test's own MAVLink view of SITL, on SERIAL1."""

    def __init__(self, sitl: Sitl) -> None:
        from pymavlink import mavutil

        self.conn = mavutil.mavlink_connection(
            f"tcp:127.0.0.1:{sitl.monitor_port}", source_system=250, source_component=0, retries=30
        )
        self.armed: bool | None = None
        self.mode: int | None = None
        self.landed: int | None = None
        self.position: tuple[float, float, float] | None = None
        self.velocity: tuple[float, float, float] | None = None
        for message_id in (245, 32):  # EXTENDED_SYS_STATE, LOCAL_POSITION_NED at 4 Hz
            self.conn.mav.command_long_send(1, 1, 511, 0, message_id, 250000, 0, 0, 0, 0, 0)

    def wait_for(self, predicate: Callable[[Monitor], bool], timeout: float) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            msg = self.conn.recv_match(
                type=["HEARTBEAT", "EXTENDED_SYS_STATE", "LOCAL_POSITION_NED"],
                blocking=True,
                timeout=0.5,
            )
            if msg is None:
                continue
            kind = msg.get_type()
            if kind == "HEARTBEAT" and msg.get_srcComponent() == 1 and msg.type != 6:
                self.armed = bool(msg.base_mode & 128)
                self.mode = int(msg.custom_mode)
            elif kind == "EXTENDED_SYS_STATE":
                self.landed = int(msg.landed_state)
            elif kind == "LOCAL_POSITION_NED":
                self.position = (float(msg.x), float(msg.y), float(msg.z))
                self.velocity = (float(msg.vx), float(msg.vy), float(msg.vz))
            if None not in (self.armed, self.landed) and predicate(self):
                return True
        return False

    def down(self, timeout: float = 60.0) -> bool:
        """Wait until the autopilot says landed and disarmed."""
        return self.wait_for(lambda m: m.landed == ON_GROUND and m.armed is False, timeout)

    def positions_for(self, seconds: float) -> list[tuple[float, float, float]]:
        """Every position the autopilot reports during the next `seconds` (what it sent
        before, while nobody read this connection, is skipped)."""
        while self.conn.recv_match(blocking=False) is not None:
            pass
        self.position = None  # only what arrives from now on
        seen: list[tuple[float, float, float]] = []

        def note(m: Monitor) -> bool:
            if m.position is not None:
                seen.append(m.position)
            return False

        self.wait_for(note, seconds)
        return seen

    def command(self, command: int, *params: float) -> None:
        """A COMMAND_LONG to the autopilot, as a second ground station would send it."""
        p = (*params, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)[:7]
        self.conn.mav.command_long_send(1, 1, command, 0, *p)

    def set_parameter(self, name: str, value: float, timeout: float = 10.0) -> None:
        """PARAM_SET, as a second ground station would send it; returns once the
        autopilot's PARAM_VALUE echoes the new value."""
        from pymavlink import mavutil

        float_type = mavutil.mavlink.MAV_PARAM_TYPE_REAL32
        self.conn.mav.param_set_send(1, 1, name.encode("ascii"), value, float_type)
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            msg = self.conn.recv_match(type="PARAM_VALUE", blocking=True, timeout=0.5)
            if msg is not None and msg.param_id == name and math.isclose(msg.param_value, value):
                return
        raise AssertionError(f"the autopilot did not confirm {name} = {value:g}")

    def land_now(self, timeout: float = 90.0) -> bool:
        """Switch to LAND (MAV_CMD_DO_SET_MODE) and wait until landed and disarmed."""
        self.command(176, 1.0, float(LAND_MODE))
        return self.down(timeout)

    def close(self) -> None:
        self.conn.close()


class Fly(AeroexecProcess):
    """`aeroexec fly` in a subprocess (SITL flights take their time)."""

    wait_s = 120.0
    finish_s = 180.0

    def __init__(self, args: list[str]) -> None:
        super().__init__(["fly", *args])


@pytest.fixture
def flight(tmp_path: Path) -> Iterator[Callable[..., Any]]:
    """Starts SITLs, monitors and fly processes; kills them all at teardown."""
    started: list[Any] = []

    def start(kind: type, *args: Any, **kwargs: Any) -> Any:
        thing = kind(*args, **kwargs)
        started.append(thing)
        return thing

    yield start
    for thing in reversed(started):
        if isinstance(thing, Fly):
            thing.kill()
        elif isinstance(thing, Sitl):
            thing.stop()
        else:
            thing.close()


def fly_args(mission: Path, url: str, record: Path, *extra: str) -> list[str]:
    return [
        str(mission),
        "--connect",
        url,
        "--output",
        str(record),
        "--connect-timeout",
        "120",
        *extra,
    ]


def recorded(record: Path) -> tuple[bool, dict[str, list[Any]]]:
    recording = open_recording(record)
    topics: dict[str, list[Any]] = {}
    for item in recording.records():
        if isinstance(item, RecordedTopic):
            topics.setdefault(item.name, []).append(item.data)
    return recording.complete, topics


def link_events(topics: dict[str, list[Any]]) -> list[str]:
    return [e["event"] for e in topics.get("mavlink/link", []) if e["event"] != "connection"]


def assert_replays_unchanged(record: Path, mission: Path | None = None) -> None:
    """Open loop, closed loop on the recorded commands, and (given the mission)
    closed loop running the mission script again: no differences."""
    options = [ReplayOptions(mode=Mode.open), ReplayOptions(mode=Mode.closed)]
    if mission is not None:
        options.append(ReplayOptions(mode=Mode.closed, mission=str(mission)))
    for option in options:
        replayed = replay_recording(record, option)
        assert replayed.diff is not None and replayed.diff.compared > 0
        assert replayed.equal, (option, [d.message for d in replayed.diff.differences])


@contextmanager
def null_modem() -> Iterator[tuple[str, str]]:
    """Two pseudo-terminals joined by a relay thread: a serial cable."""
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
                    os.write(masters[1 - masters.index(fd)], os.read(fd, 4096))
                except OSError:
                    continue

    thread = threading.Thread(target=relay, daemon=True)
    thread.start()
    try:
        yield os.ttyname(slaves[0]), os.ttyname(slaves[1])
    finally:
        stop.set()
        thread.join(5)
        for fd in masters + slaves:
            os.close(fd)


# -- whole missions ----------------------------------------------------------------------------


def test_appendix_c_over_udp_lands_and_replays_unchanged(tmp_path: Path, flight: Any) -> None:
    port = free_udp_port()
    record = tmp_path / "flight.mcap"
    fly = flight(Fly, fly_args(APPENDIX_C, f"udpin:127.0.0.1:{port}", record))
    sitl = flight(Sitl, tmp_path, serial0=f"udpclient:127.0.0.1:{port}")
    code, out, err = fly.finish()

    assert code == 0, err
    assert "7 activations: 6 GOAL_ACHIEVED, 0 rejected" in out
    assert "ending: vehicle on the ground at (" in out and "in LAND, disarmed" in out
    monitor = flight(Monitor, sitl)
    assert monitor.down(timeout=30) and monitor.mode == LAND_MODE
    complete, topics = recorded(record)
    assert complete
    assert link_events(topics) == ["connected", "mission_end", "ending"]
    assert [e["code"] for e in topics["behavior_event"]].count("GOAL_ACHIEVED") == 6
    acks = [r["fields"] for r in topics["mavlink/rx"] if r["type"] == "COMMAND_ACK"]
    assert acks and all(a["result"] == 0 for a in acks)  # every command ACCEPTED
    assert_replays_unchanged(record, APPENDIX_C)
    # What aeroexec's semantics promise holds on the real autopilot's flight too.
    safety = check_recording(record, load_properties(["aeroexec:safety"]))
    assert {v.name: v.status for v in safety.verdicts} == {
        "compatible_capabilities": "held",
        "activations_answered": "held",
        "ends_landed_disarmed": "held",
        "grounded_lands": "held",
    }


LONGER = (
    "    results = [api.executeBehavior('TAKE_OFF')]\n"
    "    results.append(api.executeBehavior('GO_TO_POINT', coordinates=[0, 0, 2]))\n"
    "    for x, y, angle in [(4, 0, 0), (4, 4, 90), (0, 4, 180), (0, 0, -90)]:\n"
    "        results.append(api.executeBehavior('GO_TO_POINT', coordinates=[x, y, 2]))\n"
    "        results.append(api.executeBehavior('ROTATE', angle=angle))\n"
    "    results.append(api.executeBehavior('START_MOVING', direction='FORWARD', speed=1))\n"
    "    results.append(api.executeBehavior('GO_TO_POINT', relative_coordinates=[0, 0, -1]))\n"
    "    results.append(api.executeBehavior('WAIT', duration=1))\n"
    "    results.append(api.executeBehavior('LAND'))\n"
    "    return results\n"
)


def test_fly_live_on_sitl_serves_exactly_the_recording(tmp_path: Path, flight: Any) -> None:
    """`fly --live` on the real autopilot: a foxglove.sdk.v1 client connected before the
    mission starts receives every message of the recording, byte for byte (issue 28)."""
    port = free_udp_port()
    record = tmp_path / "flight.mcap"
    args = fly_args(APPENDIX_C, f"udpin:127.0.0.1:{port}", record)
    fly = flight(Fly, [*args, "--live", "--port", "0", "--rerun-port", "0", "--wait-viewer"])
    url = fly.wait_for("live: Foxglove, Lichtblick: ").split(": ")[-1].strip()
    flight(Sitl, tmp_path, serial0=f"udpclient:127.0.0.1:{port}")
    client = FoxgloveClient(url).start()
    code, out, err = fly.finish()

    assert code == 0, err
    assert "7 activations: 6 GOAL_ACHIEVED, 0 rejected" in out
    client.wait_closed()
    assert_parity(client, record)
    assert {"/drone1/mavlink/rx", "/drone1/vehicle/state"} <= {m.topic for m in client.messages}


def test_a_longer_mission_over_tcp(tmp_path: Path, flight: Any) -> None:
    record = tmp_path / "flight.mcap"
    mission = write_mission(tmp_path, LONGER)
    sitl = flight(Sitl, tmp_path)  # SERIAL0: a TCP server waiting for its client
    fly = flight(Fly, fly_args(mission, f"tcp:127.0.0.1:{sitl.tcp_port}", record))
    code, out, err = fly.finish()

    assert code == 0, err
    assert "14 activations: 14 GOAL_ACHIEVED, 0 rejected" in out
    monitor = flight(Monitor, sitl)
    assert monitor.down(timeout=30)
    assert monitor.wait_for(lambda m: m.position is not None, 10)
    assert monitor.position is not None and abs(monitor.position[0]) < 6.0
    complete, topics = recorded(record)
    assert complete and link_events(topics) == ["connected", "mission_end", "ending"]
    velocity = [r for r in topics["mavlink/tx"] if r["type"] == "SET_POSITION_TARGET_LOCAL_NED"]
    assert any(r["fields"]["type_mask"] == 0x9C7 for r in velocity)  # START_MOVING's
    assert_replays_unchanged(record, mission)


# -- losing the link ---------------------------------------------------------------------------


def test_sitl_stopped_mid_flight_is_a_lost_link_then_the_failsafe_lands(
    tmp_path: Path, flight: Any
) -> None:
    port = free_udp_port()
    record = tmp_path / "flight.mcap"
    mission = write_mission(
        tmp_path,
        "    return [api.executeBehavior('TAKE_OFF'),\n"
        f"            api.executeBehavior('GO_TO_POINT', coordinates={FAR_LEG})]\n",
    )
    args = fly_args(mission, f"udpin:127.0.0.1:{port}", record, "--heartbeat-timeout", "1")
    fly = flight(Fly, args)
    sitl = flight(Sitl, tmp_path, serial0=f"udpclient:127.0.0.1:{port}", params=SLOW)
    fly.wait_for("start    GO_TO_POINT")
    time.sleep(1.0)
    sitl.signal(signal.SIGSTOP)  # the autopilot freezes: no heartbeat, no telemetry
    fly.wait_for("end      GO_TO_POINT", timeout=30)
    time.sleep(1.0)
    sitl.signal(signal.SIGCONT)
    code, out, err = fly.finish()

    assert code == 1
    assert "GO_TO_POINT PROCESS_FAILURE" in out and "(vehicle fault: link_lost)" in out
    assert (
        err.strip()
        .splitlines()[-1]
        .startswith(
            "aeroexec fly: the link was lost 1 time during the flight; vehicle on the ground at ("
        )
    )
    complete, topics = recorded(record)
    assert complete
    assert link_events(topics) == [
        "connected",
        "lost",
        "mission_end",
        "restored",
        "failsafe",
        "failsafe_seen",
        "ending",
    ]
    failsafe = next(e for e in topics["mavlink/link"] if e["event"] == "failsafe")
    assert failsafe["action"] == "land"
    monitor = flight(Monitor, sitl)
    assert monitor.down(timeout=60) and monitor.mode == LAND_MODE
    assert monitor.wait_for(lambda m: m.position is not None, 10)
    assert monitor.position is not None and 1.0 < monitor.position[0] < 55.0  # short of 60 m
    assert_replays_unchanged(record, mission)


def test_sitl_killed_mid_flight_ends_fly_with_the_vehicle_last_seen(
    tmp_path: Path, flight: Any
) -> None:
    record = tmp_path / "flight.mcap"
    mission = write_mission(
        tmp_path,
        "    return [api.executeBehavior('TAKE_OFF'),\n"
        f"            api.executeBehavior('GO_TO_POINT', coordinates={FAR_LEG})]\n",
    )
    sitl = flight(Sitl, tmp_path, params=SLOW)
    url = f"tcp:127.0.0.1:{sitl.tcp_port}"
    fly = flight(Fly, fly_args(mission, url, record, "--link-timeout", "2"))
    fly.wait_for("start    GO_TO_POINT")
    time.sleep(1.0)
    sitl.signal(signal.SIGKILL)
    code, _, err = fly.finish()

    assert code == 1
    line = err.strip().splitlines()[-1]
    assert line.startswith(
        "aeroexec fly: vehicle not landed: link lost, no heartbeat for 2 s; last seen flying at ("
    ), err
    assert " m in GUIDED, armed, " in line and line.endswith(" s ago")
    complete, topics = recorded(record)
    assert complete  # the recording has its footer although the vehicle is gone
    lost = next(e for e in topics["mavlink/link"] if e["event"] == "lost")
    # TCP: known at once, from the connection (an EOF or a reset, as the kernel has it),
    # not after the 3 s heartbeat timeout.
    assert lost["why"] in ("closed by the peer", "Connection reset by peer")
    assert lost["silent_s"] < 1.0
    ending = topics["mavlink/link"][-1]
    assert ending["event"] == "ending" and not ending["down"]


# -- stopping fly ------------------------------------------------------------------------------


def test_sigterm_of_fly_mid_flight_lands_finalizes_and_exits_143(
    tmp_path: Path, flight: Any
) -> None:
    port = free_tcp_port()
    record = tmp_path / "flight.mcap"
    mission = write_mission(
        tmp_path,
        "    return [api.executeBehavior('TAKE_OFF'),\n"
        f"            api.executeBehavior('GO_TO_POINT', coordinates={FAR_LEG})]\n",
    )
    # fly listens; SITL is the TCP client (as a companion computer's router would be).
    fly = flight(Fly, fly_args(mission, f"tcpin:127.0.0.1:{port}", record))
    fly.wait_for("waiting for a heartbeat")
    sitl = flight(Sitl, tmp_path, serial0=f"tcpclient:127.0.0.1:{port}", params=SLOW)
    fly.wait_for("start    GO_TO_POINT")
    time.sleep(1.0)
    fly.popen.send_signal(signal.SIGTERM)
    code, _, err = fly.finish()

    assert code == 143
    (line,) = err.strip().splitlines()
    assert line.startswith("aeroexec fly: interrupted by SIGTERM; vehicle on the ground at (")
    assert line.endswith(f"in LAND, disarmed; recording finalized: {record}")
    complete, topics = recorded(record)
    assert complete
    mission_end = next(e for e in topics["mavlink/link"] if e["event"] == "mission_end")
    assert mission_end["how"] == "SIGTERM"
    ending = topics["mavlink/link"][-1]
    assert ending["down"] and ending["actions"][0] == "inhibited GO_TO_POINT"
    # At speed it brakes first, seen holding; then LAND, seen in the autopilot's HEARTBEAT.
    assert ending["actions"][1].startswith("braked: seen holding in BRAKE at (")
    assert ending["actions"][2].startswith("switched to LAND: seen in LAND ")
    interrupted = [e for e in topics["behavior_event"] if e["code"] == "INTERRUPTED"]
    assert [e["name"] for e in interrupted] == ["GO_TO_POINT"]
    monitor = flight(Monitor, sitl)
    assert monitor.down(timeout=30) and monitor.mode == LAND_MODE
    assert_replays_unchanged(record, mission)


def test_sigkill_of_fly_leaves_it_to_the_autopilots_gcs_failsafe(
    tmp_path: Path, flight: Any
) -> None:
    """fly's own 1 Hz heartbeat is what ArduPilot's GCS failsafe watches: when fly dies
    without an ending, the autopilot lands by itself (FS_GCS_ENABLE 5: always land)."""
    mission = write_mission(
        tmp_path,
        "    return [api.executeBehavior('TAKE_OFF'),\n"
        f"            api.executeBehavior('GO_TO_POINT', coordinates={FAR_LEG})]\n",
    )
    with null_modem() as (ground, vehicle):
        sitl = flight(
            Sitl, tmp_path, serial0=f"uart:{vehicle}:57600", params={**SLOW, "FS_GCS_ENABLE": 5}
        )
        fly = flight(Fly, fly_args(mission, f"{ground},57600", tmp_path / "flight.mcap"))
        fly.wait_for("start    GO_TO_POINT")
        monitor = flight(Monitor, sitl)
        assert monitor.wait_for(lambda m: m.mode == GUIDED_MODE and m.armed is True, 30)
        fly.popen.kill()
        fly.popen.wait(10)
        assert monitor.wait_for(lambda m: m.mode == LAND_MODE, timeout=30)
        assert monitor.down(timeout=60)


# -- runtime assurance: fly --spec -------------------------------------------------------------

GEOFENCE = """\
properties:
  - name: geofence
    description: stay within 15 m of home
    formula: always(distance_home <= 15)
    action: land
"""


def test_a_geofence_in_fly_spec_lands_at_the_fence(tmp_path: Path, flight: Any) -> None:
    """The property's action ends the flight with LAND where the fence is crossed, on the
    real autopilot: not at the mission's target 60 m away."""
    port = free_udp_port()
    record = tmp_path / "flight.mcap"
    spec = tmp_path / "fence.yaml"
    spec.write_text(GEOFENCE, encoding="utf-8")
    mission = write_mission(
        tmp_path,
        "    api.executeBehavior('TAKE_OFF')\n"
        f"    api.executeBehavior('GO_TO_POINT', coordinates={FAR_LEG})\n"
        "    api.executeBehavior('LAND')\n",
    )
    fly = flight(Fly, fly_args(mission, f"udpin:127.0.0.1:{port}", record, "--spec", str(spec)))
    sitl = flight(Sitl, tmp_path, serial0=f"udpclient:127.0.0.1:{port}", params=SLOW)
    code, out, err = fly.finish()

    assert code == 1, err  # the property was violated
    assert "error geofence: stay within 15 m of home: violated" in out
    assert "mission stopped: property geofence violated at" in err
    assert "ending: switched to LAND" in out
    monitor = flight(Monitor, sitl)
    assert monitor.down(timeout=60) and monitor.mode == LAND_MODE
    assert monitor.wait_for(lambda m: m.position is not None, 10)
    assert monitor.position is not None
    distance = (monitor.position[0] ** 2 + monitor.position[1] ** 2) ** 0.5
    assert 15.0 < distance < 25.0, monitor.position  # at the fence, not at 60 m
    complete, topics = recorded(record)
    assert complete
    [early, *_] = topics["properties"]
    assert early["property"] == "geofence" and early["action"] == "land"


# -- refusals and the failsafe preflight -------------------------------------------------------

TAKE_OFF_AND_LAND = "    return [api.executeBehavior('TAKE_OFF'), api.executeBehavior('LAND')]\n"


def test_refused_arming_exits_1_with_the_autopilots_reason_and_replays_unchanged(
    tmp_path: Path, flight: Any
) -> None:
    """ArduCopter refuses to arm below BATT_ARM_VOLT (SITL's battery: 12.6 V): TAKE_OFF
    ends PROCESS_FAILURE at once, fly exits 1 and says why in the autopilot's words."""
    port = free_udp_port()
    record = tmp_path / "flight.mcap"
    mission = write_mission(tmp_path, TAKE_OFF_AND_LAND)
    fly = flight(Fly, fly_args(mission, f"udpin:127.0.0.1:{port}", record))
    sitl = flight(
        Sitl, tmp_path, serial0=f"udpclient:127.0.0.1:{port}", params={"BATT_ARM_VOLT": 20.0}
    )
    code, out, err = fly.finish()

    assert code == 1, out + err
    assert "Battery 1 below minimum arming voltage" in out  # printed as the autopilot said it
    # The autopilot's pre-arm verdict, reported before the mission starts.
    lines = out.splitlines()
    start = next(i for i, line in enumerate(lines) if "start    TAKE_OFF" in line)
    assert "preflight: pre-arm failure: SYS_STATUS unhealthy: PREARM_CHECK" in lines[:start]
    assert "end      TAKE_OFF PROCESS_FAILURE after 0.0 s (" in out
    failed = [line for line in err.splitlines() if "mission failed: TAKE_OFF" in line]
    assert failed and "MAV_CMD_COMPONENT_ARM_DISARM refused: FAILED (autopilot: " in failed[0]
    assert "Battery 1 below minimum arming voltage" in failed[0]
    monitor = flight(Monitor, sitl)
    assert monitor.wait_for(lambda m: True, 30) and monitor.armed is False
    assert_replays_unchanged(record, mission)


def test_a_gcs_failsafe_that_is_off_is_refused_before_arming(tmp_path: Path, flight: Any) -> None:
    """copter.parm's FS_GCS_ENABLE 0: fly reads it at connect and refuses, nothing armed."""
    port = free_udp_port()
    record = tmp_path / "flight.mcap"
    mission = write_mission(tmp_path, TAKE_OFF_AND_LAND)
    fly = flight(Fly, fly_args(mission, f"udpin:127.0.0.1:{port}", record))
    sitl = flight(
        Sitl, tmp_path, serial0=f"udpclient:127.0.0.1:{port}", params={"FS_GCS_ENABLE": 0.0}
    )
    code, out, err = fly.finish()

    assert code == 2, out + err
    assert "preflight: GCS failsafe off;" in out
    (line,) = err.strip().splitlines()
    assert line.startswith(
        "aeroexec fly: error: the autopilot's GCS failsafe is off (FS_GCS_ENABLE=0): "
    )
    assert line.endswith("or pass --allow-no-gcs-failsafe; nothing was armed")
    assert not record.exists()
    monitor = flight(Monitor, sitl)
    assert monitor.wait_for(lambda m: m.mode is not None, 30)
    assert monitor.armed is False and monitor.mode != GUIDED_MODE  # never commanded


# -- confirmed endings -------------------------------------------------------------------------


HOLD_AT = re.compile(
    r"ending: braked: seen holding in GUIDED at \((-?[\d.]+), (-?[\d.]+), (-?[\d.]+)\) m"
)
#: How many --on-exit hold flights the hold test makes (SITL_HOLD_RUNS to change it).
HOLD_RUNS = int(os.environ.get("SITL_HOLD_RUNS", "10"))


def test_on_exit_hold_over_tcp_holds_10_of_10_with_the_cpu_loaded(
    tmp_path: Path, flight: Any
) -> None:
    """The mission returns in the middle of a 60 m leg; fly must report the hold only
    once the autopilot shows it, and the vehicle must still be there after fly has
    closed the TCP connection (a GCS failsafe 60 s away, so it is the hold we see).
    The test lands it from its own connection before the next flight."""
    mission = write_mission(
        tmp_path,
        "    api.executeBehavior('TAKE_OFF')\n"
        "    api.activateBehavior('GO_TO_POINT', relative_coordinates=[0, 40, 1])\n"
        "    return api.executeBehavior('WAIT', duration=1)\n",
    )
    # Ten flights would drain the simulated 3.3 Ah battery below what TAKE_OFF accepts.
    params = {**SLOW, "FS_GCS_TIMEOUT": 60.0, "BATT_CAPACITY": 100000.0}
    sitl = flight(Sitl, tmp_path, params=params)
    monitor = None
    held = []
    start = 0.0  # y (north) where the flight starts: where the last one was landed
    with cpu_loaded():
        for run in range(HOLD_RUNS):
            record = tmp_path / f"hold{run}.mcap"
            url = f"tcp:127.0.0.1:{sitl.tcp_port}"
            fly = flight(Fly, fly_args(mission, url, record, "--on-exit", "hold"))
            code, out, err = fly.finish()
            assert code == 1, out + err
            seen = HOLD_AT.search(out)
            assert seen is not None, out + err
            x, y, _ = (float(v) for v in seen.groups())
            if monitor is None:  # SITL's second port is up once fly has flown
                monitor = flight(Monitor, sitl)
            # Two seconds of the autopilot's own positions after fly is gone.
            positions = monitor.positions_for(2.0)
            assert positions and monitor.mode == GUIDED_MODE
            drift = max(math.hypot(p[1] - x, p[0] - y) for p in positions)  # NED vs ENU
            held.append(drift < 1.0)
            print(f"run {run}: seen holding at ({x}, {y}); {drift:.2f} m off it after fly exited")
            assert 1.0 < y - start < 38.0, (start, y)  # stopped on the leg, short of its end
            assert monitor.land_now(), "the test could not land the vehicle"
            start = monitor.positions_for(0.5)[-1][0]
    print(f"held {sum(held)} of {len(held)} over TCP with the CPU loaded")
    assert all(held), held


def test_sigterm_at_speed_brakes_then_lands_where_it_stopped(tmp_path: Path, flight: Any) -> None:
    """At ~7.5 m/s a SIGTERM makes fly brake in BRAKE (ArduCopter's hardest stop), see
    it holding, then LAND: the vehicle comes down where it stopped. Where it stopped is
    as far from the signal as ArduCopter needs to stop (measured: ~15 m from 7.4 m/s, in
    5.6 s; at most ~5.7 m/s2 at its 30 degree lean limit, so never within 2 m): see
    docs/mavlink.md. The old LAND-at-once landed 11-19 m on, wherever the descent ended."""
    record = tmp_path / "flight.mcap"
    mission = write_mission(
        tmp_path,
        "    return [api.executeBehavior('TAKE_OFF'),\n"
        "            api.executeBehavior('GO_TO_POINT', coordinates=[0, 100, 3])]\n",
    )
    sitl = flight(Sitl, tmp_path, params={"WPNAV_SPEED": 770.0})
    fly = flight(Fly, fly_args(mission, f"tcp:127.0.0.1:{sitl.tcp_port}", record))
    fly.wait_for("start    GO_TO_POINT")
    monitor = flight(Monitor, sitl)
    fast = monitor.wait_for(
        lambda m: m.velocity is not None and math.hypot(m.velocity[0], m.velocity[1]) > 7.0,
        60,
    )
    assert fast, "never reached 7 m/s"
    fly.popen.send_signal(signal.SIGTERM)
    code, out, err = fly.finish()
    assert code == 143, out + err
    assert monitor.down(timeout=60)
    assert monitor.wait_for(lambda m: m.position is not None, 10)
    assert monitor.position is not None
    touchdown = (monitor.position[1], monitor.position[0])  # NED -> ENU (x east, y north)
    complete, topics = recorded(record)
    assert complete
    actions = topics["mavlink/link"][-1]["actions"]
    braked = re.fullmatch(
        r"braked: seen holding in BRAKE at \((-?[\d.]+), (-?[\d.]+), (-?[\d.]+)\) m, .*",
        actions[1],
    )
    assert braked is not None, actions
    assert actions[2].startswith("switched to LAND: seen in LAND"), actions
    # Where fly was when the signal stopped the mission: its last state before mission_end.
    end_ns = next(
        t for t, e in topics_with_times(record, "mavlink/link") if e["event"] == "mission_end"
    )
    at_signal = [s for t, s in topics_with_times(record, "vehicle/state") if t <= end_ns][-1]
    speed = math.hypot(*at_signal["velocity"][:2])
    stopped = (float(braked.group(1)), float(braked.group(2)))
    from_signal = math.dist(touchdown, at_signal["position"][:2])
    print(
        f"SIGTERM at {speed:.1f} m/s: stopped {math.dist(stopped, at_signal['position'][:2]):.1f}"
        f" m on, touched down {from_signal:.1f} m from the position at the signal, "
        f"{math.dist(touchdown, stopped):.2f} m from where it stopped"
    )
    assert speed > 6.5
    assert math.dist(touchdown, stopped) < 1.0  # straight down from where it stopped
    assert from_signal < LANDING_BOUND_M, from_signal


def topics_with_times(record: Path, name: str) -> list[tuple[int, Any]]:
    return [
        (item.log_time_ns, item.data)
        for item in open_recording(record).records()
        if isinstance(item, RecordedTopic) and item.name == name
    ]


# -- what if: a fault struck on the real autopilot (issue 26) ----------------------------------

#: Out 60 m, back, land: the fault strikes on the way out, long before the leg's end.
OUT_AND_BACK = (
    "    results = [api.executeBehavior('TAKE_OFF')]\n"
    f"    results.append(api.executeBehavior('GO_TO_POINT', coordinates={FAR_LEG}))\n"
    "    results.append(api.executeBehavior('GO_TO_POINT', coordinates=[0, 0, 2]))\n"
    "    results.append(api.executeBehavior('LAND'))\n"
    "    return results\n"
)


@dataclass(frozen=True)
class AutopilotFault:
    """A fault of the simulator's registry and its counterpart on ArduCopter SITL."""

    #: What explore strikes in the simulator (at end:TAKE_OFF).
    simulated: str
    #: SITL's failsafe settings, at start.
    params: dict[str, float]
    #: The simulation parameter set at the moment, and its value.
    parameter: tuple[str, float]
    #: The autopilot's STATUSTEXT that says its failsafe took over.
    failsafe: str
    #: The vehicle fault the simulator reports, and why it refuses the next leg.
    reports: str
    refusal: str


AUTOPILOT_FAULTS = {
    # ArduCopter's battery failsafe: LAND when the voltage stays below 10.5 V for 2 s;
    # SITL's battery is 12.6 V full. The simulator's empty battery forces a landing.
    "empty battery": AutopilotFault(
        "low_battery:level=0",
        {"BATT_FS_LOW_ACT": 1.0, "BATT_LOW_VOLT": 10.5, "BATT_LOW_TIMER": 2.0},
        ("SIM_BATT_VOLTAGE", 10.0),
        "Battery Failsafe",
        "battery_empty",
        "the battery is empty (landing)",
    ),
    # The GPS gone: ArduCopter's EKF failsafe (FS_EKF_ACTION's default, LAND) once its
    # variances grow. The simulator's lost position lands where it is.
    "lost position": AutopilotFault(
        "lost_position",
        {},
        ("SIM_GPS_DISABLE", 1.0),
        "EKF Failsafe: changed to LAND Mode",
        "position_lost",
        "no position estimate",
    ),
}


def behavior_events(record: Path) -> list[tuple[str, str, str]]:
    """(name, code, detail) of every behavior event, in order."""
    _, topics = recorded(record)
    return [(e["name"], e["code"], e["detail"]) for e in topics.get("behavior_event", [])]


@pytest.mark.parametrize("fault", AUTOPILOT_FAULTS.values(), ids=AUTOPILOT_FAULTS.keys())
def test_a_fault_struck_on_the_autopilot_makes_the_executive_decide_as_in_the_simulator(
    tmp_path: Path, flight: Any, fault: AutopilotFault
) -> None:
    """The counterexample explore would strike at end:TAKE_OFF, struck on the real
    autopilot through its own simulation parameters when fly prints TAKE_OFF's end:
    ArduCopter's failsafe (LAND) takes over. The executive decides the same in both: the
    same behaviors end with the same codes in the same order. What differs is the cause
    it is told, explained in docs/whatif.md ("On the real autopilot"): the simulator
    reports its fault, over MAVLink the executive sees only that the autopilot left
    GUIDED for LAND (`mode_changed:LAND`)."""
    record = tmp_path / "flight.mcap"
    mission = write_mission(tmp_path, OUT_AND_BACK)
    sitl = flight(Sitl, tmp_path, params={**SLOW, **fault.params})
    fly = flight(Fly, fly_args(mission, f"tcp:127.0.0.1:{sitl.tcp_port}", record))
    fly.wait_for("start    TAKE_OFF")
    monitor = flight(Monitor, sitl)  # connected before the moment, to strike without delay
    fly.wait_for("end      TAKE_OFF GOAL_ACHIEVED")
    monitor.set_parameter(*fault.parameter)
    code, out, err = fly.finish()

    assert code == 1, out + err  # the mission's goals failed; the vehicle is down
    assert f"autopilot: {fault.failsafe}" in out
    assert "ending: vehicle on the ground at (" in out and "in LAND, disarmed" in out
    assert monitor.down(timeout=30) and monitor.mode == LAND_MODE
    # The autopilot's own failsafe struck during the first leg, as the fault does in the
    # simulator: after TAKE_OFF ended, before the leg ended.
    ends = [t for t, _ in topics_with_times(record, "behavior_event")]
    failsafe = [
        t
        for t, r in topics_with_times(record, "mavlink/rx")
        if r["type"] == "STATUSTEXT" and r["fields"]["text"] == fault.failsafe
    ]
    assert len(failsafe) == 1 and ends[0] < failsafe[0] <= ends[1], (ends, failsafe)
    flown = behavior_events(record)

    # The simulator's side, as explore makes it: the flight's simulated twin (the same
    # mission from where the flight started), then the fault at the twin's end:TAKE_OFF.
    twin = tmp_path / "twin.mcap"
    made = replay_recording(
        record, ReplayOptions(mode=Mode.closed, mission=str(mission), output=str(twin), twin=True)
    )
    assert made.error is None, made.error
    struck = tmp_path / "struck.mcap"
    injection = parse_injection(f"{fault.simulated}@end:TAKE_OFF")
    options = ReplayOptions(
        mode=Mode.closed, mission=str(mission), output=str(struck), injections=(injection,)
    )
    replayed = replay_recording(twin, options)
    assert replayed.error is None, replayed.error
    simulated = behavior_events(struck)

    # Without the fault every goal is reached: the failures are the fault's.
    assert [code for _, code, _ in behavior_events(twin)] == ["GOAL_ACHIEVED"] * 4
    decided = [
        ("TAKE_OFF", "GOAL_ACHIEVED"),
        ("GO_TO_POINT", "PROCESS_FAILURE"),  # the leg the fault struck in
        ("GO_TO_POINT", "PROCESS_FAILURE"),  # refused at its start: the vehicle is landing
        ("LAND", "GOAL_ACHIEVED"),
    ]
    assert [(name, code) for name, code, _ in flown] == decided, flown
    assert [(name, code) for name, code, _ in simulated] == decided, simulated
    # The explained difference: the cause each failure names, and nothing else.
    assert [detail for _, _, detail in simulated[1:3]] == [
        f"vehicle fault: {fault.reports}",
        f"on_start failed: VehicleCommandError: go_to: refused, {fault.refusal}; "
        f"vehicle fault: {fault.reports}",
    ]
    assert [detail for _, _, detail in flown[1:3]] == [
        "vehicle fault: mode_changed:LAND",
        "on_start failed: VehicleCommandError: go_to: refused, the autopilot is in LAND "
        "mode, not GUIDED; vehicle fault: mode_changed:LAND",
    ]
    # The executive never learns the battery is low over MAVLink: the charge it gets
    # (SYS_STATUS battery_remaining) is computed from the mAh used, not the voltage.
    charges = [s["battery"] for _, s in topics_with_times(record, "vehicle/state")]
    assert min(charges) > 0.9, min(charges)
    # Nor that the position is lost: LOCAL_POSITION_NED goes on after the failsafe (the
    # EKF's dead reckoning without GPS), so the position belief stays.
    positions = [
        t
        for t, r in topics_with_times(record, "mavlink/rx")
        if r["type"] == "LOCAL_POSITION_NED" and t > failsafe[0]
    ]
    assert len(positions) > 10, len(positions)
    # The same properties hold on both.
    safety = load_properties(["aeroexec:safety"])
    verdicts = [
        {v.name: v.status for v in check_recording(path, safety).verdicts}
        for path in (record, struck)
    ]
    assert verdicts[0] == verdicts[1] and set(verdicts[0].values()) == {"held"}, verdicts
