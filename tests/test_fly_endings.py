"""How `fly` ends, against `MavSim` (fast): --on-exit land|hold|none after a mission that
returns or raises in the air, behaviors still active, a link that never comes back
(--link-timeout), the rtl failsafe, and signals (SIGTERM mid-flight, SIGINT while
waiting for the autopilot). The same endings are flown on ArduCopter SITL in
test_sitl_flights.py."""

from __future__ import annotations

import math
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from live_helpers import (
    AeroexecProcess,
    cpu_loaded,
    free_tcp_port,
    free_udp_port,
    mavsim_thread,
    write_mission,
)
from pymavlink.dialects.v20 import ardupilotmega as mavlink
from typer.testing import CliRunner, Result

from aeroexec.cli import app
from aeroexec.executive.bus import MemoryObserver, TopicRecord
from aeroexec.executive.clock import WallClock
from aeroexec.mavlink.sim_peer import MavSim
from aeroexec.mission.live import FlightConfig, fly
from aeroexec.recording import open_recording
from aeroexec.recording.reader import RecordedTopic
from aeroexec.vehicles.mavlink.convert import BRAKE, GUIDED, LAND

AIRBORNE = (
    "    api.executeBehavior('TAKE_OFF')\n"
    "    return api.executeBehavior('GO_TO_POINT', relative_coordinates=[1, 0, 0])\n"
)


def landed_as_seen(actions: Sequence[str]) -> bool:
    """The ending's actions: an optional brake seen to hold, then LAND seen in a HEARTBEAT."""
    *brake, land = actions
    return bool(re.fullmatch(r"switched to LAND: seen in LAND \d+\.\d s later", land)) and (
        brake == [] or (len(brake) == 1 and brake[0].startswith("braked: seen holding in BRAKE"))
    )


def config(mission: Path, port: int, **overrides: Any) -> FlightConfig:
    return FlightConfig(mission=mission, connect=f"udpin:127.0.0.1:{port}", **overrides)


# -- --on-exit ----------------------------------------------------------------------------------


def test_a_mission_that_returns_in_the_air_is_landed(tmp_path: Path) -> None:
    port = free_udp_port()
    with mavsim_thread(f"udpout:127.0.0.1:{port}") as sim:
        result = fly(config(write_mission(tmp_path, AIRBORNE), port))
        final = sim.stats()["final"]
    assert result.outcome.value == "GOAL_ACHIEVED"
    assert result.ending is not None and landed_as_seen(result.ending.actions)
    assert result.safe and result.ending.down
    assert final["mode"] == "LAND" and not final["armed"] and not final["flying"]
    assert abs(final["position"][0] - 1.0) < 0.06  # landed where the mission left it


def test_on_exit_hold_leaves_it_holding_and_exits_1(tmp_path: Path) -> None:
    port = free_udp_port()
    mission = write_mission(tmp_path, AIRBORNE)
    with mavsim_thread(f"udpout:127.0.0.1:{port}") as sim:
        result = CliRunner().invoke(
            app, ["fly", str(mission), "--connect", f"udpin:127.0.0.1:{port}", "--on-exit", "hold"]
        )
        time.sleep(0.3)
        final = sim.stats()["final"]
    assert result.exit_code == 1
    assert "ending: braked: seen holding in GUIDED at (1.0" in result.output
    last = result.output.strip().splitlines()[-1]
    assert last.startswith(
        "aeroexec fly: vehicle not landed: --on-exit hold left it flying; last seen flying at (1.0"
    )
    assert last.endswith(" m in GUIDED, armed")
    assert final["mode"] == "GUIDED" and final["flying"] and final["armed"]


def test_on_exit_none_commands_nothing(tmp_path: Path) -> None:
    port = free_udp_port()
    traffic = MemoryObserver()
    with mavsim_thread(f"udpout:127.0.0.1:{port}") as sim:
        result = fly(
            config(write_mission(tmp_path, AIRBORNE), port, on_exit="none"), observers=[traffic]
        )
        final = sim.stats()["final"]
    assert result.ending is not None and result.ending.actions == () and not result.safe
    assert result.ending.problem == "--on-exit none left it as it was"
    sent_after_mission = _after(traffic, "mission_end", "mavlink/tx")
    assert {r["type"] for r in sent_after_mission} <= {"HEARTBEAT"}  # no command, no setpoint
    assert final["flying"] and final["mode"] == "GUIDED"


def _after(traffic: MemoryObserver, event: str, topic: str) -> list[dict[str, Any]]:
    """Records of `topic` after the `mavlink/link` `event`, in bus order."""
    records, seen = [], False
    for record in traffic.records:
        if not isinstance(record, TopicRecord):
            continue
        if record.topic == "mavlink/link" and record.data["event"] == event:
            seen = True
        elif seen and record.topic == topic:
            records.append(record.data)
    return records


def test_a_mission_that_raises_in_the_air_is_landed_and_fails(tmp_path: Path) -> None:
    port = free_udp_port()
    mission = write_mission(
        tmp_path, "    api.executeBehavior('TAKE_OFF')\n    raise RuntimeError('lost my way')\n"
    )
    with mavsim_thread(f"udpout:127.0.0.1:{port}") as sim:
        result = CliRunner().invoke(
            app, ["fly", str(mission), "--connect", f"udpin:127.0.0.1:{port}"]
        )
        final = sim.stats()["final"]
    assert result.exit_code == 1
    assert "ending: switched to LAND: seen in LAND " in result.output
    assert "ending: vehicle on the ground at (" in result.output
    # The failure is reported at the mission's own line.
    last = result.output.strip().splitlines()[-1]
    assert last.endswith("mission.py:6: mission failed: RuntimeError: lost my way")
    assert final["mode"] == "LAND" and not final["armed"]


def test_behaviors_still_active_are_inhibited_before_landing(tmp_path: Path) -> None:
    port = free_udp_port()
    mission = write_mission(
        tmp_path,
        "    api.executeBehavior('TAKE_OFF')\n"
        "    return api.activateBehavior('GO_TO_POINT', coordinates=[0, 30, 1])\n",
    )
    with mavsim_thread(f"udpout:127.0.0.1:{port}") as sim:
        result = fly(config(mission, port))
        final = sim.stats()["final"]
    assert result.ending is not None
    assert result.ending.actions[0] == "inhibited GO_TO_POINT"
    assert landed_as_seen(result.ending.actions[1:])
    go_to = next(a for a in result.activations if a.behavior == "GO_TO_POINT")
    assert go_to.end_code == "INTERRUPTED"
    assert result.safe and final["position"][1] < 5.0  # it never flew the 30 m


def test_a_vehicle_a_pilot_took_over_is_left_to_the_pilot(tmp_path: Path) -> None:
    port = free_udp_port()
    mission = write_mission(
        tmp_path,
        "    api.executeBehavior('TAKE_OFF')\n    return api.executeBehavior('WAIT', duration=2)\n",
    )
    with mavsim_thread(f"udpout:127.0.0.1:{port}") as sim:

        def pilot() -> None:
            while not sim.flying:
                time.sleep(0.05)
            time.sleep(0.5)
            sim._enter_mode(5)  # the pilot flips the mode switch to LOITER

        thread = threading.Thread(target=pilot, daemon=True)
        thread.start()
        result = fly(config(mission, port))
        thread.join(5)
        final = sim.stats()["final"]
    assert result.ending is not None and result.ending.actions == ()
    assert result.ending.problem == (
        "LOITER was not commanded by aeroexec: a pilot or the autopilot has it"
    )
    assert final["mode"] == "LOITER" and final["flying"]  # no LAND forced on the pilot


# -- a link that does not come back ---------------------------------------------------------------


def test_a_link_lost_longer_than_link_timeout_stops_the_mission(tmp_path: Path) -> None:
    port = free_udp_port()
    mission = write_mission(
        tmp_path,
        "    api.executeBehavior('TAKE_OFF')\n"
        "    return api.executeBehavior('WAIT', duration=60)\n",
    )
    traffic = MemoryObserver()
    with mavsim_thread(f"udpout:127.0.0.1:{port}", drop_heartbeats_at=0.5, drop_for=60):
        started = time.monotonic()
        result = fly(
            config(mission, port, heartbeat_timeout=0.5, link_timeout=1.0), observers=[traffic]
        )
        took = time.monotonic() - started
    # WAIT does not fail on a lost link, so the mission would have waited a minute:
    # the link timeout stopped it.
    assert took < 10.0
    assert not result.outcome.returned
    assert result.outcome.error.startswith("stopped: the link was lost for 1.")
    assert result.ending is not None and not result.ending.down
    assert result.problem().startswith(
        "vehicle not landed: link lost, no heartbeat for 1 s; last seen flying at ("
    )
    events = [e["event"] for e in traffic.topics("mavlink/link")]
    assert events == ["connected", "lost", "mission_end", "ending"]
    assert traffic.topics("mavlink/link")[2]["how"] == "link_timeout"


def test_the_rtl_failsafe_flies_home_and_lands(tmp_path: Path) -> None:
    port = free_udp_port()
    mission = write_mission(
        tmp_path,
        "    api.executeBehavior('TAKE_OFF')\n"
        "    return api.executeBehavior('GO_TO_POINT', coordinates=[0, 12, 1])\n",
    )
    with mavsim_thread(
        f"udpout:127.0.0.1:{port}", drop_heartbeats_at=1.0, drop_for=1.5, rtl_altitude=3.0
    ) as sim:
        result = fly(config(mission, port, heartbeat_timeout=0.5, failsafe="rtl"))
        final = sim.stats()["final"]
    assert result.outcome.value == "PROCESS_FAILURE"  # GO_TO_POINT: vehicle fault: link_lost
    assert result.ending is not None and result.ending.down
    assert result.ending.actions == ("left it in RTL",)
    assert result.link_losses == 1 and not result.safe
    assert final["mode"] == "RTL" and not final["armed"]
    assert math.hypot(final["position"][0], final["position"][1]) < 0.05  # home


# -- signals ------------------------------------------------------------------------------------


def test_a_mission_spinning_in_the_air_is_stopped_by_timeout_and_landed(tmp_path: Path) -> None:
    port = free_udp_port()
    mission = write_mission(
        tmp_path, "    api.executeBehavior('TAKE_OFF')\n    while True:\n        pass\n"
    )
    with mavsim_thread(f"udpout:127.0.0.1:{port}") as sim:
        result = CliRunner().invoke(
            app, ["fly", str(mission), "--connect", f"udpin:127.0.0.1:{port}", "--timeout", "1"]
        )
        final = sim.stats()["final"]
    assert result.exit_code == 1, result.output
    assert "ending: switched to LAND" in result.output
    last = result.output.strip().splitlines()[-1]
    assert last.endswith(
        "mission.py:6: mission stopped: still running after 1 s of wall-clock time (--timeout)"
    )
    assert final["mode"] == "LAND" and not final["armed"]


def test_sigterm_mid_flight_lands_finalizes_the_recording_and_exits_143(tmp_path: Path) -> None:
    port = free_udp_port()
    record = tmp_path / "flight.mcap"
    mission = write_mission(
        tmp_path,
        "    api.executeBehavior('TAKE_OFF')\n"
        "    return api.executeBehavior('GO_TO_POINT', coordinates=[0, 30, 1])\n",
    )
    args = ["fly", str(mission), "--connect", f"udpin:127.0.0.1:{port}", "--output", str(record)]
    with mavsim_thread(f"udpout:127.0.0.1:{port}") as sim:
        proc = subprocess.Popen(
            [sys.executable, "-m", "aeroexec", *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        try:
            assert proc.stdout is not None
            for line in proc.stdout:
                if "start    GO_TO_POINT" in line:
                    break
            time.sleep(0.5)
            proc.send_signal(signal.SIGTERM)
            _, err = proc.communicate(timeout=60)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait(5)
        final = sim.stats()["final"]
    assert proc.returncode == 143
    (line,) = err.strip().splitlines()
    assert line.startswith("aeroexec fly: interrupted by SIGTERM; vehicle on the ground at (")
    assert line.endswith(f"in LAND, disarmed; recording finalized: {record}")
    assert final["mode"] == "LAND" and not final["armed"] and 0.5 < final["position"][1] < 29
    recording = open_recording(record)
    assert recording.complete
    events = [
        item.data
        for item in recording.records()
        if isinstance(item, RecordedTopic) and item.name == "mavlink/link"
    ]
    assert [e["event"] for e in events] == ["connected", "mission_end", "ending"]
    assert events[1]["how"] == "SIGTERM"
    assert events[2]["actions"][0] == "inhibited GO_TO_POINT"
    assert landed_as_seen(events[2]["actions"][1:])


def test_sigint_while_waiting_for_the_autopilot_exits_130_having_commanded_nothing(
    tmp_path: Path,
) -> None:
    port = free_udp_port()
    mission = write_mission(tmp_path, AIRBORNE)
    proc = subprocess.Popen(
        [
            *(sys.executable, "-m", "aeroexec", "fly", str(mission)),
            *("--connect", f"udpin:127.0.0.1:{port}", "--connect-timeout", "60"),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        assert "waiting for a heartbeat" in proc.stdout.readline()
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(5)
    assert proc.returncode == 130
    assert err.strip() == (
        "aeroexec fly: interrupted by SIGINT; stopped before the autopilot was ready; "
        "nothing was commanded"
    )


# -- time -----------------------------------------------------------------------------------------


def test_a_late_tick_is_not_made_up_for_with_a_burst() -> None:
    tick = 10_000_000  # 10 ms
    clock = WallClock(tick_ns=tick)
    clock.advance()
    time.sleep(0.055)  # a command waited for its ack: five ticks were missed
    late = clock.advance()
    following = clock.advance()
    # The tick after the late one waits for the next slot of the grid instead of
    # running at once to catch up.
    assert following // tick > late // tick


# -- confirmed endings --------------------------------------------------------------------------


HOLD_AT = re.compile(
    r"ending: braked: seen holding in GUIDED at \((-?[\d.]+), (-?[\d.]+), (-?[\d.]+)\) m, "
    r"[\d.]+ m/s, [\d.]+ s after the brake"
)


def test_on_exit_hold_over_tcp_is_seen_holding_10_of_10_with_the_cpu_loaded(
    tmp_path: Path,
) -> None:
    """The mission returns with the vehicle flying a 30 m leg; --on-exit hold must stop it
    there, as the autopilot's own telemetry shows, before fly says so and closes the TCP
    connection, and it must still be there after fly is gone."""
    mission = write_mission(
        tmp_path,
        "    api.executeBehavior('TAKE_OFF')\n"
        "    api.activateBehavior('GO_TO_POINT', coordinates=[0, 30, 1])\n"
        "    return api.executeBehavior('WAIT', duration=1)\n",
    )
    held = 0
    with cpu_loaded():
        for _ in range(10):
            port = free_tcp_port()
            with mavsim_thread(f"tcpin:127.0.0.1:{port}") as sim:
                result = CliRunner().invoke(
                    app,
                    [
                        "fly",
                        str(mission),
                        "--connect",
                        f"tcp:127.0.0.1:{port}",
                        "--on-exit",
                        "hold",
                    ],
                )
                seen = HOLD_AT.search(result.stdout)
                first = sim.stats()["final"]
                time.sleep(1.0)  # fly is gone: the vehicle holds by itself
                later = sim.stats()["final"]
            assert result.exit_code == 1, result.output
            assert seen is not None, result.output
            where = tuple(float(v) for v in seen.groups())
            assert 0.5 < where[1] < 25.0, result.output  # stopped on the leg, short of its end
            for final in (first, later):
                assert final["mode"] == "GUIDED" and final["flying"]
                assert math.dist(final["position"], where) < 0.5, (final, where)
            held += 1
    assert held == 10


def test_a_hold_the_autopilot_does_not_show_is_not_reported_held(tmp_path: Path) -> None:
    """The autopilot falls silent as the mission ends: no HEARTBEAT or position after
    the brake shows it holding, so fly says so (not "held") and exits 1."""
    port = free_udp_port()
    mission = write_mission(
        tmp_path,
        "    api.executeBehavior('TAKE_OFF')\n"
        "    api.activateBehavior('GO_TO_POINT', coordinates=[0, 30, 1])\n"
        "    return api.executeBehavior('WAIT', duration=1)\n",
    )
    silent = {"drop_heartbeats_at": 1.2, "drop_for": 20.0}
    with mavsim_thread(f"udpout:127.0.0.1:{port}", **silent):
        result = CliRunner().invoke(
            app,
            [
                "fly",
                str(mission),
                "--connect",
                f"udpin:127.0.0.1:{port}",
                "--on-exit",
                "hold",
                "--link-timeout",
                "1",
            ],
        )
    assert result.exit_code == 1
    assert "ending: braked: NOT seen holding: the link was lost while braking" in result.stdout
    assert "seen holding" not in result.stdout.replace("NOT seen holding", "")
    assert "aeroexec fly: vehicle not landed: hold not confirmed: the link was lost while" in (
        result.stderr
    )


@dataclass(frozen=True)
class Flown:
    """What `fly_on_mavsim` saw: the command's result, and the simulated vehicle as the
    command left it."""

    result: Result
    final: dict[str, Any]
    velocity_setpoints: int


def fly_on_mavsim(mission: Path, *args: str, **sim: Any) -> Flown:
    """`aeroexec fly MISSION --connect ... ARGS`, in this process, against mavsim in a
    thread over UDP (`sim`: mavsim_thread's options: its kind, refusals, speed-up)."""
    port = free_udp_port()
    with mavsim_thread(f"udpout:127.0.0.1:{port}", **sim) as simulator:
        result = CliRunner().invoke(
            app, ["fly", str(mission), "--connect", f"udpin:127.0.0.1:{port}", *args]
        )
        return Flown(result, simulator.stats()["final"], simulator.counters.setpoints["velocity"])


class AcceptsLandButStaysGuided(MavSim):
    """An autopilot that acknowledges LAND and goes on hovering in GUIDED (as one whose
    mode change another GCS or a failing mode check overrides would look)."""

    def _enter_mode(self, mode: int) -> int:
        if mode == LAND:
            return mavlink.MAV_RESULT_ACCEPTED
        return super()._enter_mode(mode)


def test_a_land_the_autopilot_acknowledges_but_does_not_show_is_not_reported(
    tmp_path: Path,
) -> None:
    """Issue 24.1: an ending is reported from the autopilot's HEARTBEAT, not from its
    COMMAND_ACK; LAND not seen within the bound is said so, and fly exits 1."""
    flown = fly_on_mavsim(write_mission(tmp_path, AIRBORNE), kind=AcceptsLandButStaysGuided)
    result, final = flown.result, flown.final
    assert result.exit_code == 1, result.output
    assert "ending: switched to LAND: NOT seen in LAND within 5 s" in result.stdout
    assert "seen in LAND " not in result.stdout.replace("NOT seen in LAND", "")
    last = result.stderr.strip().splitlines()[-1]
    assert last.startswith(
        "aeroexec fly: vehicle not landed: LAND not confirmed: the autopilot still says "
        "GUIDED 5 s after it acknowledged LAND; last seen flying at ("
    ), last
    assert final["mode"] == "GUIDED" and final["flying"]


def recorded_ending(record: Path) -> dict[str, Any]:
    """The `mavlink/link` `ending` event of a complete recording."""
    recording = open_recording(record)
    assert recording.complete
    (ending,) = (
        item.data
        for item in recording.records()
        if isinstance(item, RecordedTopic)
        and item.name == "mavlink/link"
        and item.data["event"] == "ending"
    )
    return ending


class ShowsLandButNeverComesDown(MavSim):
    """An autopilot that acknowledges LAND, shows it in its HEARTBEAT and says it is
    landing (EXTENDED_SYS_STATE), but whose vehicle never comes down and stays armed (as
    a descent held off by a rangefinder that reads the ground too far would look)."""

    def _enter_mode(self, mode: int) -> int:
        result = super()._enter_mode(mode)
        if mode == LAND and self.flying:
            self.sim.hover()
        return result


NOT_DOWN = re.compile(r"ending: NOT seen landed and disarmed within (\d+) s: landing, armed\n")


def test_a_land_seen_but_never_seen_down_is_not_reported_landed(tmp_path: Path) -> None:
    """Issue 24.1: LAND in the HEARTBEAT is not a landing. Landed and disarmed must be seen
    (EXTENDED_SYS_STATE, HEARTBEAT) within the landing's bound (20 s + 4 s per metre of
    height + 1 s per metre from home: 25 s here, on fly's wall clock, which mavsim's
    speed-up does not shorten); not seen, fly says so, exits 1 and records it."""
    record = tmp_path / "flight.mcap"
    mission = write_mission(tmp_path, AIRBORNE)
    flown = fly_on_mavsim(mission, "-o", str(record), kind=ShowsLandButNeverComesDown)
    result, final = flown.result, flown.final
    assert final["mode"] == "LAND" and final["flying"] and final["armed"]  # as it misbehaves
    assert result.exit_code == 1, result.output
    assert re.search(r"ending: switched to LAND: seen in LAND \d+\.\d s later\n", result.stdout)
    bound = NOT_DOWN.search(result.stdout)
    assert bound is not None, result.stdout
    assert 24 <= int(bound.group(1)) <= 26, result.stdout  # 20 s + 4 s x 1 m + 1 s x 1 m
    assert "on the ground" not in result.output
    last = result.stderr.strip().splitlines()[-1]
    assert last.startswith(
        "aeroexec fly: vehicle not landed: landing not confirmed: the autopilot still says "
        f"landing, armed {bound.group(1)} s after LAND was seen; last seen flying at (1.0"
    ), last
    assert last.endswith(" m in LAND, armed"), last
    ending = recorded_ending(record)
    assert not ending["down"]
    assert ending["actions"][-1].startswith("NOT seen landed and disarmed within ")
    assert ending["problem"].startswith("landing not confirmed: the autopilot still says landing")


class DriftsOnWhenBraked(MavSim):
    """An autopilot that acknowledges BRAKE and shows it, and takes every zero-velocity
    setpoint in GUIDED, but whose vehicle never stops: it drifts on at `DRIFT` m/s (as
    one in wind stronger than it can fight would), until LAND holds it over a point."""

    DRIFT = 1.0  # m/s, as LOCAL_POSITION_NED reports it

    def _drift(self) -> None:
        if self.flying:
            self.sim.set_velocity(0.0, self.DRIFT / self.config.speed_factor, 0.0)

    def _enter_mode(self, mode: int) -> int:
        result = super()._enter_mode(mode)
        if mode == BRAKE:
            self._drift()
        return result

    def _setpoint(self, msg: Any) -> None:
        super()._setpoint(msg)
        zero = (msg.vx, msg.vy, msg.vz) == (0.0, 0.0, 0.0) and msg.type_mask & 0b111
        if zero and self.mode == GUIDED:
            self._drift()


#: The mission returns with the vehicle flying a 30 m leg. At mavsim's own speed (1x) it
#: is below 2 m/s then, so the brake's bound (8 s + 1 s per m/s) stays near 10 s.
LEG_THEN_RETURN = (
    "    api.executeBehavior('TAKE_OFF')\n"
    "    api.activateBehavior('GO_TO_POINT', coordinates=[0, 30, 1])\n"
    "    return api.executeBehavior('WAIT', duration=1)\n"
)
STILL_MOVING = r"still 1\.00 m/s in {mode} (\d+) s after the brake"


def test_a_hold_never_seen_to_stop_is_not_reported_held(tmp_path: Path) -> None:
    """Issue 24.1: a zero-velocity setpoint is never acknowledged, so only the autopilot's
    velocity shows a hold. It stays at 1 m/s: fly says it was NOT seen holding, exits 1
    and records it."""
    record = tmp_path / "flight.mcap"
    mission = write_mission(tmp_path, LEG_THEN_RETURN)
    flown = fly_on_mavsim(
        mission, "--on-exit", "hold", "-o", str(record), kind=DriftsOnWhenBraked, speed_factor=1.0
    )
    result, final = flown.result, flown.final
    assert final["mode"] == "GUIDED" and final["flying"]
    assert flown.velocity_setpoints >= 2  # braked, and braked again
    assert result.exit_code == 1, result.output
    moving = STILL_MOVING.format(mode="GUIDED")
    assert re.search(f"ending: braked: NOT seen holding: {moving}\n", result.stdout), result.stdout
    assert "seen holding" not in result.stdout.replace("NOT seen holding", "")
    last = result.stderr.strip().splitlines()[-1]
    assert re.match(
        f"aeroexec fly: vehicle not landed: hold not confirmed: {moving}; last seen flying ", last
    ), last
    ending = recorded_ending(record)
    assert not ending["down"]
    assert re.fullmatch(f"braked: NOT seen holding: {moving}", ending["actions"][-1])
    assert re.fullmatch(f"hold not confirmed: {moving}", ending["problem"])


def test_a_brake_before_landing_never_seen_to_stop_fails_the_landing(tmp_path: Path) -> None:
    """Issue 24.1 and 24.5: the vehicle is braked (BRAKE, acknowledged and shown) before
    LAND so that it lands where it stopped. It never stops: fly lands it all the same
    (the safest thing left) but says the brake was NOT seen, exits 1 although the vehicle
    came down, and records it."""
    record = tmp_path / "flight.mcap"
    mission = write_mission(tmp_path, LEG_THEN_RETURN)
    flown = fly_on_mavsim(mission, "-o", str(record), kind=DriftsOnWhenBraked, speed_factor=1.0)
    result, final = flown.result, flown.final
    assert final["mode"] == "LAND" and not final["flying"] and not final["armed"]
    assert result.exit_code == 1, result.output
    moving = STILL_MOVING.format(mode="BRAKE")
    lines = [line for line in result.stdout.splitlines() if line.startswith("ending: ")]
    assert lines[0] == "ending: inhibited GO_TO_POINT"
    assert re.fullmatch(f"ending: braked: NOT seen holding: {moving}", lines[1]), lines
    assert re.fullmatch(r"ending: switched to LAND: seen in LAND \d+\.\d s later", lines[2])
    assert lines[3].startswith("ending: vehicle on the ground at (")
    assert "seen holding" not in result.stdout.replace("NOT seen holding", "")
    last = result.stderr.strip().splitlines()[-1]
    assert re.fullmatch(
        r"aeroexec fly: vehicle on the ground at \(.+\) m in LAND, disarmed; "
        f"brake before landing not confirmed: {moving}",
        last,
    ), last
    ending = recorded_ending(record)
    assert ending["down"]  # it did come down ...
    assert re.fullmatch(f"brake before landing not confirmed: {moving}", ending["problem"])
    assert re.fullmatch(f"braked: NOT seen holding: {moving}", ending["actions"][1])


class DriftsUntilTheLinkDrops(DriftsOnWhenBraked):
    """Drifts on when braked until its heartbeats were dropped; brakes as it should after."""

    def _drift(self) -> None:
        if self.counters.dropped_heartbeats == 0:
            super()._drift()


def test_a_link_lost_while_braking_before_landing_does_not_stop_the_landing(
    tmp_path: Path,
) -> None:
    """The link is lost while the ending brakes (in BRAKE) before LAND, and comes back;
    --failsafe hold leaves a vehicle in BRAKE as it is. The landing then starts over:
    braked again, seen holding, LAND seen, seen down; fly exits 1 for the lost link. It
    used to wait for ever with the vehicle holding in BRAKE."""
    port = free_udp_port()
    record = tmp_path / "flight.mcap"
    mission = write_mission(tmp_path, LEG_THEN_RETURN)
    # The mission returns ~3.5 s after the take-off; the first brake drifts on for 10 s.
    drop = {"drop_heartbeats_at": 6.0, "drop_for": 2.0}
    with mavsim_thread(
        f"udpout:127.0.0.1:{port}", kind=DriftsUntilTheLinkDrops, speed_factor=1.0, **drop
    ) as sim:
        proc = AeroexecProcess(
            [
                *("fly", str(mission), "--connect", f"udpin:127.0.0.1:{port}"),
                *("--heartbeat-timeout", "0.5", "--failsafe", "hold", "-o", str(record)),
            ]
        )
        try:
            code, out, err = proc.finish(40)
        except subprocess.TimeoutExpired:
            pytest.fail("fly still waiting 40 s on; it printed:\n" + "".join(proc.out))
        finally:
            proc.kill()
        final = sim.stats()["final"]
    assert final["mode"] == "LAND" and not final["flying"] and not final["armed"]
    assert code == 1, out + err
    lines = [line for line in out.splitlines() if line.startswith("ending: ")]
    assert lines[:2] == [
        "ending: inhibited GO_TO_POINT",
        "ending: braked: NOT seen holding: the link was lost while braking",
    ]
    assert lines[2].startswith("ending: braked: seen holding in BRAKE at ("), lines
    assert re.fullmatch(r"ending: switched to LAND: seen in LAND \d+\.\d s later", lines[3])
    assert lines[4].startswith("ending: vehicle on the ground at ("), lines
    last = err.strip().splitlines()[-1]
    assert last.startswith(
        "aeroexec fly: the link was lost 1 time during the flight; vehicle on the ground at ("
    ), err
    ending = recorded_ending(record)
    assert ending["down"] and ending["problem"] == ""


#: A take-off the autopilot refuses after it armed (mavsim --refuse MAV_CMD_NAV_TAKEOFF):
#: the mission fails with the vehicle armed on the ground.
TAKE_OFF_ONLY = "    return api.executeBehavior('TAKE_OFF')\n"
REFUSED_TAKE_OFF = (mavlink.MAV_CMD_NAV_TAKEOFF,)


def test_a_vehicle_left_armed_on_the_ground_is_disarmed_as_seen(tmp_path: Path) -> None:
    """The ending disarms a vehicle left armed on the ground and says so from a HEARTBEAT
    heard after the disarm. It used to leave it armed: the ending came before the first
    HEARTBEAT after the arm, and the one before it (disarmed) counted as down."""
    flown = fly_on_mavsim(write_mission(tmp_path, TAKE_OFF_ONLY), refuse=REFUSED_TAKE_OFF)
    result, final = flown.result, flown.final
    assert not final["armed"] and not final["flying"]
    assert result.exit_code == 1, result.output  # the take-off failed
    lines = [line for line in result.stdout.splitlines() if line.startswith("ending: ")]
    assert len(lines) == 2 and re.fullmatch(
        r"ending: disarmed: seen disarmed \d+\.\d s later", lines[0]
    )
    assert lines[1] == "ending: vehicle on the ground at (0.00, 0.00, 0.00) m in GUIDED, disarmed"


class AcksDisarmButStaysArmed(MavSim):
    """An autopilot that acknowledges a disarm and stays armed, as its HEARTBEAT says."""

    def _execute(self, command: int, msg: Any) -> int:
        if command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM and msg.param1 < 0.5:
            return mavlink.MAV_RESULT_ACCEPTED
        return super()._execute(command, msg)


def test_a_disarm_acknowledged_but_never_seen_is_not_reported_disarmed(tmp_path: Path) -> None:
    """Issue 24.1: the disarm's COMMAND_ACK is not a disarm; not seen in a HEARTBEAT within
    20 s (the bound of a disarm on the ground), fly says so and records it."""
    record = tmp_path / "flight.mcap"
    mission = write_mission(tmp_path, TAKE_OFF_ONLY)
    flown = fly_on_mavsim(
        mission, "-o", str(record), kind=AcksDisarmButStaysArmed, refuse=REFUSED_TAKE_OFF
    )
    result, final = flown.result, flown.final
    assert final["armed"] and not final["flying"]  # as it misbehaves
    assert result.exit_code == 1, result.output
    assert "ending: NOT seen disarmed within 20 s: on the ground, armed\n" in result.stdout
    assert "seen disarmed" not in result.stdout.replace("NOT seen disarmed", "")
    assert result.stderr.strip().splitlines()[-1] == (
        "aeroexec fly: vehicle not landed: disarm not confirmed: the autopilot still says on "
        "the ground, armed 20 s after it acknowledged the disarm; last seen on the ground at "
        "(0.00, 0.00, 0.00) m in GUIDED, armed"
    )
    ending = recorded_ending(record)
    assert not ending["down"]
    assert ending["actions"] == ["NOT seen disarmed within 20 s: on the ground, armed"]
    assert ending["problem"].startswith("disarm not confirmed: the autopilot still says on the")
